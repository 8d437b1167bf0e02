// The discrepancy workflow on generated runs in which an effect is hidden from the base model
// (across benches, loop periods 10–50 ms, noise, ripple, lead-ins and strengths), on runs that
// need nothing, on the sample data (data/), and its JSON/text/SVG reports.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

#include "../../bench/explain_study.hpp"
#include "spindown/effect_fit.hpp"
#include "spindown/explain.hpp"
#include "spindown/explain_report.hpp"
#include "spindown/fit.hpp"
#include "spindown/lab_units.hpp"
#include "spindown/read_recording.hpp"
#include "spindown/runs.hpp"
#include "spindown/svg_plot.hpp"
#include "spindown/synthetic_run.hpp"

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
  d.weight = o.result.weight;
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
  // fit's names: viscous alone is c1; beside Coulomb friction c3 and c4, as in fit's combined model.
  EXPECT_NE(r.base.param("c1"), nullptr);
  EXPECT_NEAR(r.final_fit.param("c4")->value, 1.1389e-4, 3e-6);
  EXPECT_NEAR(r.final_fit.param("c3")->value, 1.822e-7, 3e-8);

  const std::string text = format_explain(r);
  for (const char* words : {"base model: viscous", "missing effect: coulomb", "rejected", "c4 = ", "gap: RMSE",
                            "smaller", "after the cut", "N·m·s/rad", "ω0 = ", "T = c4"})
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
  for (const char* part : {"</svg>", "<polyline", "time after the cut (s)", "reading (V)", "base: viscous",
                           "step 1: + coulomb -&gt; combined (viscous+coulomb)"})
    EXPECT_NE(svg.find(part), std::string::npos) << part;
}

namespace {

ExplainResult explain_file_run(const std::string& name, ExplainOptions opt = {}) {
  const auto recs = read_recordings(std::string(SPINDOWN_SAMPLE_DATA) + "/" + name);
  EXPECT_EQ(recs.size(), 1u);
  const Segmentation seg = find_runs(recs.at(0));
  EXPECT_EQ(seg.runs.size(), 1u);
  return explain_run(recs.at(0), seg.runs.at(0), opt);
}

RunFit fit_file_run(const std::string& name) {
  const auto recs = read_recordings(std::string(SPINDOWN_SAMPLE_DATA) + "/" + name);
  const Segmentation seg = find_runs(recs.at(0));
  return fit_run(recs.at(0), seg.runs.at(0), FitOptions{});
}

// A Recording from a synthetic run, cut off `keep` of the way from the cut to the stop (no standstill
// in it), its readings in `q` (volts converted with K_b).
Recording cut_before_stop(const SyntheticRunSpec& spec, double keep, Quantity q) {
  const SyntheticRun run = make_synthetic_run(spec);
  const double t_stop_ms = run.t_cut_ms + 1000 * keep * run.t_stop_s;
  Recording rec;
  rec.quantity = q;
  const double kb = spec.bench.kb_v_s_per_rad;
  const double per_volt = value_per_rad_per_s(q, kb) / kb;  // reading per volt of back-EMF
  for (std::size_t i = 0; i < run.t_ms.size() && run.t_ms[i] <= t_stop_ms; ++i)
    rec.push(run.t_ms[i] / 1000.0, q == Quantity::back_emf_volts ? run.volts[i] : run.volts[i] * per_volt);
  return rec;
}

}  // namespace

