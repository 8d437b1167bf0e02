#pragma once
// One lab session's results gathered for a report: every input file read (Arduino/PuTTY text,
// delimited text, LCM logs with one recording per bench), every run fitted with each model,
// explained (design §6) and judged for motor health; runs grouped by bench in time order, and
// per bench the drift of the friction coefficients (combined model's c_v, c_c) over its runs
// with a trend and its uncertainty. html_report.hpp renders it; building it never throws for
// bad input (problems become diagnostics and failures, and the rest is still used).
#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "spindown/bench.hpp"
#include "spindown/bench_file.hpp"
#include "spindown/bench_naming.hpp"
#include "spindown/read_recording.hpp"
#include "spindown/recording.hpp"
#include "spindown/recording_time.hpp"
#include "spindown/runs.hpp"
#include "spindown/session_report.hpp"

namespace spindown {

// What one bench's TOML file (--bench-config) says that a report uses.
struct BenchReference {
  std::string file;
  MotorHealthConfig health;           // datasheet / baseline / thresholds
  std::optional<BenchFile> bench;     // its [bench] J and K_b (for choose_bench_params), when it sets either
};

// What a report needs of a bench file (load_bench_file): its health references, and J, K_b
// when its [bench] section sets them.
BenchReference bench_reference(const BenchFile& file);

struct SessionReportOptions {
  ReadOptions read;
  FitOptions fit;               // models and the default bench (lab defaults or the command line's)
  ExplainOptions explain;       // base model and workflow settings (bench set per run)
  bool explain_runs = true;
  BenchChoice bench;            // the command line's J and K_b (choose_bench_params; fit.bench is its given)
  BenchNaming naming;           // which bench a text file is from (roster, pattern, --bench); else its file name
  std::map<std::string, BenchReference, std::less<>> references;  // by bench id
  std::size_t max_diagnostics_per_file = 200;  // kept per file; the rest are counted
};

struct ReportProgress {
  std::uintmax_t bytes_done = 0, bytes_total = 0;
  std::size_t runs_found = 0, runs_done = 0;
  std::string_view file;
};
using ReportProgressFn = std::function<void(const ReportProgress&)>;

// Reads, fits, explains and judges every file; never throws for bad input.
SessionReport build_session_report(std::span<const std::string> paths, const SessionReportOptions& options,
                                   const ReportProgressFn& progress = {});

// The pieces, for callers that already hold recordings (tests, services).
// One run of rec on bench: fit, explain, health.
ReportRun make_report_run(const Recording& rec, const Run& run, const std::string& bench, const BenchParams& params,
                          const SessionReportOptions& options);
// Fills run.context_tau/context_y from rec, whose runs (in any order) are runs: at most max_points
// samples, the lowest and the highest of each stretch kept when it must thin them (a spike, a
// floating pin or a lost coast stays visible).
void set_run_context(ReportRun& run, const Recording& rec, std::span<const Run> runs, std::size_t max_points = 4000);


}  // namespace spindown
