#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "spindown/fit_report.hpp"
#include "spindown/health_report.hpp"

using namespace spindown;

namespace {

constexpr double inf = std::numeric_limits<double>::infinity();
constexpr double not_a_number = std::numeric_limits<double>::quiet_NaN();

Parameter param(std::string name, double v, double se, std::string unit) {
  return Parameter{std::move(name), v, se, std::move(unit)};
}

ModelFit model(ModelKind kind, std::vector<Parameter> params, double rmse, double bic, double t_stop) {
  ModelFit m;
  m.kind = kind;
  m.params = std::move(params);
  m.rmse = rmse;
  m.r2 = 0.999;
  m.aic = bic + 5;
  m.bic = bic;
  m.t_stop_pred_s = t_stop;
  m.n = 1400;
  m.converged = true;
  return m;
}

// A hand-made fit shaped like the lab's 3 V run.
RunFit lab_like_fit() {
  RunFit f;
  f.run.number = 1;
  f.run.cut_index = 100;
  f.run.stop_index = 1400;
  f.run.end_index = 1500;
  f.run.t_cut_s = 8.244;
  f.run.t_stop_s = 35.49;
  f.run.stopped = true;
  f.run.zero_level = 0.0;
  f.run.noise_level = 0.004;
  f.run.lead_in = "zeros";
  f.run.period_s = 0.020;
  f.quantity = Quantity::back_emf_volts;
  f.models.push_back(model(ModelKind::viscous,
                           {param("c1", 1.3973e-6, 2.1e-9, "N*m*s/rad"), param("omega0", 346.6, 0.23, "rad/s"),
                            param("A", 2.805, 0.0019, "V"), param("B", 0.124, 0.0002, "1/s")},
                           0.061, -5000.0, inf));
  f.models.push_back(model(ModelKind::coulomb,
                           {param("c2", 1.3827e-4, 1.1e-7, "N*m"), param("omega0", 340.1, 0.1, "rad/s"),
                            param("A", -0.0993, 0.0001, "V/s"), param("B", 2.75, 0.001, "V")},
                           0.0068, -8000.0, 27.7));
  f.models.push_back(model(ModelKind::combined,
                           {param("c3", 1.822e-7, 3.4e-9, "N*m*s/rad"), param("c4", 1.1389e-4, 2.0e-7, "N*m"),
                            param("omega0", 345.99, 0.12, "rad/s"), param("A", -5.0581, 0.01, "V"),
                            param("B", 7.858, 0.01, "V"), param("C", -0.01617, 0.0003, "1/s")},
                           0.0041, -8412.5, 27.25));
  f.best = "combined";
  return f;
}

FileFit one_file(RunFit run) {
  FileFit file;
  file.file = "seed-3v-run1.tsv";
  file.samples = 1681;
  file.lines_read = 1683;
  file.lines_skipped = 2;
  file.diagnostics.push_back({Diagnostic::Severity::note, file.file, 1, "PuTTY header skipped"});
  file.runs.push_back(std::move(run));
  return file;
}

// Display column of the first occurrence of needle in line (code points, not bytes).
std::size_t display_column(const std::string& line, const std::string& needle) {
  const auto pos = line.find(needle);
  if (pos == std::string::npos) return std::string::npos;
  std::size_t col = 0;
  for (std::size_t i = 0; i < pos; ++i)
    if ((static_cast<unsigned char>(line[i]) & 0xC0) != 0x80) ++col;
  return col;
}

}  // namespace

