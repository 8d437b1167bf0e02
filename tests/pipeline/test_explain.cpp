// The discrepancy workflow on generated runs in which an effect is hidden from the base model
// (across benches, loop periods 10–50 ms, noise, ripple, lead-ins and strengths), on runs that
// need nothing, on the sample data (data/), and its JSON/text/SVG reports.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>

#include "../../bench/explain_study.hpp"
#include "spindown/effect_fit.hpp"
#include "spindown/explain.hpp"
#include "spindown/explain_report.hpp"
#include "spindown/read_recording.hpp"
#include "spindown/runs.hpp"

using namespace spindown;

namespace {

struct Outcome {
  std::string named;
  double rmse_final = 0, rmse_truth = 0;
  ExplainResult result;
};

Outcome explain_generated(const study::GeneratedRun& g) {
  Outcome o;
  const Segmentation seg = find_runs(g.recording);
  EXPECT_FALSE(seg.runs.empty()) << g.recording.source;
  if (seg.runs.empty()) return o;
  ExplainOptions opt;
  opt.bench = g.spec.bench;
  std::string why;
  opt.base = parse_effect_list(g.base, &why);
  o.result = explain_run(g.recording, seg.runs.front(), opt);
  for (const auto& s : o.result.steps) o.named += (o.named.empty() ? "" : "+") + s.added;
  if (o.named.empty()) o.named = "none";
  std::string truth;
  for (const auto& t : g.truth) truth += (truth.empty() ? "" : ",") + t;
  EffectFitData d;
  d.tau = o.result.tau;
  d.y = o.result.y;
  const Run& run = seg.runs.front();
  d.moving = std::min((run.stopped ? run.stop_index : run.end_index) - run.cut_index, o.result.tau.size());
  d.k = opt.bench.kb_v_s_per_rad;
  d.inertia_kg_m2 = opt.bench.inertia_kg_m2;
  o.rmse_final = o.result.rmse_final();
  o.rmse_truth = fit_effects(parse_effect_list(truth, &why), d).rmse;
  return o;
}

}  // namespace

// Six runs per family (30 in all): the workflow names the hidden effect, and its final RMSE
// is within a few percent of a fit of the true structure.
TEST(Explain, NamesTheHiddenEffect) {
  for (const auto& family : study::families()) {
    for (std::uint64_t seed = 1000; seed < 1006; ++seed) {
      const study::GeneratedRun g = study::generate(family, seed);
      const Outcome o = explain_generated(g);
      EXPECT_EQ(o.named, family) << g.recording.source << ": " << o.result.conclusion;
      EXPECT_LT(o.rmse_final, 1.03 * o.rmse_truth) << g.recording.source;
    }
  }
}

TEST(Explain, AddsNothingToARunThatNeedsNothing) {
  for (std::uint64_t seed = 2000; seed < 2008; ++seed) {
    const study::GeneratedRun g = study::generate("none", seed);
    const Outcome o = explain_generated(g);
    EXPECT_TRUE(o.result.ok) << o.result.message;
    EXPECT_TRUE(o.result.steps.empty()) << g.recording.source << " added " << o.named;
    EXPECT_EQ(o.result.final_fit.label(), o.result.base.label());
    EXPECT_FALSE(o.result.conclusion.empty());  // it says why it stopped
    for (const auto& t : o.result.final_trials) EXPECT_FALSE(t.verdict.empty());  // and why each was rejected
  }
}

