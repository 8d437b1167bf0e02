#include "spindown/level_return.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "spindown/reading_scale.hpp"

namespace spindown {

std::optional<LevelReturn> level_return(const SampleStore& s, const LevelReturnInput& in,
                                        const std::function<const LagNoise&()>& coast_noise,
                                        std::vector<double>& scratch) {
  const std::size_t c = in.cut, from = in.from, coast_end = in.coast_end;
  if (coast_end < c + 24 || !(in.v0 > 0) || from >= coast_end) return std::nullopt;
  double top = s.v(from < coast_end ? from : c);
  for (std::size_t k = from; k < coast_end; ++k) top = std::max(top, s.v(k));
  // The scan over means of len readings, their noise se: the last window [back - len, back) that
  // stands back at the coast's level, where it must have lost `lost`; back 0 when none does. With
  // se 0, whether any window could for some noise: a return needs lost > 10 se and a mean above
  // level - 3 se, so above level - 0.3 lost, and se is at least a sixth of the reading's step.
  std::size_t back = 0;
  double at_level = 0, lost = 0, level = 0;
  // The highest reading of each block of 64 from `from` (block_v[b]: readings from + 64 b …), and
  // the highest over the blocks that hold the readings [from + lo, from + hi): a bound on the mean
  // of any window there. (Times only grow in the store: a clock going back restarts it.)
  constexpr std::size_t block = 64;
  double* block_v = nullptr;  // scratch: the blocks' highest readings
  const auto block_max = [&](std::size_t lo, std::size_t hi) {
    double x = block_v[lo / block];
    for (std::size_t i = lo / block + 1; i <= (hi - 1) / block; ++i) x = std::max(x, block_v[i]);
    return x;
  };
  const auto scan = [&](std::size_t len, double se) {
    back = 0;
    if (coast_end < from + 4 * len) return;
    double sum = 0;
    for (std::size_t k = from; k < from + len; ++k) sum += s.v(k);
    // The level the coast began at, read from its first samples (not the cut's line, which a bounce
    // pulls down and a line fitted to a curve lifts): the highest median of three over its first
    // two windows (a contact's bounce at the connection reads low, a glitch alone decides nothing).
    level = -std::numeric_limits<double>::infinity();
    for (std::size_t k = from + 1; k + 1 < std::min(from + 2 * len, coast_end); ++k)
      level = std::max(level, median_of_three(s.v(k - 1), s.v(k), s.v(k + 1)));
    // The coast's own pace: its whole fall (to the mean of its last samples: its standstill, or
    // where a coast that did not stop was closed) over its whole time, a quarter of it at most
    // early on (Stribeck friction, strongest near standstill, makes a coast's start its slowest part).
    double last = 0;
    for (std::size_t k = coast_end - len; k < coast_end; ++k) last += s.v(k);
    last /= double(len);
    const double span_s = 0.5 * (s.t(coast_end - len) + s.t(coast_end - 1)) - in.t_cut_s;
    if (!(span_s > 0)) return;
    const double least_rate = 0.25 * std::max(level - last, 0.0) / span_s;
    if (se == 0) {  // the same test, rearranged, with a margin for the rounding of sums
      // With s = s.t(k) + s.t(k + len - 1) and the window's sum: should = rate·s − least_rate·s.t(from),
      // so "sum ≥ n (level − 0.3 should) and should > least" is "sum + 0.3 n rate s ≥ K and s > S",
      // K and S the same for every window.
      const double n = double(len), rate = 0.5 * least_rate, least = 10.0 * in.step / 6.0;
      if (!(rate > 0)) return;
      const double c0 = least_rate * s.t(from), kappa = 0.3 * n * rate;
      const double margin = 1e-9 * n * (std::abs(level) + std::abs(in.v0) + std::abs(kappa * s.t(coast_end - 1)));
      const double K = n * level + 0.3 * n * c0 - margin, S = (least + c0) / rate;
      const double S_low = S - 1e-12 * std::abs(S);
      // Windows a block at a time: none in a block passes when even its highest reading, as every
      // reading of a window, and its latest times fall short (most of a coast, far below its level).
      const std::size_t m = coast_end - from;
      for (std::size_t j0 = 0; j0 + len <= m; j0 += block) {
        const std::size_t j1 = std::min(j0 + block, m - len + 1);  // the windows [from + j, from + j + len), j0 ≤ j < j1
        const double s_hi = s.t(from + j1 - 1) + s.t(from + j1 + len - 2);
        if (!(s_hi > S_low) || n * block_max(j0, j1 + len - 1) + kappa * s_hi + margin < K) continue;
        double sum_j = 0;
        for (std::size_t k = from + j0; k < from + j0 + len; ++k) sum_j += s.v(k);
        for (std::size_t k = from + j0;; ++k) {  // the window [k, k + len)
          const double s_k = s.t(k) + s.t(k + len - 1);
          if (sum_j + kappa * s_k >= K && s_k > S_low) {
            back = k + len;
            return;
          }
          if (k + 1 >= from + j1) break;
          sum_j += s.v(k + len) - s.v(k);
        }
      }
      return;
    }
    for (std::size_t k = from;; ++k) {  // the window [k, k + len)
      const double mean = sum / double(len);
      const double should = least_rate * (0.5 * (s.t(k) + s.t(k + len - 1)) - s.t(from));  // lost since the level was read
      if (should > 10.0 * se && mean >= level - 3.0 * se &&
                 2 * count_from(s, top - in.step, k, k + len) < len && 2 * count_from(s, s.v(k), k, k + len, s.v(k)) <= len) {
        // Where the coast must have lost ten of its means' noise, it stands within three of the
        // cut's level — and not mostly within a reading step of the coast's highest reading (a
        // converter's top, read until the back-EMF comes below it) or on one repeated value (a stall).
        back = k + len, at_level = mean, lost = should;
      }
      if (k + len >= coast_end) break;
      sum += s.v(k + len) - s.v(k);
    }
  };
  // The means are over whole ripples where the coast shows one (a wheel's once per revolution, a
  // drive's hunting: 2 to 256 readings, twice the lag of the largest noise up to half a second),
  // else over five readings. Most coasts fall well below their level at every length: then their
  // noise (most of this search's time) is not needed.
  const std::size_t mid = c + (coast_end - c) / 2;
  const std::size_t max_len = 2 * std::max(noise_max_lag(s, c, mid), noise_max_lag(s, mid, coast_end));
  if (coast_end < from + 20) return std::nullopt;
  scratch.assign((coast_end - from + block - 1) / block, 0.0);
  block_v = scratch.data();
  for (std::size_t b = 0, k = from; k < coast_end; ++b) {
    double x = s.v(k);
    for (const std::size_t e = std::min(k + block, coast_end); ++k < e;) x = std::max(x, s.v(k));
    block_v[b] = x;
  }
  bool could = false;
  for (std::size_t len = 5; len <= std::max<std::size_t>(max_len, 5) && !could; len = len == 5 ? 8 : 2 * len) {
    scan(len, 0.0);
    could = back != 0;
  }
  if (!could) return std::nullopt;
  // The means' noise (or a sixth of the print's step: a level read in whole steps is known no better).
  const LagNoise& noise = coast_noise();
  const bool rippled = noise.wander > 2.0 * noise.white;
  const std::size_t len = rippled ? std::max<std::size_t>(5, 2 * noise.wander_lag) : 5;
  if (coast_end < c + 4 * len) return std::nullopt;
  const double se =
      std::max((rippled ? noise.wander : noise.white) / std::sqrt(double(len)), in.step / 6.0);
  if (!(se > 0)) return std::nullopt;
  scan(len, se);
  if (back == 0) return std::nullopt;
  return LevelReturn{back, at_level, level, lost, se};
}

}  // namespace spindown
