#include "spindown/signal_loss.hpp"

#include <algorithm>
#include <cmath>

#include "spindown/window_fit.hpp"

namespace spindown {

std::optional<SignalLoss> signal_loss(const SampleStore& s, const SignalLossInput& in) {
  const std::size_t cut = in.cut, first_in = in.first_in;
  const double z = in.zero_level, amp = in.amplitude;
  if (first_in < cut + 8 || !(amp > 0)) return std::nullopt;
  // The coast's last reading before the standstill, and the first sample that held it.
  const std::size_t last = first_in - 1;
  std::size_t held = last;
  while (held > cut && s.v(held - 1) == s.v(last)) --held;
  // The most friction lets the reading fall in one sample: the coast's slope over the second
  // before the held value, per period.
  std::size_t from = held;  // the second before the held value, found from its end
  while (from > cut && s.t(held) - s.t(from - 1) <= 1.0) --from;
  const WindowFit f = window_over(s, 1.0, from, held);
  if (f.n < 5) return std::nullopt;  // too few samples to know how fast friction lets it fall
  // A sensor that gives up reads zero (the motor's, when the lead-in showed it) after it.
  if (std::abs(z - in.motor_zero) > 0.05 * amp) return std::nullopt;
  const double period = s.t(first_in) - s.t(last);
  const double fall = std::max(-f.slope(), 0.0) * period;
  const double drop = s.v(last) - z;
  // A collapse: a fall far beyond the coast's, from a reading held longer than the coast allows
  // (friction would have moved it two steps), or beyond any fall the coast showed.
  const double held_for = double(first_in - held);
  const bool big_drop = drop > std::max({10.0 * fall, 6.0 * f.resid_sd(), 3.0 * in.step, 0.005 * amp});
  const bool long_hold = held_for * fall > std::max(2.0 * in.step, 3.0 * f.resid_sd());
  if (!(big_drop && (long_hold || drop > 30.0 * fall))) return std::nullopt;
  return SignalLoss{held, s.v(held), s.v(last), fall};
}

}  // namespace spindown
