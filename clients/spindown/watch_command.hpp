#pragma once
// `spindown watch`: a live table of the lab's benches over LCM — each bench's run state
// (RUN), last fit (FIT: best model, coefficients ± error, RMSE), bridge health (STATUS:
// connected, lines good/bad, rate), sequence gaps seen on SAMPLE and the age of its last
// message — plus the services' heartbeats (fitter, logger). On a terminal the table is redrawn
// in place; with --plain (or when stdout is not a terminal) events are printed as lines and the
// table now and then. Ends on SIGINT/SIGTERM or after --duration; --once prints one table.
#include <string>

#include "lab_options.hpp"

namespace CLI {
class App;
}

namespace spindown::cli {

struct WatchCommandOptions {
  std::string bench_regex = ".*";  // benches shown (full match on the id); services always
  std::string lcm_url;             // "" = LCM_DEFAULT_URL or LCM's default
  bool once = false;               // listen for --duration (default 3 s), print one table, exit
  double duration_s = 0;           // 0 = until a signal
  bool plain = false;              // append-only lines even on a terminal
  double interval_s = 0;           // redraw period; 0 = 1 s on a terminal, 10 s with --plain
  bool lab_units = false;          // coefficients in the lab's g·cm² units
  bool no_events = false;          // --plain: only tables, no event lines
  LabOptions lab;                  // only this lab's messages; with a key only signed ones
};

void setup_watch(CLI::App& app);
// Exit code: 0 stopped by a signal or --duration, 1 LCM could not start.
int run_watch(const WatchCommandOptions& options);

}  // namespace spindown::cli