// The lab's story: believed viscous, the data need Coulomb friction too.
TEST(Explain, TellsTheLabStoryOnTheSeedData) {
  const auto recs = read_recordings(std::string(SPINDOWN_SAMPLE_DATA) + "/seed-3v-run1.tsv");
  ASSERT_EQ(recs.size(), 1u);
  const Segmentation seg = find_runs(recs[0]);
  ASSERT_EQ(seg.runs.size(), 1u);
  const ExplainResult r = explain_run(recs[0], seg.runs[0], ExplainOptions{});
  ASSERT_TRUE(r.ok) << r.message;
  ASSERT_EQ(r.steps.size(), 1u);
  EXPECT_EQ(r.steps[0].added, "coulomb");
  EXPECT_FALSE(r.steps[0].where.empty());
  EXPECT_GT(r.rmse_base() / r.rmse_final(), 5.0);
  EXPECT_NEAR(r.final_fit.param("c_c")->value, 1.1389e-4, 3e-6);
  EXPECT_NEAR(r.final_fit.param("c_v")->value, 1.822e-7, 3e-8);

  const std::string text = format_explain(r);
  for (const char* words : {"base model: viscous", "missing effect: coulomb", "rejected", "c_c = ", "gap: RMSE",
                            "smaller", "after the cut"})
    EXPECT_NE(text.find(words), std::string::npos) << words << "\n" << text;

  const ExplainJson j = explain_run_json(r);
  EXPECT_EQ(j["run"], 1);
  EXPECT_EQ(j["base"], ExplainJson::array({"viscous"}));
  EXPECT_EQ(j["final"], ExplainJson::array({"viscous", "coulomb"}));
  ASSERT_EQ(j["steps"].size(), 1u);
  const auto& s = j["steps"][0];
  EXPECT_EQ(s["added"], "coulomb");
  for (const char* key : {"rmse_before", "rmse_after", "where", "why"}) EXPECT_TRUE(s.contains(key)) << key;
  for (const char* key : {"t_from_s", "t_to_s", "mean_residual"}) EXPECT_TRUE(s["where"][0].contains(key)) << key;
  EXPECT_GT(s["where"][0]["t_from_s"].get<double>(), r.run.t_cut_s - 1e-9);  // the file's clock
  EXPECT_TRUE(j["rmse_base"].is_number());
  EXPECT_TRUE(j["rmse_final"].is_number());

  FileExplain file;
  file.file = "seed-3v-run1.tsv";
  file.runs.push_back(r);
  const std::string svg = explain_svg(std::span<const FileExplain>(&file, 1));
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  for (const char* part : {"</svg>", "<polyline", "time after the cut (s)", "reading (V)", "base model: viscous",
                           "final model: viscous+coulomb", "before:", "after:"})
    EXPECT_NE(svg.find(part), std::string::npos) << part;
}

// A file of several benches (an LCM log): every run names its bench in text, JSON and the SVG.
TEST(Explain, RunsOfSeveralBenchesSayWhoseTheyAre) {
  const auto recs = read_recordings(std::string(SPINDOWN_SAMPLE_DATA) + "/seed-3v-run1.tsv");
  ASSERT_EQ(recs.size(), 1u);
  const Segmentation seg = find_runs(recs[0]);
  ASSERT_EQ(seg.runs.size(), 1u);
  FileExplain file;
  file.file = "lab.lcm";
  file.runs = {explain_run(recs[0], seg.runs[0], ExplainOptions{}), explain_run(recs[0], seg.runs[0], ExplainOptions{})};
  file.run_bench = {"bench-a", "bench-b"};
  const std::string text = format_file_explain(file);
  EXPECT_NE(text.find("run 1 of bench bench-a: cut at"), std::string::npos) << text;
  EXPECT_NE(text.find("run 1 of bench bench-b: cut at"), std::string::npos) << text;
  const ExplainJson j = explain_report_json(std::span<const FileExplain>(&file, 1));
  EXPECT_EQ(j["files"][0]["runs"][0]["bench"], "bench-a");
  EXPECT_EQ(j["files"][0]["runs"][1]["bench"], "bench-b");
  const std::string svg = explain_svg(std::span<const FileExplain>(&file, 1));
  EXPECT_NE(svg.find("lab.lcm bench bench-b - run 1"), std::string::npos);
  // One bench, one file: no bench named.
  file.run_bench.clear();
  EXPECT_EQ(format_file_explain(file).find(" of bench "), std::string::npos);
  EXPECT_FALSE(explain_report_json(std::span<const FileExplain>(&file, 1))["files"][0]["runs"][0].contains("bench"));
}

TEST(Explain, RejectsBadOptionsWithAReason) {
  ExplainOptions opt;
  opt.base = {find_effect("sensor_offset")};
  std::string why;
  EXPECT_FALSE(opt.is_valid(&why));
  EXPECT_NE(why.find("friction"), std::string::npos) << why;
  spindown::Run run;
  run.cut_index = 0;
  run.end_index = 3;
  const std::vector<double> t{0, 1, 2}, v{1, 0.5, 0};
  const ExplainResult r = explain_run(t, v, Quantity::back_emf_volts, run, ExplainOptions{});
  EXPECT_FALSE(r.ok);
  EXPECT_FALSE(r.message.empty());
}