// Issue 22: the base model is fit's model of the same name on the same samples, with fit's names:
// one "viscous" on a page, not two (fit's c1 = 7.37e-7, ω0 = 403.7 against explain's 7.20e-7, 397.9
// when explain fitted raw readings unweighted).
TEST(Explain, TheBaseModelIsFitsModelOfTheSameName) {
  const RunFit fit = fit_file_run("stribeck-example.tsv");
  const ExplainResult r = explain_file_run("stribeck-example.tsv");
  ASSERT_TRUE(r.ok) << r.message;
  const ModelFit* viscous = fit.model(ModelKind::viscous);
  ASSERT_NE(viscous, nullptr);
  EXPECT_EQ(r.base.fit_model(), "viscous");
  for (const char* name : {"c1", "omega0"}) {
    ASSERT_NE(r.base.param(name), nullptr) << name;
    EXPECT_NEAR(r.base.param(name)->value, viscous->param(name)->value, 1e-4 * std::abs(viscous->param(name)->value))
        << name;
    EXPECT_NEAR(r.base.param(name)->std_error, viscous->param(name)->std_error,
                0.05 * viscous->param(name)->std_error)
        << name;
    EXPECT_EQ(r.base.param(name)->unit, viscous->param(name)->unit) << name;
  }
  EXPECT_NEAR(r.base.rmse, viscous->rmse, 1e-5 * viscous->rmse);
  EXPECT_EQ(r.base.n, viscous->n);
  // Coulomb added to it is fit's combined model: c3, c4 and ω0 as fit gives them.
  ASSERT_FALSE(r.steps.empty());
  EXPECT_EQ(r.steps[0].added, "coulomb");
  EXPECT_EQ(r.steps[0].fit.fit_model(), "combined");
  const ModelFit* combined = fit.model(ModelKind::combined);
  for (const char* name : {"c3", "c4", "omega0"})
    EXPECT_NEAR(r.steps[0].fit.param(name)->value, combined->param(name)->value,
                1e-3 * std::abs(combined->param(name)->value))
        << name;
  // ... and the run's answer stays the truth's (stribeck-example.tsv.truth.json: c_v 1.5e-7, c_c 1e-4,
  // c_s 2e-4, w_s 35).
  EXPECT_EQ(r.final_fit.label(), "viscous+coulomb+stribeck");
  EXPECT_NEAR(r.final_fit.param("c3")->value, 1.5e-7, 3e-9);
  EXPECT_NEAR(r.final_fit.param("c4")->value, 1e-4, 1e-6);
  EXPECT_NEAR(r.final_fit.param("c_s")->value, 2e-4, 4e-6);
  EXPECT_NEAR(r.final_fit.param("w_s")->value, 35, 1);
  EXPECT_EQ(r.final_fit.param("c_v"), nullptr);  // one vocabulary: no second name for c3
}

// One noise figure: the reading noise σ, the same number in fit and explain, the bin's derived from it.
TEST(Explain, OneNoiseFigureNamedTheSameEverywhere) {
  const RunFit fit = fit_file_run("stribeck-example.tsv");
  const ExplainResult r = explain_file_run("stribeck-example.tsv");
  ASSERT_TRUE(r.ok);
  EXPECT_GT(r.reading_noise, 0);
  EXPECT_DOUBLE_EQ(r.reading_noise, fit.reading_noise);
  // The truth: noise_v 0.003 V (no ripple) and the 0.01 V print's rounding, 0.01/√12.
  EXPECT_NEAR(r.reading_noise, std::hypot(0.003, 0.01 / std::sqrt(12.0)), 0.0005);
  EXPECT_DOUBLE_EQ(r.bin_noise_white(), r.reading_noise / std::sqrt(double(r.bin_samples)));
  EXPECT_GE(r.bin_noise, r.bin_noise_white());
  const std::string text = format_explain(r);
  EXPECT_NE(text.find(fmt::format("reading noise σ {:.2g} V", fit.reading_noise)), std::string::npos) << text;
  EXPECT_NE(text.find(fmt::format("σ/√{} = {:.2g} V", r.bin_samples, r.bin_noise_white())), std::string::npos) << text;
  EXPECT_EQ(text.find("per reading"), std::string::npos) << text;
  const ExplainJson j = explain_run_json(r);
  EXPECT_DOUBLE_EQ(j["reading_noise"].get<double>(), fit.reading_noise);
  EXPECT_FALSE(j.contains("noise_level"));
  EXPECT_EQ(j["bin_samples"].get<std::size_t>(), r.bin_samples);
}

// --lab-units as fit gives them: the same conversion (lab_units.hpp), in text and JSON.
TEST(Explain, LabUnitsAsFitGivesThem) {
  const ExplainResult r = explain_file_run("seed-3v-run1.tsv");
  ASSERT_TRUE(r.ok);
  const Parameter& c4 = *r.final_fit.param("c4");
  ReportOptions lab;
  lab.lab_units = true;
  const std::string text = format_explain(r, {}, lab);
  const auto unit = lab_unit_for(c4.unit);
  ASSERT_TRUE(unit.has_value());
  EXPECT_NE(text.find(lab_unit_text(c4)), std::string::npos) << text;
  EXPECT_NE(text.find("g·cm²·rad·s⁻²"), std::string::npos);
  EXPECT_EQ(format_explain(r).find("g·cm²"), std::string::npos);  // only when asked
  const ExplainJson j = explain_run_json(r, {}, lab);
  EXPECT_DOUBLE_EQ(j["final_params"]["c4"]["lab"]["value"].get<double>(), c4.value * unit->per_si);
  EXPECT_EQ(j["final_params"]["c4"]["lab"]["unit"], "g*cm^2*rad/s^2");
  EXPECT_EQ(j["final_params"]["c4"]["unit"], "N*m");
}

