// The reading's own noise: white noise reads the same at every lag; a ripple that moves
// neighbouring samples together is seen at its half period, far above the lag-1 noise; a coast's
// steady bend is no noise; a stretch of another kind over part of the range does not set it.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "spindown/lag_noise.hpp"

namespace spindown {
namespace {

TEST(LagNoise, WhiteNoiseReadsTheSameAtEveryLag) {
  std::mt19937 rng(41);
  std::normal_distribution<double> e(0, 0.5);
  std::vector<double> v;
  for (int k = 0; k < 5000; ++k) v.push_back(300.0 - 0.01 * k + e(rng));
  const LagNoise n = measure_lag_noise(v, 128);
  EXPECT_NEAR(n.white, 0.5, 0.05);
  EXPECT_LT(n.wander, 0.6);  // the largest of seven lags' estimates of the same 0.5
}

TEST(LagNoise, ARippleIsSeenAtItsHalfPeriod) {
  // A 500 Hz wheel-speed reading with a ±12 rpm ripple of 0.2 s (100 samples) and 0.5 rpm noise
  // on a coast falling 15 rpm a second: the lag-1 noise sees the noise, the wander the ripple.
  std::mt19937 rng(42);
  std::normal_distribution<double> e(0, 0.5);
  std::vector<double> v;
  for (int k = 0; k < 8000; ++k) {
    const double t = 0.002 * k;
    v.push_back(370.0 - 15.0 * t + 12.0 * std::sin(2 * M_PI * t / 0.2) + e(rng));
  }
  const LagNoise n = measure_lag_noise(v, 250);
  EXPECT_LT(n.white, 1.0);
  EXPECT_GT(n.wander, 15.0);  // about 1.7 times the amplitude, crest to trough
  EXPECT_GE(n.wander_lag, 32u);
  EXPECT_LE(n.wander_lag, 64u);
}

TEST(LagNoise, ACoastsBendIsNoNoise) {
  // The lab's coast (3 V, τ = 10 s, every 20 ms, lags up to half a second), no noise: its second
  // differences are its bend, one sign throughout; centred on their median they stay below the
  // step of the lab's 10-bit converter (4.9 mV).
  std::vector<double> v;
  for (int k = 0; k < 1500; ++k) v.push_back(3.0 * std::exp(-0.02 * k / 10.0));
  const LagNoise n = measure_lag_noise(v, 25);
  EXPECT_LT(n.wander, 0.0049);
}

TEST(LagNoise, AHumOverAThirdOfTheRangeDoesNotSetIt) {
  std::mt19937 rng(43);
  std::normal_distribution<double> e(0, 0.01);
  std::vector<double> v;
  for (int k = 0; k < 3000; ++k) {
    const double hum = k < 1000 ? 0.3 * std::sin(2 * M_PI * k / 2.5) : 0.0;  // an open pin's mains hum
    v.push_back(2.8 - 0.0005 * k + hum + e(rng));
  }
  const LagNoise n = measure_lag_noise(v, 25);
  EXPECT_LT(n.white, 0.02);
  EXPECT_LT(n.wander, 0.03);
}

TEST(LagNoise, TooFewReadingsSayNothing) {
  EXPECT_EQ(measure_lag_noise({}, 8).white, 0.0);
  EXPECT_EQ(measure_lag_noise({1.0, 2.0}, 8).wander, 0.0);
}

}  // namespace
}  // namespace spindown
