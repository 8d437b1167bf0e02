#pragma once
// `spindown fit FILE...`: read each file, find its spin-down runs, fit the friction models,
// report per run a table like the lab report's (or design §5's JSON with --json), or a class's
// table of one row per run across every file (--table csv|json).
#include <string>
#include <vector>

#include "input_options.hpp"

namespace CLI {
class App;
}

namespace spindown::cli {

struct FitCommandOptions {
  std::vector<std::string> files;
  bool json = false;
  bool pretty = false;  // --pretty: indented JSON into a pipe or file too
  std::string table;     // "csv" | "json": one row per run across all files (run_table.hpp)
  std::string output;    // -o: the output (text, JSON or table) to this file instead of stdout
  std::string csv_locale;  // --csv-locale: the table's CSV style (csv_output.hpp)
  bool lab_units = false;
  bool details = false;  // 95 % intervals, correlations, reduced χ² in the text
  bool verbose = false;  // every diagnostic, notes included
  std::vector<std::string> models;  // names; empty = all
  InputOptions input;  // the bench, --bench-config, delimited-text columns, a class's roster
  unsigned jobs = 0;  // files fitted at once; 0 = one per core
};

void setup_fit(CLI::App& app);
// Returns the exit code (0 ok, 1 a file or run could not be used); throws
// CLI::ValidationError for bad usage (exit code 2).
int run_fit(const FitCommandOptions& options);

}  // namespace spindown::cli
