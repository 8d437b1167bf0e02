#pragma once
// `spindown simulate [-o FILE] [--truth FILE] [--putty-header] [bench options…]`: what the lab's
// Arduino would print for simulated spin-down runs (the virtual bench's simulator and faults,
// the same options as spindown-virtual-bench), written to a file instead of a serial port. For
// an instructor's known-answer recordings, or to try spindown fit/explain on a given friction.
#include <string>

#include "spindown/virtual_bench.hpp"
#include "spindown/virtual_bench_cli.hpp"

namespace CLI {
class App;
}

namespace spindown::cli {

struct SimulateCommandOptions {
  VirtualBenchOptions bench;
  VirtualBenchCli bench_cli;
  std::string out;          // "" or "-": stdout; an existing file is refused
  std::string truth;        // the parameters, each run's cut and stop, the faults (JSON)
  bool putty_header = false;  // a PuTTY log's first line, as the lab's logs have
};

void setup_simulate(CLI::App& app);
int run_simulate(SimulateCommandOptions options);

}  // namespace spindown::cli
