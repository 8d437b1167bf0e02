#include "spindown/plateau_watch.hpp"

#include <algorithm>
#include <cmath>

#include "spindown/reading_scale.hpp"

namespace spindown {

std::optional<Plateau> PlateauWatch::look(const SampleStore& s, const WindowFit& h, double now, double every_s,
                                          const PlateauCoast& c) {
  next_look_s_ = now + every_s;
  bool hit = false;
  const double mu = h.mean(), u0 = c.v0 - c.motor_zero, u1 = mu - c.motor_zero;
  // The first crossing of a quarter of the fall above the plateau (the cursor only moves on: a
  // coast's level only falls, and a later crossing gives a lower rate, the safe side).
  const double near = mu + 0.25 * (c.v0 - mu);
  cursor_ = std::max(cursor_, c.cut);
  while (cursor_ < h.first && s.v(cursor_) > near) ++cursor_;
  const double e_raw = h.resid_sd(), sxx = h.sxx(), e = std::max(e_raw, c.noise_floor);
  // A reading that holds one value is a frozen sensor's, not a drive's (the standstill checks
  // judge it); a plateau under power shows its noise.
  if (h.n >= 8 && h.first > c.cut && u0 > 0 && u1 > 0.3 * u0 && !c.one_value && e_raw > 0 && sxx > 0) {
    // The coast's rate at its top is at least its mean rate over the first three quarters of its
    // fall to the plateau, a fall that stands well out of the noise and spans a few samples (a lab
    // motor's reading drops a step at the cut, its winding's transient, and then coasts slowly: a
    // mean over most of the fall is not misled by it).
    double top_rate = 0;
    if (cursor_ < h.first && cursor_ >= c.cut + 3 && c.v0 - mu > 10.0 * e) {
      const double to_near = crossing_time(s, cursor_, c.cut, near) - c.t_cut_s;
      if (to_near > 0) top_rate = 0.75 * (c.v0 - mu) / to_near;
    }
    const double ratio = std::min(u1, u0) / u0;
    const double se1 = e / std::sqrt(sxx), rate1 = -h.slope();
    const double least = 0.25 * ratio * ratio * top_rate;
    hit = least > 0 && rate1 < 0.5 * least && 2.0 * se1 <= 0.5 * least;
    if (hit && hits_++ == 0) from_ = h.first;
    if (hit && hits_ >= 3) return Plateau{from_, mu, rate1, least};
  }
  if (!hit) hits_ = 0;
  return std::nullopt;
}

}  // namespace spindown
