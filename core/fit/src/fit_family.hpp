#pragma once
// The friction models' fits, inside: the one family the three lab models belong to, its
// parameters and its closed form. Private to spindown_fit, as is everything in namespace
// spindown::friction.
#include <cmath>
#include <limits>

#include "spindown/fit.hpp"
#include "spindown/phi_function.hpp"

namespace spindown::friction {

inline constexpr double inf = std::numeric_limits<double>::infinity();
inline constexpr double nan = std::numeric_limits<double>::quiet_NaN();

// The three lab models are one family in reading units (r = k·ω above the zero level):
//   r(τ) = max(0, u0·e^(−ατ) − β·τ·φ(ατ)),  φ(x) = (1 − e^(−x))/x,
// with α = c_viscous/J (1/s) and β = k·c_coulomb/J (reading/s). viscous: β = 0; coulomb:
// α = 0; combined: both free. Once r reaches 0 it stays 0: for α, β ≥ 0 the closed form is
// decreasing, so clamping at zero is exactly the stop.
struct Family {
  bool alpha_free, beta_free;
  int size() const { return 1 + alpha_free + beta_free; }
};

inline Family family_of(ModelKind k) {
  switch (k) {
    case ModelKind::viscous: return {true, false};
    case ModelKind::coulomb: return {false, true};
    case ModelKind::combined: return {true, true};
  }
  return {true, true};
}

struct Theta {
  double u0 = 0, alpha = 0, beta = 0;
};

inline Theta unpack(const Family& f, const double* x) {
  Theta th;
  int i = 0;
  th.u0 = x[i++];
  if (f.alpha_free) th.alpha = x[i++];
  if (f.beta_free) th.beta = x[i++];
  return th;
}

// Model reading at τ and, when grad is given, its partial derivatives (zero once stopped).
inline double reading(const Family& f, const Theta& th, double tau, double* grad) {
  const double x = th.alpha * tau;
  const double e = std::exp(-x);
  double p, dp;
  phi(x, e, p, dp);
  const double m = th.u0 * e - th.beta * tau * p;
  const bool moving = m > 0;
  if (grad) {
    int i = 0;
    grad[i++] = moving ? e : 0.0;
    if (f.alpha_free) grad[i++] = moving ? (-th.u0 * tau * e - th.beta * tau * tau * dp) : 0.0;
    if (f.beta_free) grad[i++] = moving ? -tau * p : 0.0;
  }
  return moving ? m : 0.0;
}

inline double stop_time(const Theta& th) {
  if (th.beta <= 0) return inf;
  if (th.alpha <= 1e-12) return th.u0 / th.beta;
  return std::log1p(th.alpha * th.u0 / th.beta) / th.alpha;
}

}  // namespace spindown::friction
