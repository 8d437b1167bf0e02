#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "spindown/coast_simulator.hpp"

using namespace spindown;

namespace {
constexpr double J = 1.12687602e-5;
}

TEST(CoastSimulator, CombinedMatchesClosedForm) {
  const FrictionTerms f{1.822e-7, 1.1389e-4};
  const double w0 = 346.0, a = f.viscous / J, b = f.coulomb / J;
  std::vector<double> tau;
  for (int i = 0; i <= 1500; ++i) tau.push_back(i * 0.02);
  const auto w = simulate_coast(f, J, w0, tau);
  const double t_stop = std::log1p(a * w0 / b) / a;
  for (std::size_t i = 0; i < tau.size(); ++i) {
    const double exact = tau[i] < t_stop ? (w0 + b / a) * std::exp(-a * tau[i]) - b / a : 0.0;
    ASSERT_NEAR(w[i], exact, 1e-6 * w0) << "tau=" << tau[i];
  }
  CoastSimulator sim(f, J, w0);
  sim.advance(40.0);
  ASSERT_TRUE(sim.stopped());
  EXPECT_NEAR(sim.stop_time(), t_stop, 1e-6);
  EXPECT_EQ(sim.omega(), 0.0);
}

TEST(CoastSimulator, ViscousNeverStops) {
  const FrictionTerms f{1.2e-6, 0.0};
  CoastSimulator sim(f, J, 346.0);
  const double w = sim.advance(60.0);
  EXPECT_FALSE(sim.stopped());
  EXPECT_NEAR(w, 346.0 * std::exp(-1.2e-6 / J * 60.0), 1e-6);
}

TEST(CoastSimulator, AngleIsIntegralOfSpeed) {
  const FrictionTerms f{0.0, 1e-4};  // linear deceleration: θ_stop = ω0²/(2 b)
  const double b = 1e-4 / J, w0 = 300.0;
  CoastSimulator sim(f, J, w0);
  sim.advance(100.0);
  EXPECT_NEAR(sim.angle(), w0 * w0 / (2 * b), 1e-3 * w0 * w0 / (2 * b));
  EXPECT_NEAR(sim.stop_time(), w0 / b, 1e-9 * w0 / b + 1e-9);
}
