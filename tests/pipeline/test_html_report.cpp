// The session report: a self-contained page (no external references), text from files
// escaped, one figure per run, the coefficient table with ± values, the health verdict, and a
// drift summary that finds a motor whose dry friction rises over the weeks.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <string>
#include <vector>

#include "spindown/fit_report.hpp"
#include "spindown/html_report.hpp"
#include "spindown/build_session_report.hpp"
#include "spindown/svg_plot.hpp"
#include "spindown/synthetic_run.hpp"

namespace spindown {
namespace {

Recording recording_of(const SyntheticRun& run, const std::string& source) {
  Recording rec;
  rec.source = source;
  for (std::size_t i = 0; i < run.t_ms.size(); ++i) rec.push(run.t_ms[i] / 1000.0, run.volts[i]);
  return rec;
}

Recording synthetic(double coulomb_scale, std::uint64_t seed, const std::string& source) {
  SyntheticRunSpec spec;
  spec.friction.coulomb *= coulomb_scale;
  spec.seed = seed;
  return recording_of(make_synthetic_run(spec), source);
}

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + what.size())) ++n;
  return n;
}

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// Adds one file holding one run to the report.
void add_run(SessionReport& report, const Recording& rec, const std::string& file, const std::string& bench,
             const SessionReportOptions& opt, std::optional<double> start_unix_s = {}) {
  ReportFile f;
  f.file = file;
  f.format = "arduino";
  f.samples = rec.size();
  f.benches = {bench};
  f.start_unix_s = start_unix_s;
  report.files.push_back(f);
  const Segmentation seg = find_runs(rec);
  ASSERT_EQ(seg.runs.size(), 1u) << file;
  ReportRun r = make_report_run(rec, seg.runs[0], bench, BenchParams{}, opt);
  r.file_index = report.files.size() - 1;
  if (start_unix_s) r.cut_unix_s = *start_unix_s + seg.runs[0].t_cut_s;
  report.runs.push_back(std::move(r));
}

const std::string evil_bench = "<script>alert('x')</script>";
const std::string evil_file = "runs/\"weird\" & <b>bold</b>.tsv";

class HtmlReportTest : public ::testing::Test {
 protected:
  void SetUp() override {
    // Bench "good" has a baseline that its runs are far above: its verdict must say so.
    MotorHealthConfig cfg;
    HealthBaseline base;
    const FrictionTerms truth = SyntheticRunSpec{}.friction;
    base.c_viscous = truth.viscous;
    base.c_viscous_stderr = 0.02 * truth.viscous;
    base.c_coulomb = truth.coulomb / 3;  // the runs have 3x the baseline's dry friction
    base.c_coulomb_stderr = 0.01 * base.c_coulomb;
    base.runs = 5;
    base.date = "2026-01-10";
    cfg.baseline = base;
    opt.references["good"] = BenchReference{"benches/good.toml", cfg, std::nullopt};
    add_run(report, synthetic(1.0, 1, "a.tsv"), evil_file, evil_bench, opt);
    add_run(report, synthetic(1.0, 2, "b.tsv"), "b.tsv", "good", opt);
    add_run(report, synthetic(1.0, 3, "c.tsv"), "c.tsv", "good", opt);
    summarize_session(report);
    page = render_html_report(report);
  }
  SessionReportOptions opt;
  SessionReport report;
  std::string page;
};

TEST_F(HtmlReportTest, PageIsSelfContained) {
  const std::string p = lower(page);
  EXPECT_EQ(count(p, "http://"), 0u);
  EXPECT_EQ(count(p, "https://"), 0u);
  EXPECT_EQ(count(p, "<script"), 0u);
  EXPECT_EQ(count(p, " src="), 0u);
  EXPECT_EQ(count(p, "<link"), 0u);
  EXPECT_EQ(count(p, "<img"), 0u);
  EXPECT_EQ(count(p, "url("), 0u);
  EXPECT_EQ(count(p, "@import"), 0u);
  EXPECT_EQ(count(p, "@font-face"), 0u);
  EXPECT_TRUE(page.starts_with("<!DOCTYPE html>"));
  EXPECT_NE(page.find("<style>"), std::string::npos);
}

