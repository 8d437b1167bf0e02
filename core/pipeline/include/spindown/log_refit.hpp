#pragma once
// An LCM log through the live fitter's code: the log's events, in log order and with their
// receive times, fed to a FitterCore, so every bench's runs and numbers are exactly what
// spindown-fitter gave for that traffic (`spindown refit`, `spindown export`).
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <spindown/explain_t.hpp>
#include <spindown/fit_t.hpp>

#include "spindown/fit_report.hpp"
#include "spindown/fitter_core.hpp"
#include "spindown/lcm_log_reader.hpp"

namespace spindown {

// One run as the live fitter would have published it.
struct RefitRun {
  std::string bench;
  RunFit fit;
  std::string bench_source;
  std::int64_t first_seq = 0, last_seq = 0;
  std::optional<HealthVerdict> health;  // when FitterOptions::health has the bench (as the live FIT)
  std::optional<ExplainResult> explain; // when FitterOptions::explain_base is set (as the live EXPLAIN)
};

struct LogRefit {
  FileFit file;                 // runs ordered by bench (first appearance), then run number, with their
                                // health; file: the session's first log
  std::vector<std::string> session_files;  // the logs read as this one session, in time order
  std::vector<RefitRun> runs;   // the same runs, with their bench ids (empty when streamed)
  std::size_t runs_fitted = 0;  // runs fitted, kept or streamed
  // SPINDOWN.<bench>.FIT messages recorded in the log (when asked) that passed the gate (the lab;
  // with a key, signed) and came from a fitter: when the log holds fitters' heartbeats, a FIT from a
  // session none of them has is not one (a forged FIT) and is left out, named in the diagnostics.
  std::vector<fit_t> live;
  std::size_t live_left_out = 0;  // FITs from a session no fitter in the log has
  std::vector<explain_t> live_explains;  // SPINDOWN.<bench>.EXPLAIN messages recorded (when asked)
  FitterCounters counters;
  std::vector<std::string> bench_order;  // benches in order of first appearance
};

// Streams one log through a FitterCore (each event in log order, its receive time from the
// log). each_event, when given, sees every event first (export writes samples from it).
// progress, when given, is told every few hundred events how far the read is (bytes of the
// file) and how many runs have been fitted.
// each_run, when given, receives every run as soon as it is fitted (per bench in run order,
// benches interleaved as the log has them) and the runs are not kept: LogRefit::runs and
// file.runs stay empty and memory stays flat in the log's length (runs_fitted counts them).
using RefitProgressFn = std::function<void(std::int64_t bytes_done, std::int64_t bytes_total, std::size_t runs)>;
using RefitRunFn = std::function<void(RefitRun&& run)>;
LogRefit refit_log(const std::string& path, const FitterOptions& options, bool keep_live_fits,
                   const std::function<void(const LcmLogEvent&)>& each_event = {},
                   const RefitProgressFn& progress = {}, const RefitRunFn& each_run = {});

// Several logs of one session (a logger's files rotated hourly, or by size), read one after the
// other through the same FitterCore, as the live fitter saw that traffic: a run that crosses a
// file boundary is one run, as it was live. `paths` must be in time order (log_session_order()).
// progress's bytes count over all the files.
LogRefit refit_log_session(const std::vector<std::string>& paths, const FitterOptions& options, bool keep_live_fits,
                           const std::function<void(const LcmLogEvent&)>& each_event = {},
                           const RefitProgressFn& progress = {}, const RefitRunFn& each_run = {});

// Logs grouped into sessions, each in time order: sorted by their first event's time; a log
// joins the session before it when it starts no earlier than that session's last log ends (a
// rotation), else (another logger's copy of the same traffic, an overlap) it starts a session
// of its own. A log whose events cannot be read is a session of its own (its refit says why).
std::vector<std::vector<std::string>> log_sessions(const std::vector<std::string>& paths);

// file_fit_json() with each run tagged as fit_message_json() tags a live FIT: bench.id,
// first_seq, last_seq.
Json refit_file_json(const LogRefit& refit, const ReportOptions& opt);

}  // namespace spindown
