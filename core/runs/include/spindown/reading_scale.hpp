#pragma once
// How finely a recording resolves its reading, measured from its own samples: the scale every
// judgement of run finding is made in. A rise, a level, a jump or a stop is evidence only when it
// stands out in these units (the reading's step, its sample-to-sample noise, its noise at every
// lag, how long one printed value lasts), never in fixed fractions. Each function reads the
// samples [from, to) of a SampleStore; none changes them.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

#include "spindown/lag_noise.hpp"
#include "spindown/sample_store.hpp"

namespace spindown {

// The smallest positive change between consecutive readings: the converter's or the print's step
// on quantized readings; 0 when none changes.
double reading_step(const SampleStore& s, std::size_t from, std::size_t to);

// The sample-to-sample noise (standard deviation): 1.4826·median|Δ²v|/√6. Second differences
// cancel a smooth curve (a coast, a rise, a slow swing); 0 for fewer than 3 samples.
double rough_sd(const SampleStore& s, std::size_t from, std::size_t to);
// The same from at most 255 second differences spread evenly over [from, to): a median of that
// many is as good a scale, at a fixed cost.
double sampled_rough_sd(const SampleStore& s, std::size_t from, std::size_t to);

// The noise at every lag up to half a second (lag_noise.hpp), each lag from at most 255 second
// differences: what a rise or a step must stand above, a ripple included.
LagNoise noise_over(const SampleStore& s, std::size_t from, std::size_t to);
// The longest lag noise_over looks at: half a second of samples, 1 to 128.
std::size_t noise_max_lag(const SampleStore& s, std::size_t from, std::size_t to);

// The most readings in a row that hold one value in [from, last] (runs of `except` not counted):
// how long one printed value lasts there.
std::size_t longest_hold(const SampleStore& s, std::size_t from, std::size_t last,
                         double except = std::numeric_limits<double>::quiet_NaN());
// Whether [from, to) only flickers between printed values at most three steps apart (8 samples
// and more: a few samples of a rise can lie within three of their steps).
bool flickers(const SampleStore& s, std::size_t from, std::size_t to);
// How many readings in [from, to) lie in [lo, hi].
std::size_t count_from(const SampleStore& s, double lo, std::size_t from, std::size_t to,
                       double hi = std::numeric_limits<double>::infinity());
// The mean of readings k-1..k+1 within [lo, hi].
double smoothed(const SampleStore& s, std::size_t k, std::size_t lo, std::size_t hi);

// When the readings crossed `level` falling into sample k: interpolated between k - 1 and k, or
// t(k) when they did not fall there (or k is `first`, the coast's first sample).
double crossing_time(const SampleStore& s, std::size_t k, std::size_t first, double level);

// Medians by min and max, the same value a sort gives.
inline double median_of_three(double a, double b, double c) {
  return std::max(std::min(a, b), std::min(std::max(a, b), c));
}
inline double median_of_five(double a, double b, double c, double d, double e) {
  return median_of_three(c, std::max(std::min(a, b), std::min(d, e)), std::min(std::max(a, b), std::max(d, e)));
}
// The median of readings k-1, k, k+1 inside [c, e) (the reading itself at the span's ends).
inline double median3(const SampleStore& s, std::size_t k, std::size_t c, std::size_t e) {
  if (k <= c || k + 1 >= e) return s.v(k);
  return median_of_three(s.v(k - 1), s.v(k), s.v(k + 1));
}

// The χ² distribution's lower quantile at the standard normal quantile z, for dof degrees of
// freedom (Wilson–Hilferty: within a few percent from 3 degrees of freedom).
inline double chi2_lower_tail(double dof, double z) {
  if (dof < 1) return 0.0;
  const double c = 2.0 / (9.0 * dof);
  const double q = 1.0 - c + z * std::sqrt(c);
  return q > 0 ? dof * q * q * q : 0.0;
}
// How far a standard deviation measured from n samples may lie below the true one: the factor to
// its upper 95 % bound (1.65 for 10 samples, 1.13 for 100); 1 for fewer than 4 samples.
inline double noise_upper_bound(std::size_t n) {
  if (n < 4) return 1.0;
  const double dof = double(n - 1), lo = chi2_lower_tail(dof, -1.6448536269514722);
  return lo > 0 ? std::sqrt(dof / lo) : 1.0;
}

}  // namespace spindown
