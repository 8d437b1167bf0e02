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
  EXPECT_NEAR(fit.param("c_v")->value, 1.5e-7, 2e-9);
  EXPECT_NEAR(fit.param("c_c")->value, 1e-4, 1e-7);
  EXPECT_NEAR(fit.param("c_s")->value, 2e-4, 2e-7);
  EXPECT_NEAR(fit.param("w_s")->value, 35, 0.1);
  EXPECT_NEAR(fit.param("c_w")->value, 5e-10, 5e-12);
  EXPECT_NEAR(fit.param("offset")->value, 0.05, 1e-5);
  EXPECT_EQ(fit.param("offset")->unit, "V");
  EXPECT_NEAR(fit.omega0, 2.9 / kb, 0.01);
}

TEST(EffectFit, StandardErrorsCoverTheTruthOnNoisyData) {
  // 20 noisy repetitions: the truth should fall within 2.5 standard errors nearly always.
  int covered = 0, total = 0;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const Data d = simulate({1.5e-7, 1e-4, 0, 0, 5e-10}, 0.0, 0.004, seed);
    const EffectFit fit = fit_effects(effects({"viscous", "coulomb", "windage"}), d.view());
    ASSERT_TRUE(fit.converged) << fit.message;
    for (auto [name, truth] : {std::pair{"c_v", 1.5e-7}, {"c_c", 1e-4}, {"c_w", 5e-10}}) {
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

TEST(EffectFit, TooFewSamplesIsAMessageNotACrash) {
  Data d = simulate({1.8e-7, 1.1e-4, 0, 0, 0}, 0.0, 0.003, 7);
  d.tau.resize(4);
  d.y.resize(4);
  d.moving = 4;
  const EffectFit fit = fit_effects(effects({"viscous", "coulomb", "stribeck"}), d.view());
  EXPECT_FALSE(fit.converged);
  EXPECT_NE(fit.message.find("too few"), std::string::npos) << fit.message;
}
