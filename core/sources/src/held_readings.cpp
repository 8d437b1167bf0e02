#include "spindown/held_readings.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <vector>

namespace spindown {

namespace {

// The q-quantile of x (0 <= q <= 1) as nth_element picks it.
double quantile(std::vector<double> x, double q) {
  const auto k = std::ptrdiff_t(q * double(x.size() - 1));
  std::nth_element(x.begin(), x.begin() + k, x.end());
  return x[std::size_t(k)];
}

}  // namespace

std::size_t take_held_readings_once(Recording& rec) {
  const std::size_t n = rec.size();
  if (n < 200) return 0;
  // The rows' period.
  std::vector<double> dt;
  dt.reserve(n);
  for (std::size_t i = 1; i < n; ++i)
    if (rec.t_s[i] > rec.t_s[i - 1]) dt.push_back(rec.t_s[i] - rec.t_s[i - 1]);
  if (dt.size() < 100) return 0;
  const double row = quantile(dt, 0.5);
  if (!(row > 0)) return 0;
  // Runs of one value: their lengths (rows) and durations (s), the first and last aside.
  std::vector<double> rows, secs;
  std::size_t start = 0;
  for (std::size_t i = 1; i <= n; ++i) {
    if (i < n && rec.value[i] == rec.value[start]) continue;
    if (start > 0 && i < n) {
      rows.push_back(double(i - start));
      secs.push_back(rec.t_s[i] - rec.t_s[start]);
    }
    start = i;
  }
  if (rows.size() < 20) return 0;
  const double shortest = quantile(rows, 0.02);
  if (shortest < 3.0) return 0;
  const double period = quantile(secs, 0.25);
  if (!(period >= 3.0 * row)) return 0;
  // A slower channel changes only on its own clock: from one change to the next is a whole number
  // of its periods (one, or more when a reading repeated). A slow coast read through a coarse print
  // (2 decimals) also holds each value for rows, but steps to the next value whenever the coast
  // crosses it: the spans between its changes are any length, most not a whole number of periods.
  std::size_t whole = 0;
  for (const double d : secs) {
    const double k = d / period;
    whole += std::fabs(k - std::round(k)) <= 0.15;
  }
  if (double(whole) < 0.7 * double(secs.size())) return 0;
  // Keep the first row of each value, and one row every period within a hold.
  std::vector<std::size_t> keep;
  keep.reserve(std::size_t(double(n) * row / period) + 16);
  double last_kept = -INFINITY;
  for (std::size_t i = 0; i < n; ++i) {
    const bool changed = i == 0 || rec.value[i] != rec.value[i - 1] || rec.t_s[i] < rec.t_s[i - 1];
    if (changed || rec.t_s[i] - last_kept >= period - 0.5 * row) {
      keep.push_back(i);
      last_kept = rec.t_s[i];
    }
  }
  const std::size_t dropped = n - keep.size();
  if (dropped == 0) return 0;
  // Clock restarts move to the row kept at or after them.
  for (std::size_t& r : rec.clock_restarts)
    r = std::size_t(std::lower_bound(keep.begin(), keep.end(), r) - keep.begin());
  std::vector<double> t, v;
  t.reserve(keep.size());
  v.reserve(keep.size());
  for (std::size_t i : keep) t.push_back(rec.t_s[i]), v.push_back(rec.value[i]);
  rec.t_s = std::move(t);
  rec.value = std::move(v);
  rec.warn(0, fmt::format("the value column holds each reading for {:.0f} rows or more (a reading about every {:.3g} s in "
                          "rows every {:.3g} s: a slower channel logged in every row): each reading taken once, "
                          "{} of {} rows kept",
                          shortest, period, row, keep.size(), n));
  return dropped;
}

}  // namespace spindown