// Issue 22, 1: a viscous coast with a little Coulomb friction, recorded in rpm and cut off before its
// stop: viscous+Coulomb and viscous+offset are the same curve (an exponential plus a constant), and
// the offset came out −238 rpm on a sensor that never reads below 0. Coulomb is the physical one.
TEST(Explain, CoulombIsNotMistakenForAnOffsetBelowZero) {
  SyntheticRunSpec spec;
  spec.friction = {1.2e-6, 3e-5};
  spec.seed = 7;
  const Recording rec = cut_before_stop(spec, 0.6, Quantity::rpm);
  const Segmentation seg = find_runs(rec);
  ASSERT_EQ(seg.runs.size(), 1u);
  ASSERT_FALSE(seg.runs[0].stopped);
  const ExplainResult r = explain_run(rec, seg.runs[0], ExplainOptions{});
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_FALSE(r.standstill_seen);
  ASSERT_EQ(r.steps.size(), 1u) << format_explain(r);
  EXPECT_EQ(r.steps[0].added, "coulomb") << format_explain(r);
  EXPECT_NEAR(r.final_fit.param("c3")->value, 1.2e-6, 0.02e-6);
  EXPECT_NEAR(r.final_fit.param("c4")->value, 3e-5, 0.1e-5);
  bool offset_tried = false;
  for (const auto& t : r.steps[0].trials)
    if (t.effect == "sensor_offset") {
      offset_tried = true;
      EXPECT_FALSE(t.impossible.empty());  // it fits as well, but would read below zero at rest
      EXPECT_NE(t.verdict.find("below zero"), std::string::npos) << t.verdict;
    }
  EXPECT_TRUE(offset_tried);
}

// ... and where the recording never shows the sensor at rest (it starts mid-coast and ends before the
// stop), the two cannot be told apart: it is said, in text and JSON, and the choice is the same
// every time.
TEST(Explain, SaysWhenCoulombAndAnOffsetCannotBeToldApart) {
  SyntheticRunSpec spec;
  spec.friction = {1.2e-6, 3e-5};
  spec.start_s = 1.5;  // no lead-in: the recording starts mid-coast
  spec.seed = 7;
  const Recording rec = cut_before_stop(spec, 0.6, Quantity::back_emf_volts);
  ASSERT_GT(*std::min_element(rec.value.begin(), rec.value.end()), 0.3);  // V: never near 0
  const Segmentation seg = find_runs(rec);
  ASSERT_EQ(seg.runs.size(), 1u);
  const ExplainResult r = explain_run(rec, seg.runs[0], ExplainOptions{});
  ASSERT_TRUE(r.ok) << r.message;
  ASSERT_EQ(r.steps.size(), 1u) << format_explain(r);
  EXPECT_EQ(r.steps[0].added, "coulomb");
  EXPECT_EQ(r.steps[0].indistinguishable, std::vector<std::string>{"sensor_offset"});
  EXPECT_NE(r.steps[0].undecided.find("cannot tell them apart"), std::string::npos) << r.steps[0].undecided;
  EXPECT_NE(r.steps[0].undecided.find("no"), std::string::npos);
  const std::string text = format_explain(r);
  EXPECT_NE(text.find("undecided: coulomb or sensor_offset"), std::string::npos) << text;
  EXPECT_NE(r.conclusion.find("undecided"), std::string::npos) << r.conclusion;
  const ExplainJson j = explain_run_json(r);
  EXPECT_EQ(j["steps"][0]["indistinguishable_from"], ExplainJson::array({"sensor_offset"}));
  EXPECT_TRUE(j["steps"][0].contains("undecided"));
}

