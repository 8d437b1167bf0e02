#pragma once
// `spindown export LOG --mcap FILE`: the log's samples, runs and fits as MCAP
// (spindown/lcm_log_mcap.hpp says what goes in) for Foxglove and PlotJuggler.
#include "export_command.hpp"

namespace spindown::cli {

// Writes options.mcap from options.log (only benches matching options.bench_regex); the exit code.
int run_export_mcap(const ExportCommandOptions& options);

}  // namespace spindown::cli
