#pragma once
// One decision of run finding, on its own: did the reading jump inside a coast? A coast never
// rises, and never steps down far faster than its own pace: a jump means what came before it was
// no part of the coast (an open pin's swing before it was connected to the motor, a coast the power
// came back on unseen). Judged in the recording's own units: a jump is beyond eight times the
// coast's sample-to-sample noise, a twentieth of its height and three of the reading's steps;
// where the coast shows a ripple all along (a wheel's once per revolution), its level over whole
// ripples must move by more than those means' noise, and only on a coast whose means before it fall.
#include <cstddef>
#include <functional>
#include <optional>
#include <vector>

#include "spindown/lag_noise.hpp"
#include "spindown/sample_store.hpp"

namespace spindown {

struct CoastJump {
  std::size_t at = 0;          // the sample of the last jump (the coast is after it)
  double rose = 0;             // how far the reading rose there (< 0: it stepped down by -rose)
  double white = 0;            // the coast's sample-to-sample noise it was judged against
  std::size_t ripple_len = 0;  // > 0: judged over whole ripples of so many samples, where
  double ripple_shift = 0;     // the level over them moved this far
  double ripple_se = 0;        // against those means' noise
};

struct CoastJumpInput {
  std::size_t cut = 0;            // the coast's cut (sample index)
  std::size_t coast_end = 0;      // one past its last sample
  double amplitude = 0;           // its height above its zero
  double step = 0;                // the reading's step (0: not quantized)
  bool floating_lead_in = false;  // after an open pin's hum the hum may run on past the cut: no ripple test
};

// The last jump inside the coast, or nullopt. coast_noise(): the coast's noise at every lag,
// asked only when there is a jump to judge against a ripple; median5: room for the medians.
std::optional<CoastJump> coast_jump(const SampleStore& s, const CoastJumpInput& in,
                                    const std::function<const LagNoise&()>& coast_noise, std::vector<double>& median5);

}  // namespace spindown
