#pragma once
// One decision of run finding, on its own: did the sensor give up before the motor stopped?
// A per-revolution pulse, an encoder or a display stops updating at low speed: its reading holds
// its last value for longer than the coast's own fall allows, then collapses to zero in one
// sample. A lab stop's last printed values (0.02, 0.01 on a 2-decimal print) are neither.
// Judged in the recording's own units: the coast's fall per sample over the second before the
// held value, its scatter about that line, the reading's step.
#include <cstddef>
#include <optional>

#include "spindown/sample_store.hpp"

namespace spindown {

struct SignalLoss {
  std::size_t held = 0;  // the first sample of the held value (the coast is fitted up to it)
  double level = 0;      // the held value
  double last = 0;       // the coast's last reading before the standstill
  double fall = 0;       // how far friction lets the reading fall in one sample there
};

struct SignalLossInput {
  std::size_t cut = 0;       // the coast's cut (sample index)
  std::size_t first_in = 0;  // the standstill's first sample
  double zero_level = 0;     // the standstill's level
  double amplitude = 0;      // the coast's height above it
  double motor_zero = 0;     // the motor's zero (the lead-in's, when it showed it)
  double step = 0;           // the reading's step (0: not quantized)
};

// The loss, when the coast [cut, first_in) ended so; nullopt when it stopped as a coast does.
std::optional<SignalLoss> signal_loss(const SampleStore& s, const SignalLossInput& in);

}  // namespace spindown
