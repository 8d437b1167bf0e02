// A slower channel logged in every row is taken once per reading; a quantized coast that changes
// from row to row where it falls fast, and a standstill read for a long time, are left as they are.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "spindown/held_readings.hpp"

namespace spindown {
namespace {

// A coast from 300 rad/s (τ = 10 s) read every `every` s, rounded to `step`, written in rows every
// `row` s; noise sd `noise` on each reading; 0 once below 5 after a 20-s coast, for `rest_s` more.
Recording held_log(double every, double row, double step, double noise, double rest_s) {
  std::mt19937 rng(4106);
  std::normal_distribution<double> e(0, noise);
  Recording rec;
  rec.source = "daq.csv";
  double reading = 300, next = 0;
  for (double t = 0; t < 20.0 + rest_s; t += row) {
    if (t >= next) {
      const double w = t < 20.0 ? 300.0 * std::exp(-t / 10.0) : 0.0;
      reading = w < 5 ? 0.0 : std::round((w + e(rng)) / step) * step;
      next += every;
    }
    rec.push(t, reading);
  }
  return rec;
}

TEST(HeldReadings, ATenHertzChannelInKilohertzRowsIsTakenOncePerReading) {
  Recording rec = held_log(0.1, 0.001, 1.0, 2.0, 10.0);
  rec.clock_restarts = {15000};  // a restart declared by a reader moves with its row
  const std::size_t rows = rec.size();
  const std::size_t dropped = take_held_readings_once(rec);
  EXPECT_EQ(rows - dropped, rec.size());
  EXPECT_NEAR(double(rec.size()), 300.0, 10.0);  // 30 s of readings every 0.1 s
  ASSERT_EQ(rec.clock_restarts.size(), 1u);
  EXPECT_NEAR(rec.t_s[rec.clock_restarts[0]], 15.0, 0.1);
  // The standstill keeps a reading every period: its last ten seconds are about 100 readings.
  std::size_t at_rest = 0;
  for (std::size_t i = 0; i < rec.size(); ++i) at_rest += rec.t_s[i] > 20.5 && rec.value[i] == 0.0;
  EXPECT_NEAR(double(at_rest), 95.0, 6.0);
  ASSERT_FALSE(rec.diagnostics.empty());
  EXPECT_NE(rec.diagnostics.back().message.find("each reading taken once"), std::string::npos);
}

TEST(HeldReadings, TheLabsTwoDecimalCoastIsLeftAsItIs) {
  // The lab's print: 3 V falling with τ = 10 s, every 20 ms, to 0.01 V, 3 mV of noise, then 5 s at
  // rest. Near its top it changes every row or two; its slow tail holds values for many rows.
  std::mt19937 rng(4107);
  std::normal_distribution<double> e(0, 0.003);
  Recording rec;
  rec.source = "putty.log";
  for (double t = 0; t < 35.0; t += 0.02) {
    const double u = t < 30.0 ? 3.0 * std::exp(-t / 10.0) : 0.0;
    rec.push(t, std::round((u + e(rng)) * 100.0) / 100.0);
  }
  const Recording before = rec;
  EXPECT_EQ(take_held_readings_once(rec), 0u);
  EXPECT_EQ(rec.t_s, before.t_s);
  EXPECT_TRUE(rec.diagnostics.empty());
}

TEST(HeldReadings, ACoarseSlowTailThatChangesEveryRowAtItsStartIsLeft) {
  // Whole rad/s at 1 kHz with no noise: the fall of 30 rad/s a second at the start changes the
  // reading every 33 rows, far from every row; but the first second of a fast coast (τ = 0.5 s)
  // does change every row, and so the channel is not held.
  Recording rec;
  rec.source = "fast.csv";
  for (double t = 0; t < 4.0; t += 0.001) rec.push(t, std::round(3000.0 * std::exp(-t / 0.5)));
  EXPECT_EQ(take_held_readings_once(rec), 0u);
}

TEST(HeldReadings, AQuantizedCoastWithoutNoiseThatHoldsEveryValueForRowsIsLeft) {
  // The lab's motor (Coulomb and viscous friction) through its 10-bit converter, printed to 2
  // decimals, no noise: every value is held 3 rows or more (0.19 V/s at the cut is 0.004 V a row)
  // and changes whenever the coast crosses the next one — at any time, not on a slower clock.
  // Before, 2 of 3 rows were dropped as "a slower channel logged in every row".
  Recording rec;
  rec.source = "sheet.csv";
  double w = 2.8 / 0.0080926;
  for (double t = 0; t < 30.0 && w > 0; t += 0.02) {
    rec.push(t, std::round(std::round(0.0080926 * w * 1023 / 5) * 5 / 1023 * 100) / 100);
    for (int k = 0; k < 20; ++k) w -= (1.8e-7 * w + 1.14e-4) / 1.127e-5 * 0.001;
  }
  ASSERT_GT(rec.size(), 1000u);
  EXPECT_EQ(take_held_readings_once(rec), 0u);
}

}  // namespace
}  // namespace spindown