TEST_F(HtmlReportTest, TextFromFilesIsEscaped) {
  EXPECT_EQ(page.find(evil_bench), std::string::npos);
  EXPECT_NE(page.find("&lt;script&gt;alert(&#39;x&#39;)&lt;/script&gt;"), std::string::npos);
  EXPECT_EQ(page.find("<b>bold</b>"), std::string::npos);
  EXPECT_NE(page.find("runs/&quot;weird&quot; &amp; &lt;b&gt;bold&lt;/b&gt;.tsv"), std::string::npos);
  // Anchors made from the bench id hold only safe characters.
  EXPECT_NE(page.find("id=\"bench-_script_alert__x____script_\""), std::string::npos);
}

TEST_F(HtmlReportTest, OneFigurePerRunAndBalancedElements) {
  EXPECT_EQ(count(page, "<svg class=\"run-plot\""), report.runs.size());
  EXPECT_EQ(count(page, "<article class=\"run\""), report.runs.size());
  for (const char* tag : {"svg", "table", "article", "section", "figure", "details", "p", "tr", "td", "th", "ol", "li"})
    EXPECT_EQ(count(page, std::string("<") + tag + " ") + count(page, std::string("<") + tag + ">"),
              count(page, std::string("</") + tag + ">"))
        << tag;
  // Bench "good" has two runs: its trend figure is in the summary; the single-run bench has none.
  EXPECT_EQ(count(page, "<svg class=\"trend-plot\""), 1u);
}

TEST_F(HtmlReportTest, CoefficientTableWithUncertaintiesInSiAndLabUnits) {
  EXPECT_EQ(count(page, "<table class=\"coef\">"), report.runs.size());
  const RunFit& fit = report.runs[0].fit;
  ASSERT_EQ(fit.best, "combined");
  const Parameter* c3 = fit.model(ModelKind::combined)->param("c3");
  ASSERT_NE(c3, nullptr);
  EXPECT_NE(page.find(format_value_error(c3->value, c3->std_error) + " N·m·s/rad"), std::string::npos);
  EXPECT_NE(page.find(format_value_error(c3->value * 1e7, c3->std_error * 1e7) + " g·cm²·s⁻¹"), std::string::npos);
  const Parameter* c4 = fit.model(ModelKind::combined)->param("c4");
  EXPECT_NE(page.find(format_value_error(c4->value * 1e7, c4->std_error * 1e7) + " g·cm²·rad·s⁻²"), std::string::npos);
  EXPECT_GE(count(page, " ± "), 3 * report.runs.size());
}

TEST_F(HtmlReportTest, HealthVerdictAndExplainStory) {
  // The bench without a config says so; the bench with a baseline gets its finding.
  EXPECT_NE(page.find("no reference configured"), std::string::npos);
  for (const ReportRun& r : report.runs) {
    if (r.bench == "good") {
      EXPECT_TRUE(r.health.has_reference);
      EXPECT_NE(r.health.level, HealthLevel::ok) << r.health.reason;
      EXPECT_EQ(r.health_config, "benches/good.toml");
    } else {
      EXPECT_FALSE(r.health.has_reference);
    }
  }
  EXPECT_NE(page.find("<span class=\"badge service\">SERVICE</span>"), std::string::npos);
  EXPECT_NE(page.find("benches/good.toml"), std::string::npos);
  EXPECT_EQ(count(page, "<div class=\"verdict"), report.runs.size());
  // The explain story: viscous is the belief, the dry friction is what it misses.
  EXPECT_EQ(count(page, "What the data say (explain)"), report.runs.size());
  EXPECT_NE(page.find("Missing effect: <strong>coulomb</strong>"), std::string::npos);
}

