// fit_t and run_t from the fitter's results: a fit survives RunFit -> fit_t -> wire -> fit_t ->
// RunFit with run_fit_json() unchanged, and inconsistent messages are refused with a reason.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "spindown/fit_message.hpp"
#include "spindown/runs.hpp"
#include "spindown/synthetic_run.hpp"

namespace spindown {
namespace {

RunFit sample_fit() {
  SyntheticRunSpec spec;
  spec.seed = 42;
  const SyntheticRun run = make_synthetic_run(spec);
  Recording rec;
  for (std::size_t i = 0; i < run.t_ms.size(); ++i) rec.push(run.t_ms[i] / 1000.0, run.volts[i]);
  const Segmentation seg = find_runs(rec);
  EXPECT_EQ(seg.runs.size(), 1u);
  FitOptions fo;
  fo.bench.inertia_source = "geometry";
  return fit_run(rec, seg.runs.at(0), fo);
}

TEST(FitMessage, RoundTripKeepsTheReport) {
  const RunFit fit = sample_fit();
  FitProvenance about{"lab-3", "config", 100, 1500, 0.004, std::nullopt, "", 0};
  const fit_t msg = to_fit_message(fit, about, 123);
  EXPECT_EQ(msg.nmodels, 3);
  EXPECT_EQ(msg.nparams, static_cast<std::int32_t>(msg.param_name.size()));
  EXPECT_EQ(msg.best, fit.best);
  EXPECT_EQ(msg.residual_unit, "V");
  EXPECT_DOUBLE_EQ(msg.latency_s, 0.004);

  // Over the wire.
  std::vector<unsigned char> buf(static_cast<std::size_t>(msg.getEncodedSize()));
  ASSERT_GT(msg.encode(buf.data(), 0, static_cast<int>(buf.size())), 0);
  fit_t back{};
  ASSERT_GT(back.decode(buf.data(), 0, static_cast<int>(buf.size())), 0);

  std::string why;
  const auto again = from_fit_message(back, &why);
  ASSERT_TRUE(again) << why;
  Json expected = run_fit_json(fit);
  EXPECT_EQ(run_fit_json(*again).dump(), expected.dump());

  const auto j = fit_message_json(back, {}, &why);
  ASSERT_TRUE(j) << why;
  EXPECT_EQ((*j)["bench"]["id"], "lab-3");
  EXPECT_EQ((*j)["first_seq"], 100);
  EXPECT_EQ((*j)["last_seq"], 1500);
  EXPECT_EQ((*j)["bench"]["J_source"], "geometry");
}

TEST(FitMessage, TheUncertaintyOfJAndKbTravelsWithEachParameter) {
  SyntheticRunSpec spec;
  spec.seed = 42;
  const SyntheticRun run = make_synthetic_run(spec);
  Recording rec;
  for (std::size_t i = 0; i < run.t_ms.size(); ++i) rec.push(run.t_ms[i] / 1000.0, run.volts[i]);
  FitOptions fo;
  fo.bench.inertia_rel_error = 0.02;
  fo.bench.kb_rel_error = 0.05;
  const RunFit fit = fit_run(rec, find_runs(rec).runs.at(0), fo);
  const fit_t msg = to_fit_message(fit, FitProvenance{"b", "config", 0, 0, 0, std::nullopt, "", 0}, 1);
  EXPECT_DOUBLE_EQ(msg.inertia_rel_error, 0.02);
  EXPECT_DOUBLE_EQ(msg.kb_rel_error, 0.05);
  ASSERT_EQ(msg.param_bench_error.size(), msg.param_name.size());
  for (std::size_t k = 0; k < msg.param_name.size(); ++k) {
    if (msg.param_name[k] == "c4") {
      EXPECT_GT(msg.param_bench_error[k], 0.04 * msg.param_value[k]);  // J's 2 % and 1/K_b's 5 %
    }
  }
  std::string why;
  const auto back = from_fit_message(msg, &why);
  ASSERT_TRUE(back) << why;
  EXPECT_EQ(run_fit_json(*back).dump(), run_fit_json(fit).dump());  // bench_stderr, total_stderr included
  EXPECT_NE(run_fit_json(fit).dump().find("\"total_stderr\""), std::string::npos);
}

// A received fit draws the fitter's curves: each model's ω(τ) from the message equals the fit's
// own, before the stop, at it and after (spindown-web draws them from the message).
TEST(FitMessage, EachModelsSpeedLawSurvivesTheMessage) {
  const RunFit fit = sample_fit();
  std::string why;
  const auto back = from_fit_message(to_fit_message(fit, {"b", "config", 0, 0, 0, std::nullopt, "", 0}, 1), &why);
  ASSERT_TRUE(back) << why;
  ASSERT_EQ(back->models.size(), fit.models.size());
  for (std::size_t i = 0; i < fit.models.size(); ++i) {
    const ModelFit& a = fit.models[i];
    const ModelFit& b = back->models[i];
    ASSERT_TRUE(a.converged) << model_name(a.kind);
    EXPECT_GT(a.omega_at(1.0), 0) << model_name(a.kind);
    for (double tau : {0.0, 1.0, 5.0, 0.5 * a.t_stop_pred_s, 20.0, 40.0}) {
      if (!std::isfinite(tau)) continue;
      EXPECT_NEAR(b.omega_at(tau), a.omega_at(tau), 1e-9 * a.omega0 + 1e-12) << model_name(a.kind) << " τ " << tau;
    }
  }
}

TEST(FitMessage, InconsistentArraysAreRefused) {
  fit_t msg = to_fit_message(sample_fit(), {"b", "config", 0, 0, 0, std::nullopt, "", 0}, 0);
  fit_t bad = msg;
  bad.nmodels = 5;
  std::string why;
  EXPECT_FALSE(from_fit_message(bad, &why));
  EXPECT_NE(why.find("nmodels"), std::string::npos);
  bad = msg;
  bad.param_model[0] = 9;
  EXPECT_FALSE(from_fit_message(bad, &why));
  bad = msg;
  bad.model[1] = "magic";
  EXPECT_FALSE(from_fit_message(bad, &why));
  EXPECT_NE(why.find("magic"), std::string::npos);
}

TEST(FitMessage, HealthVerdictTravelsWithTheFit) {
  const RunFit fit = sample_fit();
  MotorHealthConfig cfg;
  cfg.baseline = HealthBaseline{};
  cfg.baseline->c_viscous = 1.822e-7;
  cfg.baseline->c_viscous_stderr = 2e-9;
  cfg.baseline->c_coulomb = 1.1389e-4 / 2.5;  // the run looks like 2.5× its baseline
  cfg.baseline->c_coulomb_stderr = 2e-7;
  const HealthVerdict verdict = assess_health(fit, cfg);
  ASSERT_EQ(verdict.level, HealthLevel::service) << verdict.reason;
  FitProvenance about{"lab-3", "config", 100, 1500, 0.004, verdict, "", 0};
  const fit_t msg = to_fit_message(fit, about, 123);
  EXPECT_EQ(msg.verdict, "service");
  EXPECT_EQ(msg.verdict_reason, verdict.reason);
  EXPECT_TRUE(msg.health_reference);
  EXPECT_EQ(msg.nfindings, static_cast<std::int32_t>(verdict.findings.size()));

  std::vector<unsigned char> buf(static_cast<std::size_t>(msg.getEncodedSize()));
  ASSERT_GT(msg.encode(buf.data(), 0, static_cast<int>(buf.size())), 0);
  fit_t back{};
  ASSERT_GT(back.decode(buf.data(), 0, static_cast<int>(buf.size())), 0);
  std::string why;
  const auto again = health_from_fit_message(back, &why);
  ASSERT_TRUE(again) << why;
  EXPECT_EQ(health_json(*again).dump(), health_json(verdict).dump());
  const auto j = fit_message_json(back, {}, &why);
  ASSERT_TRUE(j) << why;
  EXPECT_EQ((*j)["health"]["level"], "service");

  // Without a bench file: no verdict, no "health" in the JSON.
  const fit_t plain = to_fit_message(fit, {"lab-3", "config", 100, 1500, 0.004, std::nullopt, "", 0}, 123);
  EXPECT_EQ(plain.verdict, "");
  EXPECT_EQ(plain.nfindings, 0);
  EXPECT_FALSE(health_from_fit_message(plain));
  EXPECT_FALSE(fit_message_json(plain)->contains("health"));

  // Inconsistent finding arrays or an unknown level are refused with a reason.
  fit_t bad = back;
  bad.nfindings += 1;
  EXPECT_FALSE(health_from_fit_message(bad, &why));
  EXPECT_NE(why.find("nfindings"), std::string::npos);
  bad = back;
  bad.finding_level[0] = "doomed";
  EXPECT_FALSE(fit_message_json(bad, {}, &why));
  EXPECT_NE(why.find("doomed"), std::string::npos);
}

TEST(FitMessage, NeverStoppedRunHasNanStop) {
  RunFit fit = sample_fit();
  fit.run.stopped = false;
  const fit_t msg = to_fit_message(fit, {"b", "config", 0, 0, 0, std::nullopt, "", 0}, 0);
  EXPECT_TRUE(std::isnan(msg.t_stop_s));
  const auto back = from_fit_message(msg);
  ASSERT_TRUE(back);
  EXPECT_FALSE(back->run.stopped);
}

TEST(FitMessage, RunMessageAndTimingFields) {
  spindown::Run r;
  r.number = 2;
  r.t_cut_s = 1.5;
  const run_t m = to_run_message("b", r, run_t::STATE_COASTING, 10, 20, 11, "cut", 5);
  EXPECT_EQ(m.run, 2);
  EXPECT_TRUE(std::isnan(m.t_stop_s));
  EXPECT_EQ(run_state_name(m.state), "coasting");
  Json j = {{"a", 1}, {"latency_s", 0.2}, {"x", {{"utime", 5}, {"b", 2}}}};
  EXPECT_EQ(without_timing_fields(j).dump(), R"({"a":1,"x":{"b":2}})");
}

}  // namespace
}  // namespace spindown
