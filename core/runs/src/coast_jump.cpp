#include "spindown/coast_jump.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "spindown/reading_scale.hpp"

namespace spindown {

std::optional<CoastJump> coast_jump(const SampleStore& s, const CoastJumpInput& in,
                                    const std::function<const LagNoise&()>& coast_noise, std::vector<double>& median5) {
  const std::size_t c = in.cut, coast_end = in.coast_end;
  if (coast_end < c + 16) return std::nullopt;
  const double amp = in.amplitude;
  // A jump is far beyond the coast's sample-to-sample noise (below) and at least `least`: a
  // twentieth of the coast's height and three steps of the print.
  const double least = std::max(0.05 * std::abs(amp), 3.0 * in.step);
  // The cheap look first. A median of five lies between the lowest and the highest of its
  // readings, so a rise of the medians by more than `least`, or a step down within three samples,
  // needs a reading more than `least` above one at most seven samples after it or anywhere before
  // it. Most coasts have none: then no median is taken. One pass back from the end: `highest` is
  // the highest reading from seven before q on.
  {
    double highest = -std::numeric_limits<double>::infinity();
    for (std::size_t p = coast_end - 7; p < coast_end; ++p) highest = std::max(highest, s.v(p));
    bool could = false;
    for (std::size_t q = coast_end; q-- > c && !could;) {
      if (q >= c + 7) highest = std::max(highest, s.v(q - 7));
      could = highest - s.v(q) > least;
    }
    if (!could) return std::nullopt;
  }
  // Medians of five: a dropout or two (a loose wire's zeros) are neither a rise nor a step down.
  // Each sample's is taken once: both searches below read it, three times a sample (a sort of
  // five per look was a third of `spindown fit`'s time).
  median5.resize(coast_end - c);
  for (std::size_t k = c + 2; k + 2 < coast_end; ++k)
    median5[k - c] = median_of_five(s.v(k - 2), s.v(k - 1), s.v(k), s.v(k + 1), s.v(k + 2));
  const auto med5 = [&](std::size_t k) { return median5[k - c]; };
  // The last rise of more than thr above the lowest reading before it, or a later step down.
  const auto last_jump = [&](double thr, double& rose) {
    double low = std::numeric_limits<double>::infinity(), rose_from = 0;
    std::size_t rise = 0;
    for (std::size_t k = c + 2; k + 2 < coast_end; ++k) {
      const double m = med5(k);
      if (m - low > thr) {
        if (rise == 0 || k > rise + 1) rose_from = low;
        rise = k, rose = m - rose_from, low = m;
      } else {
        low = std::min(low, m);
      }
    }
    // A step down: a fall within three samples far steeper than the coast's own pace on either
    // side of it (an open pin above the back-EMF, then connected to the motor).
    if (coast_end >= c + 24) {
      for (std::size_t k = c + 10; k + 10 < coast_end; ++k) {
        const double drop = med5(k - 2) - med5(k + 1);
        if (!(drop > thr)) continue;
        const double before = (med5(k - 8) - med5(k - 2)) / (s.t(k - 2) - s.t(k - 8));
        const double after = (med5(k + 1) - med5(k + 7)) / (s.t(k + 7) - s.t(k + 1));
        const double pace = std::max({before, after, 0.0}) * (s.t(k + 1) - s.t(k - 2));
        if (drop > 4.0 * pace + thr && k > rise) rise = k - 1, rose = -drop;
      }
    }
    return rise;
  };
  // A jump is far beyond the coast's sample-to-sample noise (the median over the whole coast: a
  // rough stretch before the rise, an open pin's hum, does not set it), a twentieth of the coast's
  // height and three steps of the print. Most coasts have no jump even of that least size: then
  // the noise (a median over the whole coast, most of this search's time) is not needed, as a
  // higher threshold finds no jump where a lower one found none.
  double rose = 0;
  if (last_jump(least, rose) == 0) return std::nullopt;
  const double white = rough_sd(s, c, coast_end);
  const std::size_t rise = last_jump(std::max(8.0 * white, least), rose);
  if (rise == 0) return std::nullopt;
  CoastJump jump{rise, rose, white};
  // A ripple (a wheel's once per revolution, a commutator's) moves neighbouring samples together:
  // its crests stand above its troughs by far more than the sample-to-sample noise says. Where the
  // coast shows one all along (the smaller of its two halves': an open pin's hum before a
  // connection is in one of them only), a rise or a step is evidence only when the level over a
  // whole ripple after it stands apart from the level over a whole ripple before it, by more than
  // those means' own noise allows.
  // (After a floating lead-in the hum may go on past the cut found: a rise there is the connection,
  // and the coast's noise is not asked.)
  const LagNoise* noise_p = !in.floating_lead_in ? &coast_noise() : nullptr;
  if (noise_p && noise_p->wander > 2.0 * noise_p->white) {
    const LagNoise& noise = *noise_p;
    const std::size_t len = std::max<std::size_t>(5, 2 * noise.wander_lag);
    if (rise < c + len || rise + len > coast_end) return std::nullopt;
    double before = 0, after = 0;
    for (std::size_t k = rise - len; k < rise; ++k) before += s.v(k);
    for (std::size_t k = rise; k < rise + len; ++k) after += s.v(k);
    const double shift = (after - before) / double(len);
    const double se = noise.wander * std::sqrt(2.0 / double(len));
    // … and only on a coast: the means over whole ripples before the rise fall, each within those
    // means' noise of the one before (an open pin's swing rises and falls by far more).
    bool falls = true;
    double prev = std::numeric_limits<double>::infinity();
    for (std::size_t k0 = c; k0 + len <= rise && falls; k0 += len) {
      double m = 0;
      for (std::size_t k = k0; k < k0 + len; ++k) m += s.v(k);
      m /= double(len);
      falls = m <= prev + 4.0 * se;
      prev = m;
    }
    if (falls) {
      const double moved = rose > 0 ? shift : -shift;  // in the jump's own direction
      if (!(moved > std::max(4.0 * se, least))) return std::nullopt;
      jump.ripple_len = len, jump.ripple_shift = shift, jump.ripple_se = se;
    }
  }
  return jump;
}

}  // namespace spindown
