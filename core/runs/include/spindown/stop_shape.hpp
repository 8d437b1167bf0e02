#pragma once
// One decision of run finding, on its own: does a coast stop, or creep into its floor? A real stop
// arrives with a finite slope (Coulomb friction keeps taking speed off to the end); an exponential
// (pure viscous friction) creeps in: its last quarter of the amplitude takes far more than a quarter
// of the coast, right before its "stop" the reading no longer falls clearly, and its rate dies with
// its height. A coast creeps in only when all three say so; it then has no stop time to fit.
// The measurements are in the recording's own units (t-statistics against the coast's scatter).
#include <cstddef>

#include "spindown/sample_store.hpp"

namespace spindown {

struct StopShape {
  double end_rate = 0;    // how fast the last quarter was crossed, relative to the coast's mean rate
  double approach_t = 0;  // the fall's t-statistic over the last hold window before the stop
  double floor_t = 0;     // the rate the coast still falls at when it meets its floor, over its standard error
  // An exponential's floor, not a stop (each of the three below what a stop shows).
  bool creeps_in() const;
};

// end_rate: a quarter of the coast's time over the time its last quarter took (1 for a Coulomb
// coast's straight line; infinite when the last quarter took no time).
double end_rate(double t_cut, double t_quarter, double t_stop);
// approach_t: the fall's t-statistic over the hold_s before sample stop of the coast cut at cut
// (infinite when fewer than three samples are there).
double approach_t_stat(const SampleStore& s, std::size_t cut, std::size_t stop, double hold_s);
// floor_t: the coast's fall over [from, to) as friction a + b·(height above the floor z), each step
// between neighbouring samples −Δv = (a + b·h)·Δt by least squares; a over its standard error.
double floor_rate_t(const SampleStore& s, std::size_t from, std::size_t to, double z);

// The first sample of the coast cut at `cut` at or below `quarter` for good before first_in.
std::size_t last_quarter_index(const SampleStore& s, std::size_t cut, std::size_t first_in, double quarter);
// The first sample of the value held up to sample to (after from) when it held longer than the
// coast's fall over the second before it allows (a sensor that holds its last reading: two of its
// steps, or three of its scatter); else to. step: the reading's step where none is seen locally.
std::size_t held_into(const SampleStore& s, std::size_t from, std::size_t to, double step);

}  // namespace spindown
