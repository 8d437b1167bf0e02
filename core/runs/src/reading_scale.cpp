#include "spindown/reading_scale.hpp"

#include <vector>

namespace spindown {

double reading_step(const SampleStore& s, std::size_t from, std::size_t to) {
  double step = std::numeric_limits<double>::infinity();
  for (std::size_t k = from + 1; k < to; ++k) {
    const double d = std::abs(s.v(k) - s.v(k - 1));
    if (d > 0) step = std::min(step, d);
  }
  return std::isfinite(step) ? step : 0.0;
}

double rough_sd(const SampleStore& s, std::size_t from, std::size_t to) {
  if (to < from + 3) return 0.0;
  // The second differences in a buffer of this thread's, kept: run finding asks this several
  // times for every cut, and an allocation (and its zeroing) each time was most of the cost.
  thread_local std::vector<double> d;
  d.clear();
  d.reserve(to - from - 2);
  for (std::size_t k = from; k + 2 < to; ++k) d.push_back(std::abs(s.v(k + 2) - 2.0 * s.v(k + 1) + s.v(k)));
  std::nth_element(d.begin(), d.begin() + std::ptrdiff_t(d.size() / 2), d.end());
  return 1.4826 * d[d.size() / 2] / std::sqrt(6.0);
}

double sampled_rough_sd(const SampleStore& s, std::size_t from, std::size_t to) {
  constexpr std::size_t most = 255;
  double d[most];
  if (to < from + 3) return 0.0;
  const std::size_t triples = to - from - 2, m = std::min(triples, most);
  for (std::size_t j = 0; j < m; ++j) {
    const std::size_t k = from + j * triples / m;
    d[j] = std::abs(s.v(k + 2) - 2.0 * s.v(k + 1) + s.v(k));
  }
  std::nth_element(d, d + m / 2, d + m);
  return 1.4826 * d[m / 2] / std::sqrt(6.0);
}

std::size_t noise_max_lag(const SampleStore& s, std::size_t from, std::size_t to) {
  if (to <= from + 2) return 1;
  const double period = (s.t(to - 1) - s.t(from)) / double(to - 1 - from);
  return period > 0 ? std::size_t(std::clamp(0.5 / period, 1.0, 128.0)) : 1;
}

LagNoise noise_over(const SampleStore& s, std::size_t from, std::size_t to) {
  std::vector<double> x;
  x.reserve(to > from ? to - from : 0);
  for (std::size_t k = from; k < to; ++k) x.push_back(s.v(k));
  return measure_lag_noise(x, noise_max_lag(s, from, to), 255);
}

std::size_t longest_hold(const SampleStore& s, std::size_t from, std::size_t last, double except) {
  std::size_t longest = 1, cur = 1;
  for (std::size_t k = from + 1; k <= last; ++k) {
    cur = s.v(k) == s.v(k - 1) ? cur + 1 : 1;
    if (!(s.v(k) == except)) longest = std::max(longest, cur);
  }
  return longest;
}

bool flickers(const SampleStore& s, std::size_t from, std::size_t to) {
  if (to < from + 8) return false;
  double lo = s.v(from), hi = s.v(from);
  for (std::size_t k = from; k < to; ++k) lo = std::min(lo, s.v(k)), hi = std::max(hi, s.v(k));
  const double step = reading_step(s, from, to);
  return step > 0 && hi - lo <= 3.0 * step;
}

std::size_t count_from(const SampleStore& s, double lo, std::size_t from, std::size_t to, double hi) {
  std::size_t n = 0;
  for (std::size_t k = from; k < to; ++k) n += s.v(k) >= lo && s.v(k) <= hi;
  return n;
}

double smoothed(const SampleStore& s, std::size_t k, std::size_t lo, std::size_t hi) {
  const std::size_t from = k > lo ? k - 1 : k, to = std::min(k + 2, hi + 1);
  double sum = 0;
  for (std::size_t j = from; j < to; ++j) sum += s.v(j);
  return sum / double(to - from);
}

double crossing_time(const SampleStore& s, std::size_t k, std::size_t first, double level) {
  if (k == first) return s.t(k);
  const double va = s.v(k - 1), vb = s.v(k);
  return va > vb ? s.t(k - 1) + (s.t(k) - s.t(k - 1)) * (va - level) / (va - vb) : s.t(k);
}

}  // namespace spindown
