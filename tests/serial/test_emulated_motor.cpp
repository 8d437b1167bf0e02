// EmulatedMotor: A0's voltage on the emulated clock (powered, cut, coast, stop, rest), the
// ATmega328P's conversion, and the truth in the virtual bench's format.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

#include "spindown/coast_simulator.hpp"
#include "spindown/emulated_motor.hpp"

namespace spindown {
namespace {

EmulatedMotorOptions two_runs() {
  EmulatedMotorOptions o;
  o.runs = 2;
  o.first_run_s = 0.5;
  o.lead_in_s = 2.0;
  o.tail_s = 1.0;
  o.idle_s = 1.0;
  o.friction = {5.5e-7, 3.4e-4};
  return o;
}

TEST(EmulatedMotor, SchedulesRunsBackToBack) {
  EmulatedMotor m(two_runs());
  ASSERT_EQ(m.runs().size(), 2u);
  const auto& r1 = m.runs()[0];
  const auto& r2 = m.runs()[1];
  EXPECT_DOUBLE_EQ(r1.lead_in_s, 0.5);
  EXPECT_DOUBLE_EQ(r1.cut_s, 2.5);
  EXPECT_TRUE(r1.stopped);
  EXPECT_GT(r1.stop_s - r1.cut_s, 3.0);
  EXPECT_LT(r1.stop_s - r1.cut_s, 20.0);
  EXPECT_DOUBLE_EQ(r2.lead_in_s, r1.stop_s + 1.0 + 1.0);
  EXPECT_DOUBLE_EQ(m.end_s(), r2.stop_s + 1.0);
}

TEST(EmulatedMotor, VoltsFollowTheCoastSimulator) {
  EmulatedMotorOptions o = two_runs();
  EmulatedMotor m(o);
  const auto r1 = m.runs()[0];
  EXPECT_EQ(m.volts_at(0.2), 0.0);   // at rest
  EXPECT_EQ(m.volts_at(1.0), 0.0);   // powered, the pin reads 0 (lead-in zeros)
  EXPECT_NEAR(m.volts_at(r1.cut_s), o.e0_v, 1e-9);
  const std::vector<double> tau = {0.0, 0.5, 1.0, 2.0, 3.0};
  const auto omega = simulate_coast(o.friction, o.bench.inertia_kg_m2, r1.omega0, tau);
  for (std::size_t i = 0; i < tau.size(); ++i)
    EXPECT_NEAR(m.volts_at(r1.cut_s + tau[i]), o.bench.kb_v_s_per_rad * omega[i], 1e-9) << "tau " << tau[i];
  EXPECT_NEAR(m.volts_at(r1.cut_s), m.volts_at(r1.cut_s + 3.0), 1e-12);  // time never goes back
  EXPECT_EQ(m.volts_at(r1.stop_s + 0.01), 0.0);  // stopped
  // The second run starts at its own e0.
  EXPECT_NEAR(m.volts_at(m.runs()[1].cut_s + 1e-9), o.e0_v, 1e-3);
}

TEST(EmulatedMotor, SupplyLeadInAndNoise) {
  EmulatedMotorOptions o = two_runs();
  o.lead_in_supply = true;
  o.supply_v = 3.2;
  EmulatedMotor quiet(o);
  EXPECT_EQ(quiet.volts_at(1.0), 3.2);
  o.noise_v = 0.01;
  EmulatedMotor noisy(o);
  double sum = 0, sum2 = 0;
  const int n = 2000;
  for (int i = 0; i < n; ++i) {
    const double v = noisy.volts_at(0.6 + i * 1e-4) - 3.2;
    sum += v;
    sum2 += v * v;
  }
  EXPECT_NEAR(sum / n, 0.0, 0.002);
  EXPECT_NEAR(std::sqrt(sum2 / n), 0.01, 0.002);
}

TEST(EmulatedMotor, ConvertsLikeAnIdealAtmegaAdc) {
  EmulatedMotor m(two_runs());
  const double lsb = 5.0 / 1024;
  EXPECT_EQ(m.counts_for(0.0), 0);
  EXPECT_EQ(m.counts_for(0.49 * lsb), 0);   // first transition at ½ LSB
  EXPECT_EQ(m.counts_for(0.51 * lsb), 1);
  EXPECT_EQ(m.counts_for(2.8), 573);        // 2.8·1024/5 = 573.44
  EXPECT_EQ(m.counts_for(-0.2), 0);
  EXPECT_EQ(m.counts_for(7.0), 1023);
  EXPECT_EQ(m.convert(0.1), 0);
  EXPECT_EQ(m.conversions(), 1);
}

TEST(EmulatedMotor, TruthStampsCutsWithTheBootBeforeThem) {
  EmulatedMotor m(two_runs());
  const auto r1 = m.runs()[0];
  const auto r2 = m.runs()[1];
  // Booted at 0; reset mid-coast of run 1; a reboot between the runs.
  const double mid = r1.cut_s + 1.0, between = r1.stop_s + 0.5;
  const auto t = m.truth_json({0.0, mid, between}, {{"protocol", "lab-tsv"}, {"samples", 42}});
  EXPECT_EQ(t["protocol"], "lab-tsv");
  EXPECT_EQ(t["samples"], 42);
  EXPECT_DOUBLE_EQ(t["c_v"].get<double>(), 5.5e-7);
  EXPECT_DOUBLE_EQ(t["c_c"].get<double>(), 3.4e-4);
  ASSERT_EQ(t["resets"].size(), 2u);
  EXPECT_EQ(t["resets"][0]["epoch"], 1);
  ASSERT_EQ(t["runs"].size(), 2u);
  EXPECT_EQ(t["runs"][0]["cut_epoch"], 0);
  EXPECT_EQ(t["runs"][0]["cut_device_us"], std::llround(r1.cut_s * 1e6));
  EXPECT_TRUE(t["runs"][0]["reset_mid_coast"].get<bool>());
  EXPECT_EQ(t["runs"][1]["cut_epoch"], 2);
  EXPECT_EQ(t["runs"][1]["cut_device_us"], std::llround((r2.cut_s - between) * 1e6));
  EXPECT_FALSE(t["runs"][1]["reset_mid_coast"].get<bool>());
}

TEST(EmulatedMotor, RejectsBadOptions) {
  EmulatedMotorOptions o = two_runs();
  o.runs = 0;
  EXPECT_THROW(EmulatedMotor{o}, std::invalid_argument);
  o = two_runs();
  o.friction.viscous = std::nan("");
  EXPECT_THROW(EmulatedMotor{o}, std::invalid_argument);
  o = two_runs();
  o.e0_v = 1.0;
  o.e0_step_v = -2.0;
  EXPECT_THROW(EmulatedMotor{o}, std::invalid_argument);
}

}  // namespace
}  // namespace spindown
