// The scale run finding judges evidence in, measured from a recording's own readings: its step,
// its sample-to-sample noise, its noise at every lag (a ripple), how long a value holds.
#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <random>

#include "spindown/reading_scale.hpp"

using namespace spindown;

namespace {

// A coast's line at 50 Hz, with white noise sigma, a ripple of amplitude ripple and period
// ripple_s, printed to `step` (0: not rounded).
SampleStore coast(std::size_t n, double sigma, double step = 0.0, double ripple = 0.0, double ripple_s = 1.0) {
  SampleStore s;
  std::mt19937_64 rng(42);
  std::normal_distribution<double> noise(0.0, 1.0);
  for (std::size_t i = 0; i < n; ++i) {
    const double t = 0.02 * double(i);
    double v = 2.8 - 0.05 * t + sigma * noise(rng) + ripple * std::sin(2 * M_PI * t / ripple_s);
    if (step > 0) v = std::round(v / step) * step;
    s.push({t, v});
  }
  return s;
}

}  // namespace

TEST(ReadingScale, TheStepOfATwoDecimalPrintIsItsLastDigit) {
  const SampleStore s = coast(1500, 0.004, 0.01);
  EXPECT_NEAR(reading_step(s, 0, s.end()), 0.01, 1e-9);
  EXPECT_EQ(reading_step(coast(50, 0.0, 0.0), 0, 1), 0.0);  // one sample: no change seen
}

TEST(ReadingScale, TheSampleToSampleNoiseIgnoresTheCoastsLine) {
  SampleStore s = coast(3000, 0.01);
  EXPECT_NEAR(rough_sd(s, 0, s.end()), 0.01, 0.001);
  EXPECT_NEAR(sampled_rough_sd(s, 0, s.end()), 0.01, 0.0015);
  EXPECT_EQ(rough_sd(s, 0, 2), 0.0);
}

TEST(ReadingScale, ARippleIsNoiseAtItsHalfPeriodThatTheWhiteNoiseDoesNotSee) {
  // A wheel's once per revolution: 0.05 amplitude at 4 Hz (12.5 samples), white noise 0.003.
  const SampleStore s = coast(3000, 0.003, 0.0, 0.05, 0.25);
  const LagNoise n = noise_over(s, 0, s.end());
  EXPECT_NEAR(n.white, 0.003 * 1.0, 0.003);  // the ripple bends the line a little at lag 1
  EXPECT_GT(n.wander, 10.0 * n.white);
  EXPECT_GE(n.wander_lag, 4u);
  EXPECT_LE(n.wander_lag, 8u);  // about its half period, 6 samples
  EXPECT_EQ(noise_max_lag(s, 0, s.end()), 25u);  // half a second at 50 Hz
  const LagNoise plain = noise_over(coast(3000, 0.003), 0, 3000);
  EXPECT_LT(plain.wander, 2.0 * plain.white);
}

TEST(ReadingScale, HoldsFlickersCountsAndMedians) {
  SampleStore s;
  for (double v : {1.0, 1.0, 1.0, 1.01, 1.0, 1.01, 1.01, 1.0, 1.0, 1.0, 1.0, 0.99}) s.push({0.0, v});
  EXPECT_EQ(longest_hold(s, 0, s.end() - 1), 4u);
  EXPECT_EQ(longest_hold(s, 0, s.end() - 1, 1.0), 2u);  // runs of 1.0 not counted
  EXPECT_TRUE(flickers(s, 0, s.end()));                  // 0.99 … 1.01: two steps
  EXPECT_EQ(count_from(s, 1.0, 0, s.end()), 11u);
  EXPECT_EQ(count_from(s, 1.0, 0, s.end(), 1.0), 8u);
  EXPECT_DOUBLE_EQ(median3(s, 3, 0, s.end()), 1.0);  // 1.0, 1.01, 1.0
  EXPECT_DOUBLE_EQ(median3(s, 0, 0, s.end()), 1.0);  // the span's end: the reading itself
  EXPECT_NEAR(smoothed(s, 5, 0, s.end() - 1), (1.0 + 1.01 + 1.01) / 3.0, 1e-12);
  SampleStore rise;
  for (int i = 0; i < 20; ++i) rise.push({0.0, 0.01 * i});
  EXPECT_FALSE(flickers(rise, 0, rise.end()));
}

TEST(ReadingScale, ANoiseMeasuredFromFewReadingsMayLieWellBelowTheTruth) {
  EXPECT_NEAR(noise_upper_bound(10), 1.65, 0.03);
  EXPECT_NEAR(noise_upper_bound(100), 1.13, 0.01);
  EXPECT_EQ(noise_upper_bound(3), 1.0);
  // The bound holds for about 95 % of windows of 10 readings of unit noise.
  std::mt19937_64 rng(7);
  std::normal_distribution<double> g(0.0, 1.0);
  int below = 0;
  for (int w = 0; w < 4000; ++w) {
    double x[10], m = 0, ss = 0;
    for (double& v : x) m += (v = g(rng)) / 10.0;
    for (double v : x) ss += (v - m) * (v - m);
    below += std::sqrt(ss / 9.0) * noise_upper_bound(10) < 1.0;
  }
  EXPECT_NEAR(below / 4000.0, 0.05, 0.015);
}
