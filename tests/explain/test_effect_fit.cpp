// Output-error estimation of any combination: recovers the truth from simulated readings,
// its standard errors are honest on noisy data, and nested models never fit worse.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "spindown/effect_fit.hpp"
#include "spindown/effect_simulator.hpp"

using namespace spindown;

namespace {

constexpr double J = 1.12687602e-5;
constexpr double kb = 1.0 / 123.569311;

struct Data {
  std::vector<double> tau, y;
  std::size_t moving = 0;
  EffectFitData view() const {
    EffectFitData d;
    d.tau = tau;
    d.y = y;
    d.moving = moving;
    d.k = kb;
    d.inertia_kg_m2 = J;
    return d;
  }
};

Data simulate(const FrictionTerms& f, double offset, double noise, std::uint64_t seed) {
  const double w0 = 2.9 / kb;
  auto effects = friction_effects(f);
  auto th = friction_theta(f, J, w0);
  if (offset != 0) {
    effects.push_back(find_effect("sensor_offset"));
    th.push_back(offset);
  }
  const EffectSimulator sim(effects, kb);
  Data d;
  for (double t = 0.011; t < sim.stop_time(th) + 2.0 && t < 60; t += 0.02) d.tau.push_back(t);
  d.y.resize(d.tau.size());
  sim.simulate(th, d.tau, d.y);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0, 1);
  const double ts = sim.stop_time(th);
  for (std::size_t i = 0; i < d.y.size(); ++i) {
    d.y[i] += noise * g(rng);
    if (d.tau[i] < ts) d.moving = i + 1;
  }
  return d;
}

std::vector<const Effect*> effects(std::initializer_list<const char*> names) {
  std::vector<const Effect*> out;
  for (auto n : names) out.push_back(find_effect(n));
  return out;
}

}  // namespace

TEST(EffectFit, RecoversEveryEffectFromExactReadings) {
  const FrictionTerms f{1.5e-7, 1e-4, 2e-4, 35, 5e-10};
  const Data d = simulate(f, 0.05, 0.0, 1);
  const EffectFit fit =
      fit_effects(effects({"viscous", "coulomb", "stribeck", "windage", "sensor_offset"}), d.view());
  ASSERT_TRUE(fit.converged) << fit.message;
  EXPECT_LT(fit.rmse, 1e-5);
  EXPECT_NEAR(fit.param("c3")->value, 1.5e-7, 2e-9);
  EXPECT_NEAR(fit.param("c4")->value, 1e-4, 1e-7);
  EXPECT_NEAR(fit.param("c_s")->value, 2e-4, 2e-7);
  EXPECT_NEAR(fit.param("w_s")->value, 35, 0.1);
  EXPECT_NEAR(fit.param("c_w")->value, 5e-10, 5e-12);
  EXPECT_NEAR(fit.param("sensor_offset")->value, 0.05, 1e-5);
  EXPECT_EQ(fit.param("sensor_offset")->unit, "V");
  EXPECT_NEAR(fit.omega0, 2.9 / kb, 0.01);
}

TEST(EffectFit, StandardErrorsCoverTheTruthOnNoisyData) {
  // 20 noisy repetitions: the truth should fall within 2.5 standard errors nearly always.
  int covered = 0, total = 0;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const Data d = simulate({1.5e-7, 1e-4, 0, 0, 5e-10}, 0.0, 0.004, seed);
    const EffectFit fit = fit_effects(effects({"viscous", "coulomb", "windage"}), d.view());
    ASSERT_TRUE(fit.converged) << fit.message;
    for (auto [name, truth] : {std::pair{"c3", 1.5e-7}, {"c4", 1e-4}, {"c_w", 5e-10}}) {
      const Parameter* p = fit.param(name);
      ASSERT_TRUE(p && std::isfinite(p->std_error) && p->std_error > 0) << name;
      covered += std::abs(p->value - truth) < 2.5 * p->std_error;
      ++total;
    }
  }
  EXPECT_GE(covered, total * 9 / 10) << covered << " of " << total;
}