TEST(FitReportJson, HasTheContractKeys) {
  const FileFit files[] = {one_file(lab_like_fit())};
  const Json j = fit_report_json(files);
  ASSERT_TRUE(j.contains("files"));
  const auto& file = j["files"].at(0);
  EXPECT_EQ(file["file"], "seed-3v-run1.tsv");
  const auto& run = file["runs"].at(0);
  EXPECT_EQ(run["run"], 1);
  EXPECT_DOUBLE_EQ(run["t_cut_s"].get<double>(), 8.244);
  EXPECT_DOUBLE_EQ(run["t_stop_s"].get<double>(), 35.49);
  EXPECT_EQ(run["samples"], 1400);
  EXPECT_EQ(run["best"], "combined");
  ASSERT_EQ(run["models"].size(), 3u);
  const char* names[] = {"viscous", "coulomb", "combined"};
  for (int i = 0; i < 3; ++i) {
    const auto& m = run["models"][i];
    EXPECT_EQ(m["name"], names[i]);
    for (const char* key : {"params", "rmse", "residual_unit", "r2", "aic", "bic"}) EXPECT_TRUE(m.contains(key)) << key;
    EXPECT_EQ(m["residual_unit"], "V");
  }
  const auto& c3 = run["models"][2]["params"]["c3"];
  EXPECT_DOUBLE_EQ(c3["value"].get<double>(), 1.822e-7);
  EXPECT_DOUBLE_EQ(c3["stderr"].get<double>(), 3.4e-9);
  EXPECT_EQ(c3["unit"], "N*m*s/rad");
  EXPECT_EQ(run["models"][2]["params"]["c4"]["unit"], "N*m");
  EXPECT_TRUE(run["models"][2]["params"].contains("C"));
  EXPECT_DOUBLE_EQ(run["models"][2]["rmse"].get<double>(), 0.0041);
  EXPECT_DOUBLE_EQ(run["models"][2]["bic"].get<double>(), -8412.5);
  // Extras the contract allows.
  EXPECT_DOUBLE_EQ(run["bench"]["J"].get<double>(), BenchParams{}.inertia_kg_m2);
  EXPECT_EQ(file["diagnostics"].at(0)["line"], 1);
  // No lab units unless asked.
  EXPECT_FALSE(c3.contains("lab"));
}

TEST(FitReportJson, NonFiniteNumbersBecomeNullAndStayValidJson) {
  RunFit f = lab_like_fit();
  f.run.stopped = false;
  f.run.t_stop_s = not_a_number;
  f.models[0].params[0].std_error = not_a_number;  // a singular Jacobian
  f.models[1].r2 = -inf;
  const FileFit files[] = {one_file(f)};
  const std::string text = fit_report_json(files).dump();
  EXPECT_EQ(text.find("NaN"), std::string::npos);
  EXPECT_EQ(text.find("nan"), std::string::npos);
  EXPECT_EQ(text.find("inf"), std::string::npos);
  const Json back = Json::parse(text);  // throws if not valid JSON
  const auto& run = back["files"][0]["runs"][0];
  EXPECT_TRUE(run["t_stop_s"].is_null());
  EXPECT_TRUE(run["models"][0]["t_stop_pred_s"].is_null());  // viscous never stops
  EXPECT_TRUE(run["models"][0]["params"]["c1"]["stderr"].is_null());
  EXPECT_TRUE(run["models"][1]["r2"].is_null());
  EXPECT_DOUBLE_EQ(run["models"][2]["t_stop_pred_s"].get<double>(), 27.25);
}

TEST(FitReportJson, LabUnitsAddedBesideSi) {
  ReportOptions opt;
  opt.lab_units = true;
  const Json run = run_fit_json(lab_like_fit(), opt);
  const auto& c3 = run["models"][2]["params"]["c3"];
  EXPECT_NEAR(c3["lab"]["value"].get<double>(), 1.822, 1e-12);
  EXPECT_EQ(c3["lab"]["unit"], "g*cm^2/s");
  EXPECT_DOUBLE_EQ(c3["value"].get<double>(), 1.822e-7);  // SI stays
  const auto& c4 = run["models"][2]["params"]["c4"];
  EXPECT_NEAR(c4["lab"]["value"].get<double>(), 1138.9, 1e-9);
  EXPECT_EQ(c4["lab"]["unit"], "g*cm^2*rad/s^2");
  EXPECT_FALSE(run["models"][2]["params"]["omega0"].contains("lab"));
  EXPECT_NEAR(run["bench"]["J_lab"]["value"].get<double>(), 112.687602, 1e-9);
}