TEST(CoefficientTrend, FindsAStraightRiseAndItsUncertainty) {
  std::vector<double> x{0, 7, 14, 21, 28}, v, se;
  for (double d : x) v.push_back(1e-4 * (1 + 0.01 * d)), se.push_back(1e-6);  // +28 % over four weeks
  const auto t = coefficient_trend("c4", "N*m", "day", x, v, se);
  EXPECT_TRUE(t.enough);
  EXPECT_TRUE(t.drifting) << t.words;
  EXPECT_NEAR(t.slope, 1e-6, 1e-9);
  EXPECT_GT(t.slope_stderr, 0);
  EXPECT_NEAR(t.relative_change, 0.28 / 1.14, 0.01);
  EXPECT_NE(t.words.find("rose"), std::string::npos);
  EXPECT_NE(t.words.find("drifting"), std::string::npos);
}

TEST(CoefficientTrend, ScatterWithinErrorsIsSteadyAndFewRunsAreNotATrend) {
  const auto steady = coefficient_trend("c3", "N*m*s/rad", "run", {1, 2, 3, 4, 5},
                                        {1.00e-7, 1.02e-7, 0.99e-7, 1.01e-7, 1.00e-7}, {2e-9, 2e-9, 2e-9, 2e-9, 2e-9});
  EXPECT_TRUE(steady.enough);
  EXPECT_FALSE(steady.drifting) << steady.words;
  // Scatter far beyond the stated errors widens the slope's error (Birge ratio) rather than
  // calling a drift.
  const auto wild = coefficient_trend("c3", "N*m*s/rad", "run", {1, 2, 3, 4, 5}, {1.0e-7, 1.5e-7, 0.8e-7, 1.4e-7, 1.1e-7},
                                      {1e-10, 1e-10, 1e-10, 1e-10, 1e-10});
  EXPECT_FALSE(wild.drifting) << wild.words;
  EXPECT_GT(wild.slope_stderr, 1e-9);
  EXPECT_NE(wild.words.find("not steady: the runs disagree far beyond their errors"), std::string::npos) << wild.words;
  EXPECT_EQ(steady.words.find("disagree"), std::string::npos) << steady.words;
  EXPECT_NE(steady.words.find("steady within its uncertainty"), std::string::npos) << steady.words;
  const auto two = coefficient_trend("c4", "N*m", "run", {1, 2}, {1e-4, 2e-4}, {1e-6, 1e-6});
  EXPECT_FALSE(two.enough);
  EXPECT_FALSE(two.drifting);
}

// Two runs 100 errors apart (a worn motor's file among a good one's): their mean is not known to
// ±0.7 % as their own errors would say, and the words say they disagree.
TEST(CoefficientTrend, RunsFarApartWidenTheMeanAndAreSaid) {
  const auto two = coefficient_trend("c4", "N*m", "run", {1, 2}, {1e-4, 2e-4}, {1e-6, 1e-6});
  EXPECT_NEAR(two.scatter, 70.7, 0.1);             // |Δ| / (√2 σ)
  EXPECT_NEAR(two.mean_stderr, 5e-5, 1e-7);        // half the spread, not 0.7e-6
  EXPECT_NE(two.words.find("the runs disagree far beyond their errors (0.0001 to 0.0002 N*m"), std::string::npos)
      << two.words;
  // A step in four runs is not "steady within its uncertainty", nor a drift: it is named, with where
  // (issue 43: a semester across a repair "stepped up between week 4 and week 5", not "not steady").
  const auto step = coefficient_trend("c4", "N*m", "run", {1, 2, 3, 4}, {1.14e-4, 1.14e-4, 2.5e-4, 2.5e-4},
                                      {3e-7, 3e-7, 3e-7, 3e-7});
  EXPECT_EQ(step.words.find("steady within"), std::string::npos) << step.words;
  EXPECT_TRUE(step.stepped);
  EXPECT_FALSE(step.drifting);
  EXPECT_NE(step.words.find("stepped up 119 % between run 2 and run 3"), std::string::npos) << step.words;
  // With wall-clock days, the step names the dates of the sessions either side.
  const double day0 = 1729555200;  // 2024-10-22 00:00 UTC
  const auto weeks = coefficient_trend("c4", "N*m", "day", {0, 0.01, 7, 7.01, 14, 14.01}, {1.14e-4, 1.15e-4, 1.14e-4,
                                       1.15e-4, 1.94e-4, 1.95e-4}, {1e-6, 1e-6, 1e-6, 1e-6, 1e-6, 1e-6}, {}, day0);
  EXPECT_NE(weeks.words.find("between 2024-10-29 and 2024-11-05"), std::string::npos) << weeks.words;
  // A steady rise is still a drift, not a step.
  const auto rise = coefficient_trend("c4", "N*m", "day", {0, 7, 14, 21, 28, 35}, {1.0e-4, 1.1e-4, 1.2e-4, 1.3e-4,
                                      1.4e-4, 1.5e-4}, {1e-6, 1e-6, 1e-6, 1e-6, 1e-6, 1e-6}, {}, day0);
  EXPECT_TRUE(rise.drifting) << rise.words;
  EXPECT_FALSE(rise.stepped) << rise.words;
  // Runs that agree keep their own small error.
  const auto agree = coefficient_trend("c4", "N*m", "run", {1, 2}, {1.000e-4, 1.001e-4}, {1e-6, 1e-6});
  EXPECT_NEAR(agree.mean_stderr, 1e-6 / std::sqrt(2.0), 1e-9);
}

