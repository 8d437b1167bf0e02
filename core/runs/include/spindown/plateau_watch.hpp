#pragma once
// One decision of run finding, on its own: is the open "coast" holding a plateau? Friction slows a
// coast at every speed it passes, fastest at its top (its torque grows with speed), and falls with
// speed no faster than windage's ω²: at level u the coast still falls at least (u/u0)² of its rate
// at the cut's u0, which is at least its mean rate over the first three quarters of its fall to u.
// A hold window well above standstill whose slope is resolved far below a quarter of that, three
// looks in a row (a second and more), held a plateau: a drive stepping down to a lower speed under
// power (a setpoint step, a start-up overshoot settling). Judged in the coast's own units: the hold
// window's scatter about its line (at least the reading step's), the coast's own rate at its top.
// Live: looked at every half hold window while the coast goes on.
#include <cstddef>
#include <limits>
#include <optional>

#include "spindown/sample_store.hpp"
#include "spindown/window_fit.hpp"

namespace spindown {

struct Plateau {
  std::size_t from = 0;  // the hold window's first sample at the first of the three looks
  double level = 0;      // the level held (the hold window's mean)
  double rate = 0;       // how fast it fell there (a second)
  double least = 0;      // the least friction would still take off there
};

// The open coast the watch looks at.
struct PlateauCoast {
  std::size_t cut = 0;     // its cut (sample index)
  double t_cut_s = 0;      // the cut's time
  double v0 = 0;           // the reading at the cut
  double motor_zero = 0;   // the motor's reading at rest
  double noise_floor = 0;  // the least scatter a level is known to (the reading step's)
  bool one_value = false;  // every reading in the hold window the same: a frozen sensor, not a drive
};

class PlateauWatch {
 public:
  // At a coast's start: the first look at first_look_s (once the hold window is clear of the cut).
  void start(std::size_t cut, double first_look_s) {
    next_look_s_ = first_look_s;
    hits_ = 0;
    cursor_ = cut;
  }
  // When the next look is due (infinite before any coast).
  double next_look_s() const { return next_look_s_; }
  // A look at time now with the coast's hold window: the plateau, on its third hit in a row; the
  // next look every_s later.
  std::optional<Plateau> look(const SampleStore& s, const WindowFit& hold, double now, double every_s,
                              const PlateauCoast& c);

 private:
  double next_look_s_ = std::numeric_limits<double>::infinity();
  int hits_ = 0;
  std::size_t from_ = 0;    // the hold window's first sample at the first hit
  std::size_t cursor_ = 0;  // the coast's first sample within a quarter of its fall of the level held now
};

}  // namespace spindown
