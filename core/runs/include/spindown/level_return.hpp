#pragma once
// One decision of run finding, on its own: did a coast come back to the level it began at?
// Friction only takes speed off: a coast never returns to its level. When the readings inside a
// coast, long after its cut, stand at the level it began at again — within their means' noise,
// where the coast's own pace says it must have fallen far below — no coast had begun (a drive
// hunting about its setpoint, a wheel spun by hand). Judged in the recording's own units: the
// means are over whole ripples where the coast shows one (its noise at every lag), their noise
// at least a sixth of the reading's step; the pace is a quarter of the coast's own average.
#include <cstddef>
#include <functional>
#include <optional>
#include <vector>

#include "spindown/lag_noise.hpp"
#include "spindown/sample_store.hpp"

namespace spindown {

struct LevelReturn {
  std::size_t back = 0;  // one past the last window that stood at the level: the coast is after it
  double at_level = 0;   // that window's mean
  double level = 0;      // the level the coast began at (the highest median of three early on)
  double lost = 0;       // what the coast would have lost by then, at a quarter of its own pace
  double se = 0;         // the means' noise
};

struct LevelReturnInput {
  std::size_t cut = 0;        // the coast's cut (sample index)
  std::size_t from = 0;       // its first reading that is the motor's (after a converter's top)
  std::size_t coast_end = 0;  // one past its last sample (its standstill, or where it was closed)
  double t_cut_s = 0;         // the cut's time
  double v0 = 0;              // the reading at the cut
  double step = 0;            // the reading's step (0: not quantized)
};

// The last return to the level inside the coast, or nullopt. noise(): the coast's noise at every
// lag, asked only when some window could be a return (most coasts fall far below their level at
// once); scratch: room the search may use.
std::optional<LevelReturn> level_return(const SampleStore& s, const LevelReturnInput& in,
                                        const std::function<const LagNoise&()>& coast_noise,
                                        std::vector<double>& scratch);

}  // namespace spindown
