#pragma once
// Readings as a device records them, for the tests of run finding's decisions: v(t) sampled at
// 50 Hz (the lab's) from 0 s to `until`, white noise sigma added, printed to `step` (0: not
// rounded), into a SampleStore; and the sample at a time.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <random>

#include "spindown/sample_store.hpp"

namespace spindown::test {

inline constexpr double lab_period_s = 0.02;

template <class F>
SampleStore record(F v, double until, double sigma, double step = 0.0, std::uint64_t seed = 7) {
  SampleStore s;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  for (double t = 0; t < until - 1e-9; t += lab_period_s) {
    double x = v(t) + (sigma > 0 ? sigma * noise(rng) : 0.0);
    if (step > 0) x = std::round(x / step) * step;
    s.push({t, x});
  }
  return s;
}

// The index of the sample at time t.
inline std::size_t at(double t) { return static_cast<std::size_t>(std::lround(t / lab_period_s)); }

}  // namespace spindown::test
