// The reading's noise model σ²(u) = a + b·u², estimated from a run without any model fit, and
// the fit weights built from it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "spindown/reading_noise.hpp"

using namespace spindown;

namespace {

// A 30 s coast sampled at 50 Hz (2.8 V → 0, combined friction), then 2 s at rest, with white
// noise of sd white_v and a multiplicative error of sd rel (ripple-like: grows with u).
std::vector<double> noisy_coast(double white_v, double rel, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> gauss;
  std::vector<double> y;
  const double alpha = 0.016, c = 5.06;  // u = (2.8 + c)·e^(−ατ) − c
  for (int i = 0; i < 1700; ++i) {
    const double tau = 0.02 * i;
    const double u = std::max(0.0, (2.8 + c) * std::exp(-alpha * tau) - c);
    y.push_back(u * (1.0 + rel * gauss(rng)) + white_v * gauss(rng));
  }
  return y;
}

TEST(ReadingNoise, WhiteNoiseGivesItsVarianceAndEqualWeights) {
  const std::vector<double> y = noisy_coast(0.005, 0.0, 1);
  const auto [noise, w] = weigh_by_noise(y);
  ASSERT_TRUE(noise.known);
  EXPECT_NEAR(std::sqrt(noise.variance(0.0)), 0.005, 0.0005);
  EXPECT_NEAR(std::sqrt(noise.variance(2.8)), 0.005, 0.0005);  // b ≈ 0: no growth with u
  const auto [lo, hi] = std::minmax_element(w.begin(), w.end());
  EXPECT_LT(*hi / *lo, 1.2);
}

TEST(ReadingNoise, ErrorGrowingWithTheReadingIsFound) {
  // 1 % ripple as sd 0.7 % (a sine's rms) on top of 5 mV white noise.
  const std::vector<double> y = noisy_coast(0.005, 0.007, 2);
  const auto [noise, w] = weigh_by_noise(y, 1000.0);  // no cap: the estimate itself
  ASSERT_TRUE(noise.known);
  EXPECT_NEAR(std::sqrt(noise.a), 0.005, 0.0007);
  EXPECT_NEAR(std::sqrt(noise.b), 0.007, 0.0010);
  // Weights: the quiet slow end counts more than the noisy start, and they average 1.
  EXPECT_GT(w[1400], 2.25 * w[0]);
  // Each weight is 1/σ² at the local mean ū over ±8 samples (not its square root).
  const auto local_mean = [&](std::size_t i) {
    double s = 0;
    for (std::size_t j = i - std::min<std::size_t>(i, 8); j <= std::min(i + 8, y.size() - 1); ++j) s += y[j];
    return s / static_cast<double>(std::min(i + 8, y.size() - 1) - (i - std::min<std::size_t>(i, 8)) + 1);
  };
  EXPECT_NEAR(w[1400] / w[0], noise.variance(local_mean(0)) / noise.variance(local_mean(1400)), 1e-9);
  double mean_w = 0;
  for (double wi : w) mean_w += wi / static_cast<double>(w.size());
  EXPECT_NEAR(mean_w, 1.0, 1e-9);
}

TEST(ReadingNoise, WeightRatioIsCapped) {
  const std::vector<double> y = noisy_coast(0.001, 0.02, 3);  // σ² spans ~3000× without the cap
  const auto [noise, w] = weigh_by_noise(y, 4.0);
  ASSERT_TRUE(noise.known);
  const auto [lo, hi] = std::minmax_element(w.begin(), w.end());
  EXPECT_LE(*hi / *lo, 4.0 + 1e-9);
  EXPECT_GT(*hi / *lo, 3.0);
}

TEST(ReadingNoise, TooFewOrNoiselessSamplesFitUnweighted) {
  const std::vector<double> few(20, 1.0);
  EXPECT_FALSE(weigh_by_noise(few).noise.known);
  const std::vector<double> flat(200, 0.0);  // no variance at all
  const auto [none, w] = weigh_by_noise(flat);
  EXPECT_FALSE(none.known);
  ASSERT_EQ(w.size(), flat.size());
  EXPECT_TRUE(std::all_of(w.begin(), w.end(), [](double wi) { return wi == 1.0; }));
}

}  // namespace