TEST(SessionSummary, DryFrictionRisingOverWeeksIsDrifting) {
  SessionReportOptions opt;
  opt.explain_runs = false;
  SessionReport report;
  const double week = 7 * 86400.0, start = 1.79e9;
  // Given out of time order: the summary sorts by the files' times.
  const double scales[] = {1.6, 1.0, 1.2, 1.4};
  const double when[] = {3, 0, 1, 2};
  for (int i = 0; i < 4; ++i)
    add_run(report, synthetic(scales[i], 10 + i, "w.tsv"), "week" + std::to_string(int(when[i])) + ".tsv", "bench-7",
            opt, start + when[i] * week);
  add_run(report, synthetic(1.0, 20, "s.tsv"), "steady1.tsv", "bench-8", opt, start);
  add_run(report, synthetic(1.0, 21, "s.tsv"), "steady2.tsv", "bench-8", opt, start + week);
  add_run(report, synthetic(1.0, 22, "s.tsv"), "steady3.tsv", "bench-8", opt, start + 2 * week);
  summarize_session(report);
  ASSERT_EQ(report.benches.size(), 2u);
  const BenchSummary& b7 = report.benches[0];
  EXPECT_EQ(b7.bench, "bench-7");
  EXPECT_EQ(b7.coulomb.x_unit, "day");
  ASSERT_EQ(b7.coulomb.value.size(), 4u);
  // Points in time order, whatever order the files came in.
  EXPECT_TRUE(std::is_sorted(b7.coulomb.x.begin(), b7.coulomb.x.end()));
  EXPECT_TRUE(b7.coulomb.drifting) << b7.coulomb.words;
  EXPECT_NEAR(b7.coulomb.relative_change, 0.6 / 1.3, 0.1);
  EXPECT_FALSE(report.benches[1].coulomb.drifting) << report.benches[1].coulomb.words;
  const std::string page = render_html_report(report);
  EXPECT_NE(page.find("dry friction rose"), std::string::npos);
  EXPECT_NE(page.find("class=\"drift\""), std::string::npos);
  EXPECT_EQ(count(page, "<svg class=\"trend-plot\""), 2u);
}

TEST(PuttyLogTime, ReadsTheHeader) {
  const auto t = putty_log_time("=~=~=~=~=~=~=~=~=~=~=~= PuTTY log 2023.09.14 10:21:33 =~=~=~=~=~=~=~=~=~=~=~=\r\n3\t0.00");
  ASSERT_TRUE(t.has_value());
  EXPECT_DOUBLE_EQ(*t, 1694686893.0);  // 2023-09-14 10:21:33 taken as UTC
  EXPECT_FALSE(putty_log_time("3\t0.00\r\n5234\t0.00").has_value());
  EXPECT_FALSE(putty_log_time("=~= PuTTY log 2023.13.14 10:21:33 =~=").has_value());
}

