#pragma once
// One decision of run finding, on its own: did a coast dwell? A free coast's speed falls at every
// level it passes (friction takes speed off at every speed), so it crosses a band of its own noise
// in about the time its rate takes to fall that far. A "coast" whose reading held a level (or came
// back to it) far longer than it then took to fall through four more such bands was under power
// while it held: the coast begins at the end of the dwell (a start-up overshoot that settled on
// its setpoint, taken for a cut at its peak). Judged in the recording's own units: the band is
// four times the coast's sample-to-sample noise, at least one reading step.
#include <cstddef>
#include <optional>
#include <vector>

#include "spindown/sample_store.hpp"

namespace spindown {

struct CoastDwell {
  std::size_t from = 0;  // the dwell's first sample (where the level was first reached)
  std::size_t at = 0;    // one past its last: the coast is after it
  double band = 0;       // the half-width h of the band it held (the level ± 2h)
};

struct CoastDwellInput {
  std::size_t cut = 0;        // the coast's cut (sample index)
  std::size_t coast_end = 0;  // one past its last sample
  double noise_near_cut = 0;  // the noise the cut was found in (the cheap look's margin)
  double step = 0;            // the reading's step (0: not quantized)
};

// The last dwell inside the coast, or nullopt (also for a frozen reading: one value held over
// half the dwell is a sensor, not a drive). scratch: room the search may use.
std::optional<CoastDwell> coast_dwell(const SampleStore& s, const CoastDwellInput& in, std::vector<double>& scratch);

// The cheap look first: a free coast falls at least as far in each third of its time as in the
// next; only a coast where a later third falls more than an earlier one (by margin) can dwell.
bool falls_faster_later(const SampleStore& s, std::size_t c, std::size_t e, double margin);

}  // namespace spindown