TEST(FitReportText, TableLikeTheLabReport) {
  const std::string text = format_run_fit(lab_like_fit());
  for (const char* s : {"viscous", "coulomb", "combined", "curve constants", "RMSE", "BIC", "c1 = ", "c2 = ",
                        "c3 = ", "c4 = ", "A = -5.0581 V", "C = -0.01617 s⁻¹", "N·m·s/rad", "never", "27.25 s",
                        "best: combined"})
    EXPECT_NE(text.find(s), std::string::npos) << "missing '" << s << "' in\n" << text;
  // Why: ΔBIC to the runner-up (coulomb, BIC −8000) and both RMSEs.
  EXPECT_NE(text.find("ΔBIC = 412.5 below coulomb"), std::string::npos) << text;
  EXPECT_NE(text.find("RMSE 0.0041 vs 0.0068"), std::string::npos) << text;
  EXPECT_EQ(text.find("g·cm²·s⁻¹"), std::string::npos);  // SI only by default
}

TEST(FitReportText, ColumnsAlignDespiteMultibyteUnits) {
  const std::string text = format_run_fit(lab_like_fit());
  std::vector<std::string> lines;
  for (std::size_t a = 0, b; a < text.size(); a = b + 1) {
    b = text.find('\n', a);
    if (b == std::string::npos) b = text.size();
    lines.push_back(text.substr(a, b - a));
  }
  std::size_t header_col = std::string::npos, rows = 0;
  for (const auto& l : lines) {
    if (l.find("model") != std::string::npos && l.find("RMSE") != std::string::npos) header_col = display_column(l, "RMSE");
    for (const char* rmse : {"0.061 V", "0.0068 V", "0.0041 V"})
      if (l.find(rmse) != std::string::npos) {
        ASSERT_NE(header_col, std::string::npos);
        EXPECT_EQ(display_column(l, rmse), header_col) << l;
        ++rows;
      }
  }
  EXPECT_EQ(rows, 3u) << text;
}

TEST(FitReportText, LabUnitsOnRequest) {
  ReportOptions opt;
  opt.lab_units = true;
  const std::string text = format_run_fit(lab_like_fit(), opt);
  EXPECT_NE(text.find("g·cm²·s⁻¹"), std::string::npos) << text;
  EXPECT_NE(text.find("g·cm²·rad·s⁻²"), std::string::npos) << text;
  EXPECT_NE(text.find("1.822 ± 0.034 g·cm²·s⁻¹"), std::string::npos) << text;
  EXPECT_NE(text.find("112.688 g·cm²"), std::string::npos) << text;
}

TEST(FitReportText, FileHeaderAndFailures) {
  FileFit file = one_file(lab_like_fit());
  file.failures.push_back("run 2: no model converged");
  const std::string text = format_file_fit(file);
  EXPECT_NE(text.find("== seed-3v-run1.tsv: 1681 samples"), std::string::npos) << text;
  EXPECT_NE(text.find("seed-3v-run1.tsv:1: note: PuTTY header skipped"), std::string::npos) << text;
  EXPECT_NE(text.find("not used: run 2: no model converged"), std::string::npos) << text;
  ReportOptions quiet;
  quiet.diagnostics_in_text = false;
  EXPECT_EQ(format_file_fit(file, quiet).find("PuTTY header"), std::string::npos);
  EXPECT_FALSE(file.usable());
}

// One noise figure, named as explain and the report name it: the reading noise σ of the coast (not
// the detector's spread at standstill, which an ADC clipping at 0 shrinks), in text and JSON.
TEST(FitReportText, NoiseIsTheReadingNoiseSigma) {
  RunFit f = lab_like_fit();
  f.reading_noise = 0.0042;
  for (bool stopped : {true, false}) {
    f.run.stopped = stopped;
    const std::string text = format_run_fit(f);
    EXPECT_NE(text.find("reading noise σ 0.0042 V"), std::string::npos) << text;
    EXPECT_EQ(text.find("standstill noise"), std::string::npos) << text;
    EXPECT_EQ(text.find("coast noise"), std::string::npos) << text;
  }
  EXPECT_DOUBLE_EQ(run_fit_json(f)["reading_noise"].get<double>(), 0.0042);
}