// With a standstill in the window the zero level is measured: an offset lies between 0 and it, give
// or take its uncertainty, never the hundreds of rpm a Coulomb term could stand in for.
TEST(Explain, AnOffsetIsBoundedByTheZeroLevelSeenAtStandstill) {
  const ExplainResult r = explain_file_run("seed-3v-run1.tsv");
  ASSERT_TRUE(r.ok);
  EXPECT_TRUE(r.standstill_seen);
  EXPECT_EQ(r.zero_level, 0.0);
  EXPECT_GE(r.offset_lo, -0.01);  // V: the zero level's own uncertainty, at most the print's step
  EXPECT_LE(r.offset_hi, 0.01);
  std::size_t offsets = 0;
  for (const auto& s : r.steps)
    for (const auto& t : s.trials)
      if (const Parameter* off = t.fit.param("sensor_offset")) {
        ++offsets;
        EXPECT_GE(off->value, r.offset_lo - 1e-12) << t.effect;
        EXPECT_LE(off->value, r.offset_hi + 1e-12) << t.effect;
      }
  EXPECT_GT(offsets, 0u);
  // A sensor offset the zero level shows (offset-example.tsv: 0.06 V after the cut) is named, within
  // the bounds the standstill sets, and the model is then fit's combined one (which subtracts the
  // zero level) with the truth's friction (offset-example.tsv.truth.json).
  ExplainOptions combined;
  combined.base = parse_effect_list("combined", nullptr);
  const ExplainResult o = explain_file_run("offset-example.tsv", combined);
  ASSERT_TRUE(o.ok);
  EXPECT_NEAR(o.zero_level, 0.06, 0.005);
  ASSERT_EQ(o.steps.size(), 1u) << format_explain(o);
  EXPECT_EQ(o.steps[0].added, "sensor_offset");
  const Parameter& off = *o.final_fit.param("sensor_offset");
  EXPECT_GE(off.value, o.offset_lo);
  EXPECT_LE(off.value, o.offset_hi);
  EXPECT_NEAR(off.value, 0.06, 0.003);
  const RunFit fit = fit_file_run("offset-example.tsv");
  for (const char* name : {"c3", "c4"})
    EXPECT_NEAR(o.final_fit.param(name)->value, fit.model(ModelKind::combined)->param(name)->value,
                0.01 * fit.model(ModelKind::combined)->param(name)->value)
        << name;
  EXPECT_NEAR(o.final_fit.param("c3")->value, 1.8e-7, 0.03e-7);
  EXPECT_NEAR(o.final_fit.param("c4")->value, 1.14e-4, 0.02e-4);
  const std::string text = format_explain(o);
  EXPECT_NE(text.find("zero level 0.06 V at standstill: spindown fit subtracts it"), std::string::npos) << text;
  EXPECT_NE(text.find("but for its zero level"), std::string::npos) << text;
}

// Issue 22, 2: Stribeck friction whose fitted ω_s is a third of the top speed or more is worded from
// its numbers (friction falling with speed over the coast), not as friction rising toward standstill.
TEST(Explain, BroadStribeckIsWordedFromItsNumbers) {
  SyntheticRunSpec spec;
  spec.friction = {1.5e-7, 1e-4, 2.2e-4, 130};
  spec.seed = 3;
  const SyntheticRun run = make_synthetic_run(spec);
  Recording rec;
  for (std::size_t i = 0; i < run.t_ms.size(); ++i) rec.push(run.t_ms[i] / 1000.0, run.volts[i]);
  const Segmentation seg = find_runs(rec);
  ASSERT_EQ(seg.runs.size(), 1u);
  const ExplainResult r = explain_run(rec, seg.runs[0], ExplainOptions{});
  ASSERT_TRUE(r.ok);
  const ExplainStep* stribeck = nullptr;
  for (const auto& s : r.steps)
    if (s.added == "stribeck") stribeck = &s;
  ASSERT_NE(stribeck, nullptr) << format_explain(r);
  ASSERT_GE(stribeck->fit.param("w_s")->value, stribeck->fit.omega0 / 3);
  EXPECT_NE(stribeck->meaning.find("falls with speed over much of the coast"), std::string::npos) << stribeck->meaning;
  EXPECT_EQ(stribeck->meaning.find("rising toward standstill"), std::string::npos) << stribeck->meaning;
  const std::string text = format_explain(r);
  EXPECT_NE(text.find("falls with speed over much of the coast"), std::string::npos) << text;
  EXPECT_EQ(text.find("rising toward standstill"), std::string::npos) << text;
  EXPECT_EQ(explain_run_json(r)["steps"][static_cast<std::size_t>(stribeck - r.steps.data())]["meaning"],
            stribeck->meaning);
  // The truth's (c_s 2.2e-4, w_s 130) within a few percent.
  EXPECT_NEAR(r.final_fit.param("c_s")->value, 2.2e-4, 0.1e-4);
  EXPECT_NEAR(r.final_fit.param("w_s")->value, 130, 8);

  // A narrow one (stribeck-example.tsv: w_s 35 rad/s of 358) keeps the standstill wording.
  const ExplainResult narrow = explain_file_run("stribeck-example.tsv");
  ASSERT_EQ(narrow.steps.size(), 2u);
  EXPECT_NE(narrow.steps[1].meaning.find("rising toward standstill"), std::string::npos) << narrow.steps[1].meaning;
}

