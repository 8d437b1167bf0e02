#pragma once
// Reporting the discrepancy workflow: the story in words, design §5's `explain --json`
// object, and an SVG figure (measurement and the model after every step, each with its RMSE;
// residuals before and after). Shared by `spindown explain` and the live fitter. The vocabulary is
// spindown fit's (fit_report.hpp): c1…c4, ω0, N·m·s/rad, the reading noise σ, --lab-units.
#include <cstddef>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "spindown/explain.hpp"
#include "spindown/fit_report.hpp"
#include "spindown/recording.hpp"

namespace spindown {

// Everything `spindown explain` learnt about one input file.
struct FileExplain {
  std::string file;
  std::size_t samples = 0;
  std::vector<Diagnostic> diagnostics;
  std::vector<ExplainResult> runs;
  std::vector<std::string> run_bench;  // a log of several benches: each run's bench id (same order)
  std::vector<std::string> failures;  // non-empty means exit code 1
  bool usable() const { return failures.empty(); }
};

using ExplainJson = nlohmann::ordered_json;

// {"run":1,"base":[…],"steps":[{"added":…,"rmse_before":…,"rmse_after":…,"where":[{"t_from_s":…,
// "t_to_s":…,"mean_residual":…}],"why":…}],"final":[…],"rmse_base":…,"rmse_final":…} plus extra
// fields (units, parameters under fit's names, candidates, the reading noise σ, conclusion).
// Non-finite numbers become null. bench: the run's bench id when its file holds several
// ("bench": … after "run"), else "". opt.lab_units: each parameter with a lab unit also carries
// "lab": {"value","stderr","unit"}, as spindown fit --json --lab-units gives it.
ExplainJson explain_run_json(const ExplainResult& r, std::string_view bench = {}, const ReportOptions& opt = {});
ExplainJson explain_report_json(std::span<const FileExplain> files, const ReportOptions& opt = {});

// The story, step by step, for people.
// bench: as explain_run_json ("run 1 of bench b2: …"); opt.lab_units: the lab's units beside SI.
std::string format_explain(const ExplainResult& r, std::string_view bench = {}, const ReportOptions& opt = {});
// The same for every run of a file, headed by the file name.
std::string format_file_explain(const FileExplain& file, const ReportOptions& opt = {});

// One SVG document; one figure (two panels) per run, stacked. Titles name file, bench (a log of
// several) and run. The top panel draws the base model and the model after each step, each
// labelled with its RMSE (the gap shrinking step by step: <polyline class="model" data-step="N"
// data-rmse="…">, step 0 the base); the bottom one their residuals' bin means.
std::string explain_svg(std::span<const FileExplain> files);

}  // namespace spindown
