#pragma once
// The CSV a command writes for a spreadsheet: --csv-locale chooses the style (csv_cells.hpp), and a
// file written for a spreadsheet starts with a UTF-8 byte-order mark so that Excel reads its names
// right: `fit --table csv -o FILE` (the class's table: students' names, "×" in the reasons), and
// any CSV file written with --csv-locale. stdout, read by scripts and pipes, never has one, nor
// has `export`'s default CSV, which is for MATLAB and Python (ASCII: bench ids, units, numbers;
// Python's csv module would take a mark as part of the first column's name).
#include <string>

#include "spindown/csv_cells.hpp"

namespace CLI {
class App;
}

namespace spindown::cli {

// Adds --csv-locale to sub, bound to locale.
void add_csv_locale_option(CLI::App* sub, std::string& locale);
// The style for the locale, with a byte-order mark when byte_order_mark. An unknown locale is bad
// usage (CLI::ValidationError).
CsvStyle csv_style_from(const std::string& locale, bool byte_order_mark);

}  // namespace spindown::cli
