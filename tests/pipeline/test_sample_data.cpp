// Issue 2's acceptance on the sample logs (data/, made by the project's simulator): read → find the run → fit,
// checked against each file's truth. Where the truth is in the combined model's class
// (viscous + Coulomb, with or without a sensor offset), c3 and c4 must come within 3·stderr
// and 5 % of c_v, c_c; the cut within one sample period. Files whose truth holds an effect
// the lab's models lack (Stribeck, windage) are fitted too, and the misfit must show — naming
// that effect is `spindown explain`'s job (issue 5).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "spindown/fit.hpp"
#include "spindown/read_recording.hpp"
#include "spindown/runs.hpp"

using namespace spindown;

namespace {

const std::string data_dir = SPINDOWN_SAMPLE_DATA;

struct Truth {
  double c_v = 0, c_c = 0, c_s = 0, c_w = 0, offset = 0, t_cut_s = 0, t_stop_s = 0;
  double t_power_cut_s = 0;  // t_cut_s is where the coast enters the readings: a floating pin's connection
  int bounces = 0;           // samples of contact bounce there (the cut may follow them)
};

Truth load_truth(const std::string& file) {
  std::ifstream in(file + ".truth.json");
  const auto j = nlohmann::json::parse(in);
  Truth t;
  t.c_v = j.at("c_v");
  t.c_c = j.at("c_c");
  t.c_s = j.value("c_s", 0.0);
  t.c_w = j.value("c_w", 0.0);
  t.offset = j.value("offset", 0.0);
  // The simulator's truth (data/make-samples): one run, its cut in device time.
  const auto& run = j.at("runs").at(0);
  t.t_power_cut_s = run.at("cut_device_us").get<double>() / 1e6;
  t.t_cut_s = run.value("connect_device_us", run.at("cut_device_us").get<double>()) / 1e6;
  t.bounces = run.contains("bounce_bench_s") ? int(run.at("bounce_bench_s").size()) : 0;
  t.t_stop_s = run.at("t_stop_s");  // after the power cut
  return t;
}

struct Fitted {
  Recording rec;
  Run run;
  RunFit fit;
};

Fitted read_and_fit(const std::string& name) {
  const std::string path = data_dir + "/" + name;
  auto recs = read_recordings(path);
  EXPECT_EQ(recs.size(), 1u) << path;
  Fitted out{std::move(recs.at(0)), {}, {}};
  EXPECT_FALSE(out.rec.has_errors()) << path;
  const Segmentation seg = find_runs(out.rec);
  EXPECT_EQ(seg.runs.size(), 1u) << path;
  if (seg.runs.empty()) return out;
  out.run = seg.runs[0];
  out.fit = fit_run(out.rec, out.run, FitOptions{});
  return out;
}

double period_of(const Recording& rec, std::size_t i) { return rec.t_s[i + 1] - rec.t_s[i]; }

}  // namespace

class CombinedClassFile : public ::testing::TestWithParam<const char*> {};

TEST_P(CombinedClassFile, RecoversTruthWithinThreeStandardErrorsAndFivePercent) {
  const std::string name = GetParam();
  if (!std::filesystem::exists(data_dir + "/" + name)) GTEST_SKIP() << "no sample data at " << data_dir;
  const Truth truth = load_truth(data_dir + "/" + name);
  const Fitted f = read_and_fit(name);
  ASSERT_TRUE(f.run.stopped) << name;
  const double period = period_of(f.rec, f.run.cut_index);
  EXPECT_GT(f.run.t_cut_s, truth.t_cut_s - period) << name;
  EXPECT_LT(f.run.t_cut_s, truth.t_cut_s + (truth.bounces + 1) * period) << name;
  EXPECT_NEAR(f.run.zero_level, truth.offset, 0.006) << name;

  const ModelFit* m = f.fit.model(ModelKind::combined);
  ASSERT_NE(m, nullptr);
  ASSERT_TRUE(m->converged) << m->message;
  const Parameter& c3 = *m->param("c3");
  const Parameter& c4 = *m->param("c4");
  EXPECT_LT(std::abs(c3.value - truth.c_v), 3 * c3.std_error) << name << " c3 " << c3.value << "±" << c3.std_error;
  EXPECT_LT(std::abs(c3.value - truth.c_v), 0.05 * truth.c_v) << name;
  EXPECT_LT(std::abs(c4.value - truth.c_c), 3 * c4.std_error) << name << " c4 " << c4.value << "±" << c4.std_error;
  EXPECT_LT(std::abs(c4.value - truth.c_c), 0.05 * truth.c_c) << name;
  EXPECT_NEAR(f.run.t_cut_s + m->t_stop_pred_s, truth.t_power_cut_s + truth.t_stop_s, 0.1) << name;
  EXPECT_EQ(f.fit.best, "combined") << f.fit.best_reason;
}

