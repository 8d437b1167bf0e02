// A coast never dwells: a free coast's speed falls at every level it passes (friction takes speed
// off at every speed), so it crosses a band of its own noise in about the time its rate takes to
// fall that far. A "coast" whose reading held a level (or came back to it) far longer than that,
// and then fell through the same span fast, was under power while it held: the coast begins at the
// end of the dwell (a start-up overshoot that settled on the setpoint, taken for a cut at its peak).
#include "run_detector_impl.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <string>

#include "run_detector_tuning.hpp"

namespace spindown {

using namespace detector_tuning;

std::size_t RunDetector::Impl::dwell_end(std::size_t c, std::size_t e, double h, std::size_t& from) {
  // Envelopes of the readings (medians of three: a single glitch makes no dwell): the lowest so far
  // from the cut (lo) and the highest from here to the coast's end (hi). A coast's level L is first
  // reached at the first k with lo(k) <= L + h and left for good after the last j with hi(j) >= L - h.
  const std::size_t n = e - c;
  double* lo = scratch(2 * n);
  double* hi = lo + n;
  const auto med3 = [&](std::size_t k) { return median3(store_, k, c, e); };
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
    const double dwell = t(c + j) - t(c + k), then = std::max(t(c + j2 + 1) - t(c + j), t(c + j + 1) - t(c + j));
    if (dwell > dwell_max_ratio * then && c + j + 1 > found) found = c + j + 1, from = c + k;
  }
  return found;
}

bool RunDetector::Impl::falls_faster_later(std::size_t c, std::size_t e, double margin) const {
  // A free coast falls at least as far in each third of its time as in the next: friction takes
  // more speed off at a higher speed (viscous, windage) or as much (Coulomb). A dwell makes an
  // earlier third fall less than a later one; only then is the coast searched for it (the search
  // would cost every run's detection a tenth more time). Stribeck friction near standstill also
  // passes here; the search then finds no dwell. Medians of three: one glitch decides nothing.
  const auto med3 = [&](std::size_t k) { return median3(store_, k, c, e); };
  const std::size_t n = e - c;
  const double v0 = med3(c), v1 = med3(c + n / 3), v2 = med3(c + 2 * n / 3), v3 = med3(e - 1);
  const double d1 = v0 - v1, d2 = v1 - v2, d3 = v2 - v3;
  return d2 > d1 + margin || d3 > d2 + margin || d3 > d1 + margin;
}

void RunDetector::Impl::recut_after_dwell(Run& r, std::size_t coast_end) {
  const std::size_t c = r.cut_index;
  if (coast_end < c + 16) return;
  // First the cheap look (the noise near the cut for a margin), then the coast's own noise.
  if (!falls_faster_later(c, coast_end, 2.0 * std::max(4.0 * coast_sd_, coast_step_))) return;
  const double h = std::max(4.0 * sampled_rough_sd(store_, c, coast_end), coast_step_);
  if (!(h > 0)) return;
  std::size_t from = c;
  const std::size_t at = dwell_end(c, coast_end, h, from);
  if (at == 0 || 2 * longest_hold(store_, from, at - 1) >= at - from) return;  // a frozen reading
  // The coast after the dwell: its cut found as any cut is, the dwell its lead-in.
  const double t_old = r.t_cut_s;
  if (!recut_from(r, at, coast_end, 1.0, 8)) return;
  const std::string said = fmt::format(
      "the reading held at {:.4g} ± {:.2g} or above from {} to {}, inside the coast taken from {}, and then fell {:.2g} "
      "times as far in a twentieth of that time or less: a coast never dwells, so the coast is taken from {} (lead-in {})",
      v(from), 2.0 * h, fmt_s(t(from)), fmt_s(t(at - 1)), fmt_s(t_old), 2.0 * dwell_fall_bands, fmt_s(r.t_cut_s),
      r.lead_in);
  run_note_ = run_note_.empty() ? said : said + "; " + run_note_;
  run_note_severity_ = Diagnostic::Severity::warning;
}

}  // namespace spindown