// Issue 22, 3: the figure shows the gap shrink step by step: the base model and the model after each
// step, each a curve labelled with its RMSE.
TEST(Explain, TheFigureShowsEveryStepWithItsRmse) {
  FileExplain file;
  file.file = "stribeck-example.tsv";
  file.runs.push_back(explain_file_run("stribeck-example.tsv"));
  const ExplainResult& r = file.runs[0];
  ASSERT_EQ(r.steps.size(), 2u);
  const std::string svg = explain_svg(std::span<const FileExplain>(&file, 1));
  std::vector<const EffectFit*> stages{&r.base};
  for (const auto& s : r.steps) stages.push_back(&s.fit);
  for (std::size_t c = 0; c < stages.size(); ++c) {
    const std::string curve = fmt::format("<polyline fill=\"none\" class=\"model\" data-step=\"{}\" data-rmse=\"{:.4g}\"",
                                          c, stages[c]->rmse);
    EXPECT_NE(svg.find(curve), std::string::npos) << curve;
    const std::string label = c == 0 ? fmt::format("base: viscous - RMSE {:.3g} V", r.base.rmse)
                                     : fmt::format("step {}: + {} -&gt; {} - RMSE {:.3g} V", c, r.steps[c - 1].added,
                                                   r.steps[c - 1].fit.title(), r.steps[c - 1].rmse_after);
    EXPECT_NE(svg.find(">" + label), std::string::npos) << label;
    EXPECT_NE(svg.find(fmt::format("class=\"residual\" data-step=\"{}\"", c)), std::string::npos) << c;
  }
  // The RMSEs fall step by step.
  EXPECT_GT(r.base.rmse, r.steps[0].rmse_after);
  EXPECT_GT(r.steps[0].rmse_after, r.steps[1].rmse_after);
}

// The legend keeps every step: an effect a later step removed is marked so, and the later step
// says what it removed.
TEST(Explain, TheLegendMarksAnEffectALaterStepRemoved) {
  FileExplain file;
  file.file = "stribeck-example.tsv";
  file.runs.push_back(explain_file_run("stribeck-example.tsv"));
  ExplainResult& r = file.runs[0];
  ASSERT_EQ(r.steps.size(), 2u);
  r.steps[1].removed = {r.steps[0].added};  // as when windage made an earlier Stribeck unneeded
  const std::string svg = explain_svg(std::span<const FileExplain>(&file, 1));
  EXPECT_NE(svg.find(fmt::format("step 1: + {} -&gt; ", r.steps[0].added)), std::string::npos) << svg;
  EXPECT_NE(svg.find(fmt::format("[{} removed at step 2]", r.steps[0].added)), std::string::npos) << svg;
  EXPECT_NE(svg.find(fmt::format("step 2: + {}, - {} (removed: not needed)", r.steps[1].added, r.steps[0].added)),
            std::string::npos)
      << svg;
  // No legend line runs past the figure: a long label wraps inside its box (tspan lines).
  std::string long_label(300, 'x');
  for (std::size_t i = 10; i < long_label.size(); i += 11) long_label[i] = ' ';
  const std::string box = svg::legend(400, 10, {{long_label, "stroke=\"#000\""}}, 540);
  std::size_t lines = 1;
  for (auto at = box.find("<tspan"); at != std::string::npos; at = box.find("<tspan", at + 1)) ++lines;
  EXPECT_EQ(lines, 5u) << box;  // 300 characters, broken at spaces into lines of at most 73
  EXPECT_NE(box.find("height=\"98\""), std::string::npos) << box;  // the box holds all five
}

