#pragma once
// A lab session's results as the report shows them (`spindown report`, render_html_report): the
// files read, every run's fit, explanation and verdict with its samples, and per bench the
// friction coefficients' trend over its runs. Built from files by build_session_report (pipeline).
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "spindown/explain.hpp"
#include "spindown/fit.hpp"
#include "spindown/motor_health.hpp"
#include "spindown/recording.hpp"
#include "spindown/runs.hpp"

namespace spindown {

struct ReportRun {
  std::string bench;
  std::size_t file_index = 0;     // into SessionReport::files
  std::string source;             // the recording (file, or "FILE SPINDOWN.<bench>.SAMPLE")
  RunFit fit;
  bool explained = false;
  ExplainResult explain;          // when explained
  std::vector<double> tau, y;     // the fitted samples: seconds after the cut, raw reading
  // The recording around the run (set_run_context), seconds after the cut and raw reading: from the
  // end of the run before it (else the recording's start) to the cut of the run after it (else the
  // recording's end), so that what came before the cut (a lead-in, a coast the cut missed) shows
  // beside the fitted window. Empty: the figure shows the fitted window only.
  std::vector<double> context_tau, context_y;
  HealthVerdict health;
  std::string health_config;      // the bench file the verdict used; "" = no reference configured
  std::optional<double> cut_unix_s;  // wall-clock time of the cut when the file tells it
  bool cut_local = false;            // that time is the recording PC's local time (PuTTY), not UTC
  int order = 0;                  // 1-based position among its bench's runs (time order)
};

struct ReportFile {
  std::string file;
  std::string format = "auto";     // the reader's name (file_format_name)
  std::uintmax_t bytes = 0;
  std::size_t samples = 0;
  std::vector<std::string> benches;
  std::string student;                  // a text file's, when the roster or --bench-pattern names one
  std::optional<double> start_unix_s;   // PuTTY header or the log's first event (recording_time.hpp)
  bool start_local = false;             // a PuTTY header's: the recording PC's local time, not UTC
  std::vector<Diagnostic> diagnostics;  // at most max_diagnostics_per_file
  std::size_t diagnostics_dropped = 0;
  std::vector<std::string> failures;    // why the file or a run in it could not be used
};

// A friction coefficient over a bench's runs: weighted least-squares line through the values
// (weights 1/stderr²), its slope's standard error widened by the scatter beyond the stated
// errors (Birge ratio), and the change the line makes over the runs' span.
struct CoefficientTrend {
  std::string name;               // "c3" or "c4" (the combined model's, as spindown fit names them)
  std::string unit;               // ASCII SI unit
  std::vector<double> x, value, std_error;  // the points (x in x_unit)
  std::string x_unit;             // "day" when every run has a wall-clock time, else "run"
  double mean = 0, mean_stderr = 0;          // weighted mean; its error widened by the scatter
  // Run-to-run scatter about the mean in units of the runs' own errors, √(χ²/(n−1)) (1 for one
  // run). Far above 1 the runs disagree: one number does not describe them, and the words say so.
  double scatter = 1;
  double slope = 0, slope_stderr = 0;        // per x_unit
  double intercept = 0;                      // the line's value at x = 0
  double change = 0, change_stderr = 0;      // slope × span (SI)
  double relative_change = 0, relative_change_stderr = 0;  // change / mean
  bool enough = false;            // at least min_runs points with a spread in x
  bool drifting = false;          // |slope| > drift_sigma·stderr and |relative change| ≥ drift_fraction
  // A step between two sessions (a repair, a part replaced): the runs before and after each agree
  // on a level, far better than with any straight line. Then it is no drift.
  bool stepped = false;
  double step_x = 0;              // where: midway between the last point before and the first after
  double level_before = 0, level_after = 0;
  std::string words;              // "dry friction rose 35 % ± 6 % over 5 runs: drifting"
};

struct TrendRules {
  std::size_t min_runs = 3;
  double drift_sigma = 3.0;
  double drift_fraction = 0.10;
  // Scatter (in the runs' errors) above which the runs are said to disagree: a worn motor among
  // good ones, another bench's file, a bad run. Below it, run-to-run variation a motor has.
  double disagree_scatter = 5.0;
};

// x0_unix: the wall-clock time of x = 0 when x_unit is "day" (to name a step's dates), else 0.
CoefficientTrend coefficient_trend(std::string name, std::string unit, std::string x_unit, std::vector<double> x,
                                   std::vector<double> value, std::vector<double> std_error,
                                   const TrendRules& rules = {}, double x0_unix = 0);

struct BenchSummary {
  std::string bench;
  std::vector<std::size_t> runs;  // indices into SessionReport::runs, time order
  HealthLevel worst = HealthLevel::not_judged;
  bool has_reference = false;
  std::string reference_file;
  CoefficientTrend viscous, coulomb;  // from the combined model
};

struct SessionReport {
  std::vector<ReportFile> files;      // time order when every file has a start time, else as given
  std::vector<ReportRun> runs;        // by bench (sorted id), then time order
  std::vector<BenchSummary> benches;  // sorted by id
  bool files_time_ordered = false;    // files were sorted by their start times
  std::vector<std::string> notes;     // session-wide remarks (unused bench configs, …)
  bool usable() const;                // no file or run failed
};

// Sorts runs by bench then time order, numbers them, and fills the bench summaries.
void summarize_session(SessionReport& report);

}  // namespace spindown
