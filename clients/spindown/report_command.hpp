#pragma once
// `spindown report FILE|LOG... -o OUT.html`: one self-contained HTML page for a lab session
// (html_report.hpp): per bench and run the measured curve with each model's fit and the
// residuals, the coefficients with uncertainties in SI and lab units, the explain story, the
// health verdict (from --bench-config files), and which motors drift across the runs.
#include <string>
#include <vector>

#include "input_options.hpp"

namespace CLI {
class App;
}

namespace spindown::cli {

struct ReportCommandOptions {
  std::vector<std::string> files;
  std::string output;                     // the HTML file
  std::string text_bench;                 // --bench: bench id of text files
  std::string base = "viscous";           // the explain workflow's starting belief
  std::vector<std::string> models;
  bool no_explain = false;
  bool no_progress = false;
  bool verbose = false;
  std::string title = "spindown report";

  InputOptions input;  // the bench, --bench-config and delimited-text columns, as for `spindown fit`
};

void setup_report(CLI::App& app);
// Exit code: 0 ok, 1 a file or run could not be used (the page is still written) or the page
// could not be written; throws CLI::ValidationError for bad usage (exit code 2).
int run_report(const ReportCommandOptions& options);

}  // namespace spindown::cli
