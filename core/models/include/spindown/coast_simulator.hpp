#pragma once
// J·dω/dt = −T_f(ω) from ω0, with the stop event: once ω reaches 0 it stays 0 (the
// friction holds it). Integrates adaptively (RK45 with error control) and lands exactly on
// the stop; a stateful stepper for the virtual bench and a batch form for tests and fits.
#include <span>
#include <vector>

#include "spindown/friction.hpp"

namespace spindown {

class CoastSimulator {
 public:
  CoastSimulator(FrictionTerms friction, double inertia_kg_m2, double omega0);
  // Advance the coast by dt seconds (dt ≥ 0); returns ω afterwards.
  double advance(double dt);
  double omega() const { return omega_; }
  double time() const { return t_; }           // seconds since the cut
  double angle() const { return angle_; }       // rad turned since the cut (for ripple)
  bool stopped() const { return stopped_; }
  double stop_time() const { return t_stop_; }  // valid once stopped()

 private:
  FrictionTerms f_;
  double inv_j_;
  double omega_, t_ = 0, angle_ = 0, t_stop_ = 0;
  bool stopped_ = false;
};

// ω at each τ (seconds since the cut, non-decreasing).
std::vector<double> simulate_coast(const FrictionTerms& friction, double inertia_kg_m2,
                                   double omega0, std::span<const double> tau);

}  // namespace spindown