TEST(FitReportText, BestReasonFromTheFitWins) {
  RunFit f = lab_like_fit();
  f.best_reason = "because the fitter said so";
  EXPECT_EQ(explain_best(f), "because the fitter said so");
  f.best_reason.clear();
  f.models.resize(1);
  f.best = "viscous";
  EXPECT_EQ(explain_best(f), "viscous is the only model asked for");
  f.models.resize(2);
  f.models[1].converged = false;
  EXPECT_EQ(explain_best(f), "viscous is the only model that converged");
  f.best.clear();
  EXPECT_EQ(explain_best(f), "no model converged");
}

TEST(FormatValueError, ErrorToTwoDigitsValueToTheSamePlace) {
  EXPECT_EQ(format_value_error(346.614, 0.2345), "346.61 ± 0.23");
  EXPECT_EQ(format_value_error(0.124, 0.0012), "0.1240 ± 0.0012");
  EXPECT_EQ(format_value_error(1.3973e-6, 2.1e-9), "(1.3973 ± 0.0021)e-06");
  EXPECT_EQ(format_value_error(1.1389e-4, 2.0e-7), "(1.1389 ± 0.0020)e-04");
  EXPECT_EQ(format_value_error(1138.9, 12.0), "1139 ± 12");
  EXPECT_EQ(format_value_error(2.5, 0), "2.5");
  EXPECT_EQ(format_value_error(2.5, not_a_number), "2.5 ± ?");
  EXPECT_EQ(format_value_error(inf, 1), "inf");
}

TEST(SummarizeDiagnostics, ErrorsFirstThenACount) {
  std::vector<Diagnostic> d;
  for (int i = 1; i <= 20; ++i) d.push_back({Diagnostic::Severity::warning, "f.tsv", i, "garbled line"});
  d.push_back({Diagnostic::Severity::error, "f.tsv", 0, "no run found"});
  const auto lines = summarize_diagnostics(d, 5);
  ASSERT_EQ(lines.size(), 6u);
  EXPECT_EQ(lines[0], "f.tsv: error: no run found");
  EXPECT_EQ(lines[1], "f.tsv:1: warning: garbled line");
  EXPECT_EQ(lines[5], "f.tsv: ... and 16 more not shown (16 warnings)");
  EXPECT_EQ(summarize_diagnostics(d, 0).size(), 21u);
  EXPECT_TRUE(summarize_diagnostics({}, 5).empty());
}

// `spindown fit --json` writes each file's entry as text, without the Json document: the bytes
// must be the document's dump, whatever the report holds.
namespace {

std::string streamed(std::span<const FileFit> files, const ReportOptions& opt) {
  std::string out;
  FitReportJsonText doc;
  for (const auto& f : files) doc.add(file_fit_json_text(f, opt), out);
  doc.finish(out);
  return out;
}

std::string document(std::span<const FileFit> files, const ReportOptions& opt) {
  return fit_report_json(files, opt).dump(2, ' ', false, Json::error_handler_t::replace);
}

// As `spindown fit --json` writes into a pipe or a file: compact entries.
std::string streamed_compact(std::span<const FileFit> files, const ReportOptions& opt) {
  std::string out;
  FitReportJsonText doc(true);
  for (const auto& f : files) doc.add(file_fit_json_text(f, opt, true), out);
  doc.finish(out);
  return out;
}

HealthVerdict a_verdict() {
  HealthVerdict v;
  v.level = HealthLevel::check;
  v.reason = "dry friction 2.4× the baseline: check bearings";
  v.has_reference = true;
  HealthFinding f;
  f.what = "dry friction";
  f.level = HealthLevel::check;
  f.reason = "2.4× the \"baseline\"\ttab";
  f.value = 2.4e-4;
  f.std_error = not_a_number;
  f.reference = 1e-4;
  f.reference_name = "baseline";
  f.ratio = 2.4;
  f.unit = "N*m";
  v.findings = {f, f};
  v.findings[1].value = inf;
  return v;
}

}  // namespace

