#pragma once
// The CSV a command writes for a spreadsheet (`fit --table csv`, `export`): --csv-locale chooses
// the style (csv_cells.hpp), and a file (-o) starts with a UTF-8 byte-order mark so that Excel
// reads its names right; stdout, read by scripts and pipes, has none.
#include <string>

#include "spindown/csv_cells.hpp"

namespace CLI {
class App;
}

namespace spindown::cli {

// Adds --csv-locale to sub, bound to locale.
void add_csv_locale_option(CLI::App* sub, std::string& locale);
// The style for the locale, with a byte-order mark when the CSV goes to a file. An unknown
// locale is bad usage (CLI::ValidationError).
CsvStyle csv_style_from(const std::string& locale, bool to_file);

}  // namespace spindown::cli
