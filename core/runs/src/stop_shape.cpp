#include "spindown/stop_shape.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "run_detector_tuning.hpp"
#include "spindown/reading_scale.hpp"
#include "spindown/window_fit.hpp"

namespace spindown {

using namespace detector_tuning;

bool StopShape::creeps_in() const {
  return end_rate < stop_min_end_rate && approach_t < stop_min_approach_t && floor_t < floor_rate_min_t;
}

double end_rate(double t_cut, double t_quarter, double t_stop) {
  const double last_quarter = t_stop - t_quarter;
  return last_quarter > 0 ? 0.25 * (t_stop - t_cut) / last_quarter : std::numeric_limits<double>::infinity();
}

double approach_t_stat(const SampleStore& s, std::size_t cut, std::size_t stop, double hold_s) {
  double approach_t = std::numeric_limits<double>::infinity();
  const double t_stop = s.t(stop);
  std::size_t from = stop;
  while (from > cut && t_stop - s.t(from - 1) <= hold_s) --from;
  if (stop >= from + 3) {
    WindowFit f;
    f.clear(from, s.t(from));
    for (std::size_t j = from; j < stop; ++j) f.add(s.t(j), s.v(j));
    const double e = f.resid_sd();
    approach_t = e > 0 ? -f.slope() * std::sqrt(f.sxx()) / e : (f.slope() < 0 ? approach_t : 0.0);
  }
  return approach_t;
}

double floor_rate_t(const SampleStore& s, std::size_t from, std::size_t to, double z) {
  // The coast's fall over its last quarter as friction a + b·(height above the floor): each step
  // between neighbouring samples, −Δv = (a + b·h)·Δt by least squares. An exponential's a is 0 (its
  // rate dies with its height); a stop's is the rate it still falls at when it meets the floor.
  if (to < from + 6) return 0.0;
  double s11 = 0, s12 = 0, s22 = 0, s1y = 0, s2y = 0, syy = 0, n = 0;
  for (std::size_t j = from; j + 1 < to; ++j) {
    const double dt = s.t(j + 1) - s.t(j);
    if (!(dt > 0)) continue;
    const double x1 = dt, x2 = (0.5 * (s.v(j) + s.v(j + 1)) - z) * dt, y = s.v(j) - s.v(j + 1);
    s11 += x1 * x1, s12 += x1 * x2, s22 += x2 * x2, s1y += x1 * y, s2y += x2 * y, syy += y * y, n += 1;
  }
  const double det = s11 * s22 - s12 * s12;
  if (n < 5 || !(det > 0)) return 0.0;
  const double a = (s1y * s22 - s2y * s12) / det, b = (s11 * s2y - s12 * s1y) / det;
  const double sse = std::max(syy - a * s1y - b * s2y, 0.0);
  const double se = std::sqrt(sse / (n - 2) * s22 / det);
  return se > 0 ? a / se : (a > 0 ? std::numeric_limits<double>::infinity() : 0.0);
}

std::size_t last_quarter_index(const SampleStore& s, std::size_t cut, std::size_t first_in, double quarter) {
  std::size_t k = first_in;
  while (k > cut && s.v(k - 1) <= quarter) --k;
  return k;
}

std::size_t held_into(const SampleStore& s, std::size_t from, std::size_t to, double step) {
  // The value the coast shows last before sample to, and the first sample that shows it.
  if (to < from + 3) return to;
  const std::size_t last = to - 1;
  std::size_t held = last;
  while (held > from && s.v(held - 1) == s.v(last)) --held;
  if (held == last) return to;
  // The coast's own fall over the second before it (5 samples at least) …
  std::size_t lo = held;
  while (lo > from && (s.t(held) - s.t(lo - 1) <= 1.0 || held - lo < 5)) --lo;
  const WindowFit f = window_over(s, 1.0, lo, held);
  if (f.n < 5) return to;
  // … would have moved the reading by two of its steps there (or three of its noise) while it held.
  const double moved = std::max(-f.slope(), 0.0) * (s.t(last) - s.t(held));
  const double local_step = reading_step(s, lo, held + 1);
  return moved > std::max(2.0 * (local_step > 0 ? local_step : step), 3.0 * f.resid_sd()) ? held : to;
}

}  // namespace spindown
