#pragma once
// Simulating any combination of effects from the library at the measured sample times:
// J·dω/dt = −ΣT(ω) from ω0 at the cut, with the stop event (ω stays 0 once the friction at
// standstill can hold it), reading = k·ω + Σ sensor terms. Closed form when the torque is
// viscous and/or Coulomb only; otherwise fixed-step RK4 on the sample grid (sub-stepped to
// max_step_s) that lands on the stop exactly by quadrature of dt = dω/(T(ω)/J).
// Optionally returns the exact sensitivities d reading/dθ (forward sensitivity equations),
// which the output-error fit uses as its Jacobian.
#include <limits>
#include <span>
#include <vector>

#include "spindown/effects.hpp"
#include "spindown/friction.hpp"

namespace spindown {

class EffectSimulator {
 public:
  static constexpr int max_params = 12;

  // k = reading per rad/s (K_b for volts, 1 for rad/s, 60/2π for rpm).
  EffectSimulator(std::vector<const Effect*> effects, double reading_per_rad_s);

  // θ = [ω0 (rad/s), then each effect's parameters in order, internal units (see effects.hpp)].
  int size() const { return size_; }
  const std::vector<const Effect*>& effects() const { return effects_; }
  int first_param(std::size_t effect_index) const { return first_[effect_index]; }
  bool closed_form() const { return closed_; }
  double reading_per_rad_s() const { return k_; }

  // Readings at τ (seconds since the cut, non-decreasing). jac, when not empty, receives the
  // n×size() row-major matrix d reading_i/dθ_j.
  void simulate(std::span<const double> theta, std::span<const double> tau, std::span<double> reading,
                std::span<double> jac = {}) const;
  // Speed only (rad/s), no sensor terms.
  std::vector<double> omega(std::span<const double> theta, std::span<const double> tau) const;

  // Total T/J (rad/s²) at ω for θ; predicted stop in seconds after the cut (inf if never).
  double rate(std::span<const double> theta, double omega) const;
  double stop_time(std::span<const double> theta) const;

  // Integrator: absolute error per step in ω, as a fraction of ω0 (readings' noise is
  // absolute), and the largest step in seconds.
  double tolerance = 1e-10;
  double max_step_s = std::numeric_limits<double>::infinity();

 private:
  struct Deriv {
    double r = 0, r_w = 0;
    double r_p[max_params] = {};
  };
  void eval(std::span<const double> theta, double omega, Deriv& d, bool with_params) const;
  double time_to_stop(std::span<const double> theta, double omega) const;
  // The ODE path of simulate(): finish(i, ω, ∂ω/∂θ) for every sample i in order.
  template <class Finish>
  void integrate(std::span<const double> theta, std::span<const double> tau, bool want_jac, Finish& finish) const;

  std::vector<const Effect*> effects_;
  std::vector<int> first_;
  int size_ = 1;
  double k_ = 1;
  bool closed_ = false;
  int viscous_ = -1, coulomb_ = -1;  // θ index of the closed-form parameters, or −1
  std::vector<std::size_t> sensors_;  // indices of the sensor effects (added per sample)
};

// Internal θ for friction given in SI (FrictionTerms) on a model of viscous, coulomb,
// stribeck and windage, for comparing with CoastSimulator and for tests.
std::vector<const Effect*> friction_effects(const FrictionTerms& f);
std::vector<double> friction_theta(const FrictionTerms& f, double inertia_kg_m2, double omega0);

}  // namespace spindown