// A PuTTY header's time is the recording PC's local time: never labelled UTC; an LCM log's is.
TEST(RecordedAt, LocalTimeIsNotCalledUtc) {
  const RecordedAt local{1726322602.0, true}, utc{1726322602.0, false};  // 2024-09-14 14:03:22
  EXPECT_EQ(recorded_at_text(local), "2024-09-14 14:03:22 local time");
  EXPECT_EQ(recorded_at_text(utc), "2024-09-14 14:03:22 UTC");
  EXPECT_EQ(recorded_date_text(local), "2024-09-14");
  SessionReportOptions opt;
  opt.explain_runs = false;
  SessionReport report;
  add_run(report, synthetic(1.0, 3, "p.tsv"), "putty.log", "bench-1", opt, 1726322602.0);
  report.files[0].start_local = report.runs[0].cut_local = true;
  summarize_session(report);
  const std::string page = render_html_report(report);
  EXPECT_EQ(page.find(" UTC"), std::string::npos) << "a local time labelled UTC";
  EXPECT_NE(page.find("2024-09-14 14:03:22 local time"), std::string::npos);
}

// The run's figure shows the recording around the run, the fitted window shaded: what came
// before the cut (here a stretch of coast the run's window left out) is in the figure.
TEST(RunFigure, TheWholeRecordingWithTheFittedWindowShaded) {
  const Recording rec = synthetic(1.0, 5, "r.tsv");
  const Segmentation seg = find_runs(rec);
  ASSERT_EQ(seg.runs.size(), 1u);
  SessionReportOptions opt;
  opt.explain_runs = false;
  ReportRun r = make_report_run(rec, seg.runs[0], "b", BenchParams{}, opt);
  set_run_context(r, rec, seg.runs);
  ASSERT_FALSE(r.context_tau.empty());
  EXPECT_DOUBLE_EQ(r.context_tau.front(), rec.t_s.front() - seg.runs[0].t_cut_s);  // from the recording's start
  EXPECT_DOUBLE_EQ(r.context_tau.back(), rec.t_s.back() - seg.runs[0].t_cut_s);    // to its end
  EXPECT_LT(r.context_tau.front(), -1.0);  // the lead-in before the cut
  const std::string svg = run_figure_svg(r);
  EXPECT_NE(svg.find("class=\"fitted-window\""), std::string::npos);
  EXPECT_NE(svg.find("fitted window:"), std::string::npos);
  EXPECT_NE(svg.find("recording outside the fitted window"), std::string::npos);
  EXPECT_NE(svg.find("class=\"cut\""), std::string::npos);
  // Thinned to at most max_points, the lowest and highest of each stretch kept.
  set_run_context(r, rec, seg.runs, 100);
  EXPECT_LE(r.context_tau.size(), 100u);
  EXPECT_DOUBLE_EQ(*std::max_element(r.context_y.begin(), r.context_y.end()),
                   *std::max_element(rec.value.begin(), rec.value.end()));
  // Another run after this one bounds the figure at its cut.
  spindown::Run later = seg.runs[0];
  later.cut_index = rec.size() - 10;
  const std::vector<spindown::Run> two{seg.runs[0], later};
  set_run_context(r, rec, two);
  EXPECT_DOUBLE_EQ(r.context_tau.back(), rec.t_s[rec.size() - 11] - seg.runs[0].t_cut_s);
}