// A motor with Coulomb friction alone: explain says the viscous term is not needed, whether it
// starts from the lab's belief (viscous: Coulomb added, viscous removed) or from fit's combined
// model (nothing to add, viscous removed as a step of its own).
TEST(Explain, SaysTheViscousTermIsNotNeededOnACoulombOnlyMotor) {
  for (std::uint64_t seed : {31u, 32u, 33u}) {
    SyntheticRunSpec spec;
    spec.friction = {0.0, 1.2e-4};
    spec.seed = seed;
    const SyntheticRun run = make_synthetic_run(spec);
    Recording rec;
    for (std::size_t i = 0; i < run.t_ms.size(); ++i) rec.push(run.t_ms[i] / 1000.0, run.volts[i]);
    const Segmentation seg = find_runs(rec);
    ASSERT_EQ(seg.runs.size(), 1u);
    ExplainOptions from_viscous;
    const ExplainResult a = explain_run(rec, seg.runs[0], from_viscous);
    ASSERT_TRUE(a.ok) << a.message;
    ASSERT_FALSE(a.steps.empty());
    EXPECT_EQ(a.steps[0].added, "coulomb");
    EXPECT_EQ(a.steps[0].removed, std::vector<std::string>{"viscous"}) << a.steps[0].why;
    EXPECT_EQ(a.final_fit.fit_model(), "coulomb");
    EXPECT_NE(format_explain(a, {}, {}).find("removed viscous: not needed"), std::string::npos);

    ExplainOptions from_combined;
    std::string why;
    from_combined.base = parse_effect_list("combined", &why);
    const ExplainResult b = explain_run(rec, seg.runs[0], from_combined);
    ASSERT_TRUE(b.ok) << b.message;
    ASSERT_EQ(b.steps.size(), 1u) << b.conclusion;
    EXPECT_EQ(b.steps[0].added, "");
    EXPECT_EQ(b.steps[0].removed, std::vector<std::string>{"viscous"});
    EXPECT_EQ(b.final_fit.fit_model(), "coulomb");
    const std::string text = format_explain(b, {}, {});
    EXPECT_NE(text.find("step 1: viscous not needed"), std::string::npos) << text;
    EXPECT_NE(b.conclusion.find("viscous removed: not needed"), std::string::npos) << b.conclusion;
  }
  // The lab's motor needs its viscous term: nothing of its belief is removed.
  const auto recs = read_recordings(std::string(SPINDOWN_SAMPLE_DATA) + "/seed-3v-run1.tsv");
  ASSERT_EQ(recs.size(), 1u);
  const ExplainResult lab = explain_run(recs[0], find_runs(recs[0]).runs.at(0), ExplainOptions{});
  for (const auto& s : lab.steps) EXPECT_TRUE(s.removed.empty()) << s.why;
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

// Issue 33: fit and explain take one window (run_window.hpp). On a run with dropouts, explain's
// samples are fit's, outliers left out, and its base viscous is fit's viscous on them; from one
// window made once or from the arrays, the same.
TEST(Explain, ExplainAndFitShareOneWindowWithItsDropoutsLeftOut) {
  SyntheticRunSpec spec;
  spec.seed = 11;
  const SyntheticRun s = make_synthetic_run(spec);
  Recording rec;
  rec.quantity = Quantity::back_emf_volts;
  for (std::size_t i = 0; i < s.t_ms.size(); ++i) {
    rec.t_s.push_back(s.t_ms[i] / 1000.0);
    // every 37th reading drops to 0 V (a loose wire)
    rec.value.push_back(i % 37 == 36 && s.t_ms[i] > s.t_cut_ms + 300 ? 0.0 : s.volts[i]);
  }
  const Segmentation seg = find_runs(rec);
  ASSERT_FALSE(seg.runs.empty());
  const spindown::Run& run = seg.runs.front();
  ASSERT_GE(run.outliers.size(), 5u) << "the dropouts are the run's outliers";
  const RunWindow window(rec.t_s, rec.value, run, true);
  const RunFit fit = fit_run(window, rec.quantity, run, FitOptions{});
  const ExplainResult shared = explain_run(window, rec.quantity, run, ExplainOptions{}, lowest_reading(rec.value));
  const ExplainResult own = explain_run(rec, run, ExplainOptions{});
  ASSERT_TRUE(shared.ok) << shared.message;
  ASSERT_EQ(shared.tau.size(), window.size());
  for (std::size_t k : run.outliers) {
    if (k < run.cut_index || k >= run.end_index) continue;
    EXPECT_FALSE(std::binary_search(shared.tau.begin(), shared.tau.end(), rec.t_s[k] - run.t_cut_s)) << k;
  }
  EXPECT_EQ(shared.base.n, fit.model(ModelKind::viscous)->n);
  EXPECT_NEAR(shared.base.rmse, fit.model(ModelKind::viscous)->rmse, 1e-6 * fit.model(ModelKind::viscous)->rmse);
  EXPECT_EQ(shared.tau, own.tau);
  EXPECT_EQ(shared.y, own.y);
  EXPECT_EQ(shared.conclusion, own.conclusion);
}

// Issue 32: where the model and the data disagree is named by the data's speed there, not the
// model's (a viscous model on a Coulomb coast starts far above the measured speed).
TEST(Explain, ADisagreementIsPlacedAtTheMeasuredSpeed) {
  SyntheticRunSpec spec;
  spec.friction.viscous = 0;
  spec.friction.coulomb = 4e-4;
  spec.seed = 5;
  const SyntheticRun s = make_synthetic_run(spec);
  Recording rec;
  rec.quantity = Quantity::back_emf_volts;
  for (std::size_t i = 0; i < s.t_ms.size(); ++i) rec.t_s.push_back(s.t_ms[i] / 1000.0), rec.value.push_back(s.volts[i]);
  const Segmentation seg = find_runs(rec);
  ASSERT_FALSE(seg.runs.empty());
  const ExplainResult r = explain_run(rec, seg.runs.front(), ExplainOptions{});
  ASSERT_TRUE(r.ok) << r.message;
  ASSERT_FALSE(r.steps.empty());
  ASSERT_FALSE(r.steps.front().where.empty());
  const double k = spec.bench.kb_v_s_per_rad;
  for (const Disagreement& d : r.steps.front().where) {
    // The readings at the stretch's first time, as a speed: within a few bins' travel of the label.
    std::size_t i = 0;
    while (i + 1 < r.tau.size() && r.tau[i] < d.tau_from_s) ++i;
    const double measured = (r.y[i] - r.zero_level) / k;
    EXPECT_NEAR(d.omega_from, measured, 0.05 * std::max(measured, 20.0)) << d.tau_from_s;
  }
}

namespace {

// A propeller's spin-down as a speed logger with a coarse reading prints it: held at its powered
// speed, then a free coast under friction a + c_w·ω² (+ b·ω) to standstill, sampled every
// period_s and rounded to whole steps of `step` rad/s (an encoder's count per window).
Recording coarse_propeller(double a, double b, double c_w, double step, double period_s) {
  Recording rec;
  rec.quantity = Quantity::rad_per_s;
  const double w_powered = 1000.0, t_cut = 3.0, j = 1.1e-5;
  double w = w_powered, t_sim = t_cut;
  for (double t = 0; t < t_cut + 6.0; t += period_s) {
    if (t >= t_cut) {
      for (; t_sim < t; t_sim += 1e-4) w = std::max(0.0, w - 1e-4 * (a + b * w + c_w * w * w) / j);
    }
    rec.push(t, step * std::round((t < t_cut ? w_powered : w) / step));
  }
  return rec;
}

}  // namespace

// Issue 41 (a real propeller's 2-s coast, read in steps of 41 rad/s at 13 Hz): windage changes
// the combined model by less than half a step, yet where the reading falls a step or more every
// sample rounding is noise, and there windage's evidence is plain. Named first, as on the real
// recording; the same coast without windage gets nothing added.
TEST(Explain, WindageOnACoarseFastReadingIsNamedWhereRoundingIsNoise) {
  const auto first_added = [](const Recording& rec) {
    const Segmentation seg = find_runs(rec);
    EXPECT_EQ(seg.runs.size(), 1u);
    if (seg.runs.empty()) return std::string("no run");
    ExplainOptions opt;
    opt.bench.inertia_kg_m2 = 1.1e-5;
    std::string why;
    opt.base = parse_effect_list("combined", &why);
    const ExplainResult r = explain_run(rec, seg.runs.front(), opt);
    for (const auto& s : r.steps)
      if (!s.added.empty()) return s.added;
    return std::string();
  };
  EXPECT_EQ(first_added(coarse_propeller(1.7e-3, 0, 2.4e-8, 41.3, 0.076)), "windage");
  EXPECT_EQ(first_added(coarse_propeller(1.7e-3, 4.0e-6, 0, 41.3, 0.076)), "");
}
