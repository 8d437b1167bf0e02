#include "csv_output.hpp"

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "input_options.hpp"

namespace spindown::cli {

void add_csv_locale_option(CLI::App* sub, std::string& locale) {
  sub->add_option("--csv-locale", locale,
                  "CSV for a spreadsheet set to this locale: en (default: ',' and decimal points) or de (';' and "
                  "decimal commas, as a German, French, Italian, Spanish or Dutch Excel opens a CSV)");
}

CsvStyle csv_style_from(const std::string& locale, bool byte_order_mark) {
  auto style = csv_style_for_locale(locale);
  if (!style) bad_usage(fmt::format("--csv-locale '{}' is not one of: en, de", locale));
  style->byte_order_mark = byte_order_mark;
  return *style;
}

}  // namespace spindown::cli