// Issue 33: the figure's fitted samples are the fit's window (run_window.hpp): a dropout the run
// leaves out is not drawn as fitted (nor its residual), and the count is the fit's.
TEST(RunFigure, TheFittedSamplesAreTheFitsWindow) {
  Recording rec = synthetic(1.0, 5, "r.tsv");
  Segmentation seg = find_runs(rec);
  ASSERT_EQ(seg.runs.size(), 1u);
  // Three single-sample dropouts to 0 V in the coast, then found again as the run's outliers.
  const std::size_t cut = seg.runs[0].cut_index;
  for (std::size_t k : {cut + 40, cut + 90, cut + 140}) rec.value[k] = 0.0;
  seg = find_runs(rec);
  ASSERT_EQ(seg.runs.size(), 1u);
  ASSERT_GE(seg.runs[0].outliers.size(), 3u);
  SessionReportOptions opt;
  opt.explain_runs = false;
  const ReportRun r = make_report_run(rec, seg.runs[0], "b", BenchParams{}, opt);
  const ModelFit* combined = r.fit.model(ModelKind::combined);
  ASSERT_NE(combined, nullptr);
  EXPECT_EQ(r.tau.size(), combined->n);
  const double coasting_s = seg.runs[0].t_stop_s - seg.runs[0].t_cut_s - 0.5;  // before the standstill
  for (std::size_t i = 0; i < r.tau.size() && r.tau[i] < coasting_s; ++i)
    EXPECT_GT(r.y[i], 0.0) << "a dropout drawn as a fitted sample at " << r.tau[i] << " s";
}

// A semester prints on a few pages: a print stylesheet leaves the per-run figures to the screen
// and keeps a one-line-per-run table.
TEST(HtmlReport, PrintsCompactly) {
  SessionReportOptions opt;
  opt.explain_runs = false;
  SessionReport report;
  add_run(report, synthetic(1.0, 7, "a.tsv"), "a.tsv", "bench-1", opt);
  add_run(report, synthetic(1.0, 8, "b.tsv"), "b.tsv", "bench-1", opt);
  summarize_session(report);
  const std::string page = render_html_report(report);
  const auto print = page.find("@media print{");
  ASSERT_NE(print, std::string::npos);
  const std::string css = page.substr(print, page.find("</style>") - print);
  EXPECT_NE(css.find("section.bench"), std::string::npos) << css;
  EXPECT_NE(css.find("svg.run-plot{display:none}"), std::string::npos) << css;
  EXPECT_NE(page.find("<table class=\"runs\">"), std::string::npos);
  EXPECT_EQ(count(page, "<tr><td>bench-1</td>"), 2u);  // one line per run
}

// Runs far apart beyond their errors that line up in time are wear, not runs of another motor.
TEST(CoefficientTrend, RunsThatLineUpInTimeAreWear) {
  std::vector<double> x, v, se;
  for (int week = 0; week < 6; ++week)
    x.push_back(7.0 * week), v.push_back(1.14e-4 * (1 + 0.05 * week)), se.push_back(3e-7);
  const auto t = coefficient_trend("c4", "N*m", "day", x, v, se);
  EXPECT_GT(t.scatter, 5) << "far apart about their mean";
  EXPECT_TRUE(t.drifting) << t.words;
  EXPECT_NE(t.words.find("friction rising steadily over 6 sessions: wear"), std::string::npos) << t.words;
  EXPECT_EQ(t.words.find("check which runs belong"), std::string::npos) << t.words;
}

TEST(SvgPlot, EscapesAndTicks) {
  EXPECT_EQ(svg::escape("a<b & \"c\">"), "a&lt;b &amp; &quot;c&quot;&gt;");
  EXPECT_EQ(html_escape("it's <x>"), "it&#39;s &lt;x&gt;");
  // Bytes that are not UTF-8 (a Latin-1 file name) and control characters become U+FFFD.
  EXPECT_EQ(html_escape("caf\xe9.tsv"), "caf\xEF\xBF\xBD.tsv");
  EXPECT_EQ(html_escape("a\x1b[2Jb"), "a\xEF\xBF\xBD[2Jb");
  EXPECT_EQ(html_escape("g·cm² ✓ 😀"), "g·cm² ✓ 😀");
  const auto t = svg::nice_ticks(0, 10);
  ASSERT_FALSE(t.empty());
  EXPECT_DOUBLE_EQ(t.front(), 0);
  EXPECT_DOUBLE_EQ(t.back(), 10);
}

}  // namespace
}  // namespace spindown