TEST(EffectFit, NestedModelIsNeverWorseThanItsWarmStart) {
  const Data d = simulate({1.8e-7, 1.1e-4, 0, 0, 0}, 0.0, 0.003, 7);
  const EffectFit base = fit_effects(effects({"viscous", "coulomb"}), d.view());
  ASSERT_TRUE(base.converged);
  for (const char* extra : {"stribeck", "windage", "sensor_offset"}) {
    auto e = effects({"viscous", "coulomb"});
    e.push_back(find_effect(extra));
    const EffectFit bigger = fit_effects(e, d.view(), &base);
    EXPECT_LE(bigger.sse, base.sse * (1 + 1e-9)) << extra;
  }
}

// The lab's names, as spindown fit gives them: viscous alone c1, Coulomb alone c2, both c3 and c4.
TEST(EffectFit, ParametersCarryFitsNames) {
  const Data d = simulate({1.8e-7, 1.1e-4, 0, 0, 0}, 0.0, 0.003, 7);
  const auto names = [&](std::initializer_list<const char*> model) {
    std::vector<std::string> out;
    for (const auto& p : fit_effects(effects(model), d.view()).params) out.push_back(p.name);
    return out;
  };
  EXPECT_EQ(names({"viscous"}), (std::vector<std::string>{"c1", "omega0"}));
  EXPECT_EQ(names({"coulomb"}), (std::vector<std::string>{"c2", "omega0"}));
  EXPECT_EQ(names({"viscous", "coulomb"}), (std::vector<std::string>{"c3", "c4", "omega0"}));
  EXPECT_EQ(names({"viscous", "coulomb", "stribeck", "sensor_offset"}),
            (std::vector<std::string>{"c3", "c4", "c_s", "w_s", "sensor_offset", "omega0"}));
  EXPECT_EQ(names({"viscous", "windage"}), (std::vector<std::string>{"c1", "c_w", "omega0"}));
  const EffectFit combined = fit_effects(effects({"viscous", "coulomb"}), d.view());
  EXPECT_EQ(combined.fit_model(), "combined");
  EXPECT_EQ(combined.title(), "combined (viscous+coulomb)");
}

// Weighted least squares (spindown fit's objective): sse is Σ w·r², rmse stays the plain one; and a
// sensor offset stays within the bound the zero level's uncertainty sets.
TEST(EffectFit, WeightsAndTheOffsetBound) {
  Data d = simulate({1.8e-7, 1.1e-4, 0, 0, 0}, 0.05, 0.003, 7);
  std::vector<double> w(d.y.size());
  for (std::size_t i = 0; i < w.size(); ++i) w[i] = i < w.size() / 2 ? 0.5 : 1.5;
  EffectFitData view = d.view();
  view.weight = w;
  const EffectFit weighted = fit_effects(effects({"viscous", "coulomb"}), view);
  double plain = 0, objective = 0;
  for (std::size_t i = 0; i < d.y.size(); ++i) {
    const double r = d.y[i] - weighted.simulated[i];
    plain += r * r, objective += w[i] * r * r;
  }
  EXPECT_NEAR(weighted.sse, objective, 1e-9 * objective);
  EXPECT_NEAR(weighted.rmse, std::sqrt(plain / double(d.y.size())), 1e-12);
  // Unbounded, the offset is found (0.05 V); bounded to [-0.01, 0.01] V it stops at the bound.
  EXPECT_NEAR(fit_effects(effects({"viscous", "coulomb", "sensor_offset"}), d.view()).param("sensor_offset")->value,
              0.05, 1e-3);
  EffectFitData bounded = d.view();
  bounded.offset_lo = -0.01;
  bounded.offset_hi = 0.01;
  const EffectFit b = fit_effects(effects({"viscous", "coulomb", "sensor_offset"}), bounded);
  EXPECT_NEAR(b.param("sensor_offset")->value, 0.01, 1e-12);
}

TEST(EffectFit, TooFewSamplesIsAMessageNotACrash) {
  Data d = simulate({1.8e-7, 1.1e-4, 0, 0, 0}, 0.0, 0.003, 7);
  d.tau.resize(4);
  d.y.resize(4);
  d.moving = 4;
  const EffectFit fit = fit_effects(effects({"viscous", "coulomb", "stribeck"}), d.view());
  EXPECT_FALSE(fit.converged);
  EXPECT_NE(fit.message.find("too few"), std::string::npos) << fit.message;
}
