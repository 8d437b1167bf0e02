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
};

struct LogRefit {
  FileFit file;                 // runs ordered by bench (first appearance), then run number; their health
  std::vector<RefitRun> runs;   // the same runs, with their bench ids (empty when streamed)
  std::size_t runs_fitted = 0;  // runs fitted, kept or streamed
  std::vector<fit_t> live;      // SPINDOWN.<bench>.FIT messages recorded in the log (when asked)
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

// file_fit_json() with each run tagged as fit_message_json() tags a live FIT: bench.id,
// first_seq, last_seq.
Json refit_file_json(const LogRefit& refit, const ReportOptions& opt);

}  // namespace spindown
