#pragma once
// Reporting fitted runs: design §5's JSON object and a text table like the lab report's
// (model | curve constants | coefficients ± standard error | RMSE | R² | BIC | predicted
// stop), plus which model fits best and why. Shared by `spindown fit` and the live fitter.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "spindown/fit.hpp"
#include "spindown/motor_health.hpp"
#include "spindown/recording.hpp"

namespace spindown {

// Everything `spindown fit` learnt about one input file.
struct FileFit {
  std::string file;                     // as named by the user
  // A text file's bench and student when a roster or --bench-pattern named them ("" otherwise).
  // Text: "(bench B, student S)" in the file's line; JSON: "bench_id", "student" beside "file".
  std::string bench, student;
  std::size_t samples = 0;              // samples read
  std::size_t lines_read = 0, lines_skipped = 0;
  std::vector<Diagnostic> diagnostics;  // reading, segmentation and fitting problems
  std::vector<RunFit> runs;
  // The bench each run is from (same order as runs) when the file is an LCM log of several
  // benches; empty for a file of one bench. JSON: "bench" -> "id"; text: a "-- bench" line.
  std::vector<std::string> run_bench;
  std::vector<std::string> run_student;  // a name written in the file before each run's cut ("" none)
  bool lcm_log = false;  // what was read were LCM messages, not text lines
  // Motor health verdict per run (same order as runs) when a bench file was given; empty or
  // nullopt entries: not assessed (no "health" in JSON).
  std::vector<std::optional<HealthVerdict>> health;
  // Why the file, or a run in it, could not be used; non-empty means exit code 1.
  std::vector<std::string> failures;
  bool usable() const { return failures.empty(); }
};

struct ReportOptions {
  bool lab_units = false;          // add g·cm², g·cm²·s⁻¹, g·cm²·rad·s⁻² beside SI
  std::size_t max_diagnostics = 8; // shown per file before the rest is summarised; 0 = all
  bool diagnostics_in_text = true; // false when the caller prints them elsewhere (stderr)
  bool details = false;            // text: 95 % intervals, correlations, reduced χ² (JSON has them always)
};

// JSON keeps insertion order so the object reads like the contract.
using Json = nlohmann::ordered_json;

// Design §5: {"files":[{"file":…,"runs":[{"run":1,"t_cut_s":…,"t_stop_s":…,"samples":…,
// "models":[{"name":…,"params":{"c1":{"value":…,"stderr":…,"unit":…},…},"rmse":…,
// "residual_unit":…,"r2":…,"aic":…,"bic":…}],"best":…}]}]}, plus extra fields (never fewer).
// Non-finite numbers become null.
Json run_fit_json(const RunFit& fit, const ReportOptions& opt = {});
// A run's "health" object: {"level":"ok"|"check"|"service","reason":…,"has_reference":…,
// "findings":[{"what":…,"level":…,"reason":…,"value":…,"stderr":…,"reference":…,
// "reference_stderr":…,"reference_name":…,"ratio":…,"ratio_stderr":…,"unit":…}]}.
Json health_json(const HealthVerdict& verdict);
Json file_fit_json(const FileFit& file, const ReportOptions& opt = {});
Json fit_report_json(std::span<const FileFit> files, const ReportOptions& opt = {});

// How `spindown refit` and a live FIT message tag a run beside run_fit_json(): "bench" -> "id"
// (the last member of "bench"), then "first_seq" and "last_seq" (the last members of the run).
struct RunTags {
  std::string_view bench_id;
  std::int64_t first_seq = 0, last_seq = 0;
  bool has_seq = true;  // false: the bench id only (`spindown fit` on an LCM log of several benches)
};
void tag_run_json(Json& run, const RunTags& tags);  // adds the tags to run_fit_json()'s document
Json tagged_run_fit_json(const RunFit& fit, const RunTags& tags, const ReportOptions& opt = {});

// run_fit_json(fit, opt) (tagged_run_fit_json when tags are given) exactly as
// dump(2, ' ', false, Json::error_handler_t::replace) lays it out nested indent spaces deep,
// appended to out without building the document; its first line is not indented (the caller
// places the opening brace).
// health, when given, is the run's "health" member, last (as a file's entry has it).
void append_run_fit_json_text(std::string& out, const RunFit& fit, const ReportOptions& opt, std::size_t indent,
                              const RunTags* tags = nullptr, const HealthVerdict* health = nullptr);

// `spindown fit --json` without a document: one entry of fit_report_json(files)'s "files"
// array exactly as dump(2, ' ', false, Json::error_handler_t::replace) lays it out there
// (indented four spaces, without the separator), written straight to text; compact: as
// dump(-1, …) writes it, no layout whitespace (a third of the bytes), as a pipe or a file gets
// it. Building and freeing the Json document cost as much as reading the files.
std::string file_fit_json_text(const FileFit& file, const ReportOptions& opt = {}, bool compact = false);

// Appends file_fit_json_text() entries, in order, into the bytes of
// fit_report_json(files).dump(2, ' ', false, Json::error_handler_t::replace).
// compact: dump(-1, …)'s bytes instead, of compact entries.
class FitReportJsonText {
 public:
  explicit FitReportJsonText(bool compact = false) : compact_(compact) {}
  void add(std::string_view file_json, std::string& out);
  void finish(std::string& out) const;  // no final newline, as dump() gives none

 private:
  bool any_ = false;
  bool compact_ = false;
};

// Text for people.
std::string format_run_fit(const RunFit& fit, const ReportOptions& opt = {});
std::string format_file_fit(const FileFit& file, const ReportOptions& opt = {});
// "file:line: warning: …" lines, errors first; past max_shown the rest is counted per
// severity in one closing line. max_shown 0 = all.
std::vector<std::string> summarize_diagnostics(std::span<const Diagnostic> diagnostics, std::size_t max_shown);
// Why the best model is best: ΔBIC to the runner-up and both RMSEs; fit.best_reason when set.
std::string explain_best(const RunFit& fit);

// "value ± error" with the error to two significant digits and the value to the same
// place, e.g. "1.3973 ± 0.0021" or "(1.3973 ± 0.0021)e-06".
std::string format_value_error(double value, double std_error);

// The one vocabulary of fit, explain and the report. A parameter's name as people read it
// ("omega0" → "ω0", "w_s" → "ω_s", "sensor_offset" → "sensor offset"; c1…c4 as they are); JSON
// keeps the ASCII names.
std::string parameter_display_name(std::string_view name);
// "name = value ± error unit" with the unit spelled for people (N·m·s/rad), and with lab_units
// " = value ± error g·cm²·s⁻¹" after it where the lab has a unit of its own (lab_units.hpp).
std::string parameter_text(const Parameter& p, bool lab_units);
// The lab-unit part alone (" = … g·cm²·s⁻¹"), "" when the lab used the SI unit.
std::string lab_unit_text(const Parameter& p);

}  // namespace spindown