TEST(FitReportJsonText, MatchesTheDocumentsDumpByteForByte) {
  RunFit odd = lab_like_fit();
  odd.run.number = 2;
  odd.run.stopped = false;
  odd.run.lead_in = "";
  odd.best.clear();
  odd.models[0].converged = false;
  odd.models[0].message = "did not converge: \"λ\" grew \\ past 1e10\n";
  odd.models[1].params.clear();
  odd.models[2].rmse = not_a_number;
  odd.models[2].bic = -inf;
  odd.bench.inertia_source = "bench file (caf\xe9.toml)";  // Latin-1: not UTF-8
  odd.bench.kb_source = "K_b ω";

  FileFit usual = one_file(lab_like_fit());
  FileFit two_runs = one_file(lab_like_fit());
  two_runs.file = "name with \"quotes\" and \x01 control.tsv";
  two_runs.runs.push_back(odd);
  two_runs.health = {std::nullopt, a_verdict()};
  two_runs.diagnostics.push_back({Diagnostic::Severity::warning, two_runs.file, 77, "\"5254\\t2.x8\": value is not a number"});
  two_runs.diagnostics.push_back({Diagnostic::Severity::error, two_runs.file, 0, "bytes \xff\xfe not UTF-8"});
  two_runs.failures = {"run 2: no model converged", "caf\xe9"};
  FileFit empty;
  empty.file = "empty.tsv";
  empty.failures = {"no samples: the file is empty"};
  FileFit health_only = one_file(lab_like_fit());
  health_only.health = {a_verdict()};
  FileFit repeated = one_file(lab_like_fit());  // a repeated key: the document keeps one member
  repeated.runs[0].models[0].params.push_back(param("c1", 9.0, 1.0, "N*m*s/rad"));

  FileFit benches = one_file(lab_like_fit());  // an LCM log of two benches: each run names its own
  benches.runs.push_back(odd);
  benches.run_bench = {"bench000", "b\"1"};
  benches.health = {a_verdict(), std::nullopt};
  benches.lcm_log = true;

  const std::vector<FileFit> all = {usual, two_runs, empty, health_only, repeated, benches};
  for (const bool lab_units : {false, true}) {
    ReportOptions opt;
    opt.lab_units = lab_units;
    EXPECT_EQ(streamed(all, opt), document(all, opt));
    // Compact: the document's dump without indentation, byte for byte (strings with spaces,
    // quotes, backslashes and line breaks inside them keep them).
    EXPECT_EQ(streamed_compact(all, opt), fit_report_json(all, opt).dump(-1, ' ', false, Json::error_handler_t::replace));
    for (const auto& f : all) EXPECT_EQ(streamed({&f, 1}, opt), document({&f, 1}, opt)) << f.file;
  }
  EXPECT_EQ(streamed({}, {}), document({}, {}));
  EXPECT_EQ(streamed_compact({}, {}), fit_report_json({}, {}).dump(-1));
}

// A doubt stands before the numbers it doubts: a reader who stops at the table has seen it.
TEST(FitReportText, ADoubtStandsBeforeTheNumbers) {
  RunFit fit = lab_like_fit();
  fit.doubts = {"readings up to 3364 V: try --value-unit rpm"};
  const std::string text = format_run_fit(fit);
  const auto doubt = text.find("doubtful: readings up to 3364 V"), table = text.find("coefficients ± standard error");
  ASSERT_NE(doubt, std::string::npos) << text;
  ASSERT_NE(table, std::string::npos) << text;
  EXPECT_LT(doubt, table) << text;
  EXPECT_LT(doubt, text.find("zero level")) << text;
}

