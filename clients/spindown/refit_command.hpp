#pragma once
// `spindown refit LOG...`: stream an LCM log (LcmLogReader, the log's own order and receive
// times) through the live fitter's FitterCore, so every bench's runs and numbers are exactly
// what spindown-fitter gave for that traffic; print them as `spindown fit` does (text or §5
// JSON, each run tagged with its bench id and sequence numbers). --live prints the FIT
// messages recorded in the log instead; --compare checks the refit against them.
// Memory is bounded by the per-bench state, not by the log's length: runs are formatted as they
// are fitted and held, per bench, in an unlinked temporary file until the log is done (the
// order contract needs every run of the first bench before the second's); --live and
// --compare keep the runs in memory.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <spindown/fit_t.hpp>

#include "input_options.hpp"
#include "spindown/fit_report.hpp"
#include "spindown/fitter_core.hpp"
#include "spindown/lcm_log_reader.hpp"
#include "spindown/log_refit.hpp"

namespace CLI {
class App;
}

namespace spindown::cli {

struct RefitCommandOptions {
  std::vector<std::string> logs;
  bool json = false;
  bool lab_units = false;
  bool verbose = false;
  bool live = false;     // print the recorded FIT messages, not a refit
  bool compare = false;  // refit and compare with the recorded FIT messages (exit 1 on a difference)
  bool no_progress = false;  // no progress line on a terminal
  // --explain: each run's EXPLAIN as the live fitter publishes it (its discrepancy workflow from
  // explain_base on the FIT's own window); --compare always checks them against the recorded ones.
  bool explain = false;
  std::string explain_base = "viscous";  // as spindown-fitter --explain-base
  std::string bench_regex = ".*";
  std::vector<std::string> models;
  // J and K_b (--inertia/--flywheel-*, --kb/--speed-constant, their errors) and --bench-config, as
  // `spindown fit` takes them: what they name wins over the log's CONFIG (said in each run's
  // bench_source). With --compare they are the live fitter's: the flags its defaults for benches
  // without CONFIG, the bench files its health references, so that like is compared with like.
  InputOptions input;
  bool ignore_config = false;
  std::size_t max_benches = FitterOptions{}.max_benches;  // as spindown-fitter --max-benches
  double admit_rate_hz = FitterOptions{}.admit_rate_hz;   // as spindown-fitter --admit-rate
  double silent_s = FitterOptions{}.silent_s;             // as spindown-fitter --silent
  double replay_window_s = FitterOptions{}.gate.replay_window_s;  // as spindown-fitter --replay-window
  double takeover_s = FitterOptions{}.stream.takeover_s;          // as spindown-fitter --takeover
};

void setup_refit(CLI::App& app);
int run_refit(const RefitCommandOptions& options);

}  // namespace spindown::cli