INSTANTIATE_TEST_SUITE_P(SharedData, CombinedClassFile,
                         ::testing::Values("seed-3v-run1.tsv", "seed-3v5-run2.tsv", "supply-leadin.tsv",
                                           "offset-example.tsv"));

TEST(SampleData, ViscousOnlyRunNeedsNoCoulombTerm) {
  const std::string name = "viscous-only.tsv";
  if (!std::filesystem::exists(data_dir + "/" + name)) GTEST_SKIP() << "no sample data";
  const Truth truth = load_truth(data_dir + "/" + name);
  const Fitted f = read_and_fit(name);
  EXPECT_LT(std::abs(f.run.t_cut_s - truth.t_cut_s), period_of(f.rec, f.run.cut_index));
  const ModelFit* v = f.fit.model(ModelKind::viscous);
  ASSERT_TRUE(v && v->converged);
  // The coast never stops: its floor on the 2-decimal print (0.01 V) is where the decay sank below
  // the print, not the zero. Subtracting it made c1 1.4 % (19 standard errors) too high and
  // invented Coulomb friction; the lead-in's zero is the zero.
  EXPECT_FALSE(f.run.stopped);
  EXPECT_EQ(f.run.zero_level, 0.0);
  const Parameter& c1 = *v->param("c1");
  EXPECT_LT(std::abs(c1.value - truth.c_v), 3 * c1.std_error) << c1.value << "±" << c1.std_error;
  const ModelFit* m = f.fit.model(ModelKind::combined);
  ASSERT_TRUE(m && m->converged);
  const Parameter& c3 = *m->param("c3");
  EXPECT_LT(std::abs(c3.value - truth.c_v), 0.01 * truth.c_v) << c3.value << "±" << c3.std_error;
  // Truth c_c = 0: whatever Coulomb torque the fit finds is under 0.2 % of the viscous torque at
  // the cut (0.06 % now; 0.41 % with the floor subtracted).
  EXPECT_LT(m->param("c4")->value, 0.002 * c3.value * m->param("omega0")->value);
}

class HiddenEffectFile : public ::testing::TestWithParam<const char*> {};

TEST_P(HiddenEffectFile, IsFittedAndTheMisfitShows) {
  const std::string name = GetParam();
  if (!std::filesystem::exists(data_dir + "/" + name)) GTEST_SKIP() << "no sample data";
  const Truth truth = load_truth(data_dir + "/" + name);
  const Fitted f = read_and_fit(name);
  EXPECT_LT(std::abs(f.run.t_cut_s - truth.t_cut_s), period_of(f.rec, f.run.cut_index));
  const ModelFit* m = f.fit.model(ModelKind::combined);
  ASSERT_TRUE(m && m->converged);
  // The residual is well above the noise seen at standstill: the combined model misses something.
  EXPECT_GT(m->rmse, 2.5 * std::max(f.run.noise_level, 0.003)) << name << " rmse " << m->rmse;
}

INSTANTIATE_TEST_SUITE_P(SharedData, HiddenEffectFile, ::testing::Values("stribeck-example.tsv", "windage-example.tsv"));