// `spindown fit` on an LCM log of several benches: a "-- bench" line before each bench's runs,
// "bench" -> "id" in JSON (no sequence numbers: those are the refit's), messages not lines.
TEST(FitReportText, RunsOfSeveralBenchesSayWhoseTheyAre) {
  FileFit f = one_file(lab_like_fit());
  f.runs.push_back(lab_like_fit());
  f.runs.push_back(lab_like_fit());
  f.run_bench = {"bench000", "bench000", "bench001"};
  f.lcm_log = true;
  const std::string text = format_file_fit(f);
  EXPECT_NE(text.find("messages ("), std::string::npos) << text;
  EXPECT_EQ(text.find("lines ("), std::string::npos) << text;
  const auto first = text.find("-- bench bench000"), second = text.find("-- bench bench001");
  ASSERT_NE(first, std::string::npos) << text;
  ASSERT_NE(second, std::string::npos) << text;
  EXPECT_EQ(text.find("-- bench bench000", first + 1), std::string::npos) << "one line per bench, not per run";
  const Json j = file_fit_json(f, {});
  EXPECT_EQ(j["runs"][2]["bench"]["id"], "bench001");
  EXPECT_FALSE(j["runs"][0].contains("first_seq"));
  EXPECT_FALSE(one_file(lab_like_fit()).lcm_log);
  EXPECT_FALSE(file_fit_json(one_file(lab_like_fit()), {})["runs"][0]["bench"].contains("id"));
}

// The refit's run text (tagged, nested eight spaces deep in {"files":[{"runs":[…]}]}) must be the
// tagged document's dump, whatever the run holds; numbers as dump() writes them.
TEST(FitReportJsonText, RunTextMatchesTheTaggedDocumentsDump) {
  RunFit odd = lab_like_fit();
  odd.run.stopped = false;
  odd.best.clear();
  odd.models[0].message = "did not converge: \"λ\" grew \\ past 1e10\n";
  odd.models[1].params.clear();
  odd.models[2].rmse = not_a_number;
  odd.models[2].bic = -inf;
  odd.bench.inertia_source = "bench file (caf\xe9.toml)";
  RunFit numbers = lab_like_fit();
  const double samples[] = {0.0, -0.0, 0.1, 1.0, -1.5, 1e300, 5e-324, 2.2250738585072014e-308, 123456789012345678.0,
                            1.0 / 3.0, 6.02214076e23, -9.87654321e-12};
  std::size_t k = 0;
  for (auto& m : numbers.models)
    for (auto& p : m.params) {
      p.value = samples[k++ % std::size(samples)];
      p.std_error = samples[k++ % std::size(samples)];
    }
  numbers.run.zero_level = -0.0;
  numbers.run.noise_level = 5e-324;
  RunFit repeated = lab_like_fit();  // a repeated key: the document keeps one member
  repeated.models[0].params.push_back(param("c1", 9.0, 1.0, "N*m*s/rad"));

  for (const bool lab_units : {false, true})
    for (const RunFit* fit : {&odd, &numbers, &repeated}) {
      ReportOptions opt;
      opt.lab_units = lab_units;
      const RunTags tags{"bench \"7\"", -3, 1234567890123};
      for (const std::size_t indent : {0, 8}) {
        std::string expected(indent, ' ');
        for (char c : tagged_run_fit_json(*fit, tags, opt).dump(2, ' ', false, Json::error_handler_t::replace)) {
          expected += c;
          if (c == '\n') expected.append(indent, ' ');
        }
        std::string got(indent, ' ');
        append_run_fit_json_text(got, *fit, opt, indent, &tags);
        EXPECT_EQ(got, expected) << lab_units << " " << indent;
        std::string untagged(indent, ' ');
        append_run_fit_json_text(untagged, *fit, opt, indent);
        std::string untagged_expected(indent, ' ');
        for (char c : run_fit_json(*fit, opt).dump(2, ' ', false, Json::error_handler_t::replace)) {
          untagged_expected += c;
          if (c == '\n') untagged_expected.append(indent, ' ');
        }
        EXPECT_EQ(untagged, untagged_expected) << lab_units << " " << indent;
      }
    }
}

// A run judged against nothing says so in words and never reads OK.
TEST(HealthReportText, NotJudgedIsNeverOk) {
  HealthVerdict v;
  v.level = HealthLevel::not_judged;
  v.has_reference = false;
  v.reason = "not judged: the bench file has no [motor] datasheet";
  const std::string text = format_health_verdict(v);
  EXPECT_EQ(text, "  health: NOT JUDGED — not judged: the bench file has no [motor] datasheet\n");
  EXPECT_EQ(health_level_name(HealthLevel::not_judged), "not_judged");
  EXPECT_EQ(parse_health_level("not_judged"), HealthLevel::not_judged);
}
