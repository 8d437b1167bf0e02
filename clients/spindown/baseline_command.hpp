#pragma once
// `spindown baseline LOG|FILE... --bench ID [-o bench.toml | --update bench.toml]`: the motor's
// friction when known good, from every run of that bench whose combined fit converged
// (weighted mean of c_v and c_c with standard error, run-to-run spread, number of runs, date),
// written as the [baseline] section of the bench's TOML file (motor_health.hpp).
#include <string>
#include <vector>

#include "input_options.hpp"

namespace CLI {
class App;
}

namespace spindown::cli {

struct BaselineCommandOptions {
  std::vector<std::string> files;
  std::string bench;        // bench id: selects the bench in an LCM log, names it in the file
  std::string output;       // -o: a new bench file (refused when it exists)
  std::string update;       // --update: replace [baseline] in this bench file ([bench] J/K_b used)
  std::string date;         // default: today (UTC)
  InputOptions input;       // J, K_b and delimited-text columns
};

void setup_baseline(CLI::App& app);
// Exit code: 0 baseline made (and written), 1 no good run or the file could not be written
// (reasons on stderr); bad usage throws CLI::ValidationError (exit code 2).
int run_baseline(const BaselineCommandOptions& options);

}  // namespace spindown::cli
