// The simulator for any combination of effects: against CoastSimulator (adaptive RK45 with
// its exact stop), the closed forms, and its sensitivities against finite differences.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "spindown/coast_simulator.hpp"
#include "spindown/effect_simulator.hpp"

using namespace spindown;

namespace {

constexpr double J = 1.12687602e-5;

std::vector<double> grid(double period, double until) {
  std::vector<double> t;
  for (double x = 0.013; x < until; x += period) t.push_back(x);
  return t;
}

void expect_matches_coast(const FrictionTerms& f, double w0, double period, double tol) {
  const auto tau = grid(period, 40.0);
  const auto ref = simulate_coast(f, J, w0, tau);
  const EffectSimulator sim(friction_effects(f), 1.0);
  const auto th = friction_theta(f, J, w0);
  const auto got = sim.omega(th, tau);
  double worst = 0;
  for (std::size_t i = 0; i < tau.size(); ++i) worst = std::max(worst, std::abs(got[i] - ref[i]));
  EXPECT_LT(worst, tol) << "largest |Δω| (rad/s) over " << tau.size() << " samples";
  CoastSimulator coast(f, J, w0);
  coast.advance(60.0);
  if (coast.stopped()) {
    EXPECT_NEAR(sim.stop_time(th), coast.stop_time(), 1e-6 * coast.stop_time());
  }
}

}  // namespace

TEST(EffectSimulator, MatchesCoastSimulatorForEveryCombination) {
  const double w0 = 346;
  expect_matches_coast({1.822e-7, 1.1389e-4}, w0, 0.02, 1e-6);               // closed form
  expect_matches_coast({1.2e-6, 0}, w0, 0.02, 1e-6);                        // viscous only
  expect_matches_coast({0, 1.1e-4}, w0, 0.05, 1e-6);                        // Coulomb only
  expect_matches_coast({1.5e-7, 1e-4, 2e-4, 35}, w0, 0.02, 2e-3);           // Stribeck (RK4)
  expect_matches_coast({8e-8, 1e-4, 0, 0, 7e-10}, w0, 0.02, 2e-3);          // windage (RK4)
  expect_matches_coast({8e-8, 1e-4, 3e-4, 20, 7e-10}, w0, 0.05, 2e-3);      // all, 50 ms loop
  expect_matches_coast({8e-8, 1e-4, 3e-4, 20, 7e-10}, w0, 0.010, 2e-3);     // all, 10 ms loop
}

TEST(EffectSimulator, StaysStoppedAndAddsTheSensorOffset) {
  std::vector<const Effect*> e{find_effect("viscous"), find_effect("coulomb"), find_effect("windage"),
                               find_effect("sensor_offset")};
  const EffectSimulator sim(e, 0.0081);
  EXPECT_FALSE(sim.closed_form());
  const std::vector<double> th{300, 0.015, 9.0, 5e-5, 0.06};
  const auto tau = grid(0.02, 60.0);
  std::vector<double> y(tau.size());
  sim.simulate(th, tau, y);
  const double ts = sim.stop_time(th);
  ASSERT_TRUE(std::isfinite(ts));
  for (std::size_t i = 0; i < tau.size(); ++i) {
    if (tau[i] > ts) {
      EXPECT_DOUBLE_EQ(y[i], 0.06) << "after the stop at " << ts;
    }
    if (tau[i] < ts - 0.05) {
      EXPECT_GT(y[i], 0.06);
    }
  }
  // Viscous + Coulomb (+ offset) uses the closed form.
  EXPECT_TRUE(EffectSimulator({find_effect("viscous"), find_effect("coulomb"), find_effect("sensor_offset")}, 1.0)
                  .closed_form());
}

TEST(EffectSimulator, SensitivitiesMatchFiniteDifferences) {
  for (bool closed : {true, false}) {
    std::vector<const Effect*> e{find_effect("viscous"), find_effect("coulomb")};
    std::vector<double> th{320, 0.02, 8.0};
    if (!closed) {
      e = {find_effect("viscous"), find_effect("coulomb"), find_effect("stribeck"), find_effect("windage"),
           find_effect("sensor_offset")};
      th = {320, 0.01, 8.0, 9.0, 30.0, 4e-5, 0.03};
    }
    const EffectSimulator sim(e, 0.0081);
    const auto tau = grid(0.02, 50.0);
    const std::size_t n = tau.size();
    const int P = sim.size();
    std::vector<double> y(n), jac(n * P), up(n), dn(n);
    sim.simulate(th, tau, y, jac);
    const double ts = sim.stop_time(th);
    for (int j = 0; j < P; ++j) {
      auto a = th, b = th;
      const double h = 1e-6 * std::max(std::abs(th[j]), 1e-6);
      a[j] += h;
      b[j] -= h;
      sim.simulate(a, tau, up);
      sim.simulate(b, tau, dn);
      for (std::size_t i = 0; i < n; ++i) {
        if (std::abs(tau[i] - ts) < 0.1) continue;  // the kink at the stop
        const double num = (up[i] - dn[i]) / (2 * h);
        ASSERT_NEAR(jac[i * P + j], num, 1e-4 * (std::abs(num) + 1e-3))
            << (closed ? "closed form" : "RK4") << " param " << j << " τ=" << tau[i];
      }
    }
  }
}
