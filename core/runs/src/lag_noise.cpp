#include "spindown/lag_noise.hpp"

#include <algorithm>
#include <cmath>

namespace spindown {

namespace {

// 1.4826·MAD/√6 of the lag-s second differences of v (at most max_terms of them, spread evenly).
double lag_noise(const std::vector<double>& v, std::size_t s, std::size_t max_terms, std::vector<double>& d) {
  const std::size_t n = v.size();
  if (n < 2 * s + 3) return 0.0;
  const std::size_t terms = n - 2 * s;
  const std::size_t stride = std::max<std::size_t>(1, terms / max_terms);
  d.clear();
  for (std::size_t k = 0; k < terms; k += stride) d.push_back(v[k + 2 * s] - 2.0 * v[k + s] + v[k]);
  const auto mid = d.begin() + std::ptrdiff_t(d.size() / 2);
  std::nth_element(d.begin(), mid, d.end());
  const double centre = *mid;
  for (double& x : d) x = std::abs(x - centre);
  std::nth_element(d.begin(), mid, d.end());
  return 1.4826 * *mid / std::sqrt(6.0);
}

}  // namespace

LagNoise measure_lag_noise(const std::vector<double>& v, std::size_t max_lag, std::size_t max_terms) {
  LagNoise r;
  std::vector<double> d;
  d.reserve(std::min(v.size(), max_terms + 1));
  r.white = lag_noise(v, 1, max_terms, d);
  r.wander = r.white;
  for (std::size_t s = 2; s <= max_lag && v.size() >= 2 * s + 8; s *= 2) {
    const double x = lag_noise(v, s, max_terms, d);
    if (x > r.wander) r.wander = x, r.wander_lag = s;
  }
  return r;
}

}  // namespace spindown
