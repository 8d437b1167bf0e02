#pragma once
// `spindown explain FILE...`: for each spin-down run, fit the base model (the user's belief),
// find where it and the measurement disagree, name the missing effect, add it, and repeat
// (design §6); the story as text, design §5's JSON with --json, a figure with --svg.
#include <string>
#include <vector>

#include "input_options.hpp"

namespace CLI {
class App;
}

namespace spindown::cli {

struct ExplainCommandOptions {
  std::vector<std::string> files;
  std::string base = "viscous";  // viscous|coulomb|combined|EFFECT,EFFECT…
  bool json = false;
  std::string svg;               // output file, empty = none
  bool lab_units = false;        // also the lab's units, as `spindown fit --lab-units`
  bool verbose = false;

  InputOptions input;  // the bench and delimited-text columns, as for `spindown fit`
};

void setup_explain(CLI::App& app);
// Returns the exit code (0 ok, 1 a file or run could not be used); throws
// CLI::ValidationError for bad usage (exit code 2).
int run_explain(const ExplainCommandOptions& options);

}  // namespace spindown::cli
