#include "spindown/coast_dwell.hpp"

#include <algorithm>

#include "run_detector_tuning.hpp"
#include "spindown/reading_scale.hpp"

namespace spindown {

using namespace detector_tuning;

namespace {

// One past the last sample of the last dwell in [c, e) (bands of half-width h), or 0; from: where
// that dwell began.
std::size_t dwell_end(const SampleStore& s, std::size_t c, std::size_t e, double h, std::size_t& from, std::vector<double>& scratch) {
  // Envelopes of the readings (medians of three: a single glitch makes no dwell): the lowest so far
  // from the cut (lo) and the highest from here to the coast's end (hi). A coast's level L is first
  // reached at the first k with lo(k) <= L + h and left for good after the last j with hi(j) >= L - h.
  const std::size_t n = e - c;
  scratch.assign(2 * n, 0.0);
  double* lo = scratch.data();
  double* hi = lo + n;
  const auto med3 = [&](std::size_t k) { return median3(s, k, c, e); };
  for (std::size_t k = 0; k < n; ++k) lo[k] = std::min(k ? lo[k - 1] : med3(c), med3(c + k));
  for (std::size_t k = n; k-- > 0;) hi[k] = std::max(k + 1 < n ? hi[k + 1] : med3(e - 1), med3(c + k));
  // For each new low (level L = lo(k) − h, the band [L − h, L + h]): the dwell D from k to the last
  // j still at L − h or above, and the time T the coast then takes to fall dwell_fall_bands more
  // bands. Both pointers only move on, as the level only falls.
  std::size_t found = 0, j = 0, j2 = 0;
  for (std::size_t k = 0; k < n; ++k) {
    if (k > 0 && !(lo[k] < lo[k - 1])) continue;
    const double leave = lo[k] - 2.0 * h, fallen = leave - 2.0 * h * dwell_fall_bands;
    j = std::max(j, k);
    while (j + 1 < n && hi[j + 1] >= leave) ++j;
    j2 = std::max(j2, j);
    while (j2 + 1 < n && hi[j2 + 1] >= fallen) ++j2;
    if (j2 + 1 >= n) break;  // the coast never falls that far after this level: nor after any lower
    const double dwell = s.t(c + j) - s.t(c + k), then = std::max(s.t(c + j2 + 1) - s.t(c + j), s.t(c + j + 1) - s.t(c + j));
    if (dwell > dwell_max_ratio * then && c + j + 1 > found) found = c + j + 1, from = c + k;
  }
  return found;
}

}  // namespace

bool falls_faster_later(const SampleStore& s, std::size_t c, std::size_t e, double margin) {
  // A free coast falls at least as far in each third of its time as in the next: friction takes
  // more speed off at a higher speed (viscous, windage) or as much (Coulomb). A dwell makes an
  // earlier third fall less than a later one; only then is the coast searched for it (the search
  // would cost every run's detection a tenth more time). Stribeck friction near standstill also
  // passes here; the search then finds no dwell. Medians of three: one glitch decides nothing.
  const auto med3 = [&](std::size_t k) { return median3(s, k, c, e); };
  const std::size_t n = e - c;
  const double v0 = med3(c), v1 = med3(c + n / 3), v2 = med3(c + 2 * n / 3), v3 = med3(e - 1);
  const double d1 = v0 - v1, d2 = v1 - v2, d3 = v2 - v3;
  return d2 > d1 + margin || d3 > d2 + margin || d3 > d1 + margin;
}

std::optional<CoastDwell> coast_dwell(const SampleStore& s, const CoastDwellInput& in, std::vector<double>& scratch) {
  const std::size_t c = in.cut, coast_end = in.coast_end;
  if (coast_end < c + 16) return std::nullopt;
  // First the cheap look (the noise near the cut for a margin), then the coast's own noise.
  if (!falls_faster_later(s, c, coast_end, 2.0 * std::max(4.0 * in.noise_near_cut, in.step))) return std::nullopt;
  const double h = std::max(4.0 * sampled_rough_sd(s, c, coast_end), in.step);
  if (!(h > 0)) return std::nullopt;
  std::size_t from = c;
  const std::size_t at = dwell_end(s, c, coast_end, h, from, scratch);
  if (at == 0 || 2 * longest_hold(s, from, at - 1) >= at - from) return std::nullopt;  // a frozen reading
  return CoastDwell{from, at, h};
}

}  // namespace spindown
