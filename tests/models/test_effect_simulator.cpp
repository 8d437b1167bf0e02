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
  expect_matches_coast({1.5e-7, 1e-4, 2e-4, 35}, w0, 0.02, 1e-5);           // Stribeck (ODE)
  expect_matches_coast({8e-8, 1e-4, 0, 0, 7e-10}, w0, 0.02, 1e-5);          // windage (ODE)
  expect_matches_coast({8e-8, 1e-4, 3e-4, 20, 7e-10}, w0, 0.05, 1e-5);      // all, 50 ms loop
  expect_matches_coast({8e-8, 1e-4, 3e-4, 20, 7e-10}, w0, 0.010, 1e-5);     // all, 10 ms loop
}

// The adaptive ODE path against the closed form on the same physics (a windage term of 0 forces
// the ODE path): speeds, the stop and the sensitivities, for coasts that stop and one that does not.
TEST(EffectSimulator, OdePathMatchesTheClosedForm) {
  const EffectSimulator closed({find_effect("viscous"), find_effect("coulomb")}, 1.0);
  const EffectSimulator ode({find_effect("viscous"), find_effect("coulomb"), find_effect("windage")}, 1.0);
  ASSERT_TRUE(closed.closed_form());
  ASSERT_FALSE(ode.closed_form());
  const auto tau = grid(0.02, 45.0);
  const std::size_t n = tau.size();
  for (const auto& p : std::vector<std::vector<double>>{{346, 0.016, 10.1}, {346, 0.1, 0}, {300, 0, 9}, {300, 0.04, 3}}) {
    std::vector<double> a(n), b(n), ja(n * 3), jb(n * 4);
    closed.simulate(p, tau, a, ja);
    const std::vector<double> p_ode{p[0], p[1], p[2], 0.0};
    ode.simulate(p_ode, tau, b, jb);
    const double ts = closed.stop_time(p);
    for (std::size_t i = 0; i < n; ++i) {
      ASSERT_NEAR(b[i], a[i], 1e-7) << "w0 " << p[0] << " τ=" << tau[i];
      if (std::abs(tau[i] - ts) < 1e-3) continue;  // the kink at the stop
      for (int j = 0; j < 3; ++j)
        ASSERT_NEAR(jb[i * 4 + j], ja[i * 3 + j], 1e-6 * (std::abs(ja[i * 3 + j]) + 1e-3)) << "param " << j << " τ=" << tau[i];
    }
  }
}

// The samples are read from the integrator's dense output: the same instant gives the same
// speed whatever the sampling grid around it (10 ms, 50 ms, a single sample).
TEST(EffectSimulator, SpeedAtAnInstantDoesNotDependOnTheSampleGrid) {
  const EffectSimulator sim({find_effect("viscous"), find_effect("coulomb"), find_effect("stribeck"),
                             find_effect("windage")},
                            1.0);
  const std::vector<double> th{346, 0.007, 8.9, 17.7, 20, 6.2e-5};
  const double ts = sim.stop_time(th);
  ASSERT_TRUE(std::isfinite(ts));
  for (double at : {0.5, 7.25, 0.5 * ts, ts - 0.3, ts - 0.01}) {
    std::vector<double> fine = grid(0.01, at), coarse = grid(0.05, at);
    fine.push_back(at);
    coarse.push_back(at);
    const double one = sim.omega(th, std::vector<double>{at})[0];
    EXPECT_NEAR(sim.omega(th, fine).back(), one, 1e-7) << at;
    EXPECT_NEAR(sim.omega(th, coarse).back(), one, 1e-7) << at;
    EXPECT_GT(one, 0) << at;
  }
  EXPECT_EQ(sim.omega(th, std::vector<double>{ts + 0.01})[0], 0.0);
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
            << (closed ? "closed form" : "ODE") << " param " << j << " τ=" << tau[i];
      }
    }
  }
}
