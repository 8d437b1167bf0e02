#include "spindown/effect_simulator.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

#include "spindown/phi_function.hpp"

namespace spindown {
namespace {

constexpr double inf = std::numeric_limits<double>::infinity();
constexpr double nan = std::numeric_limits<double>::quiet_NaN();

// 8-point Gauss–Legendre nodes/weights on [−1, 1] (positive half).
constexpr std::array<double, 4> gl_x = {0.1834346424956498, 0.5255324099163290, 0.7966664774136267,
                                        0.9602898564975363};
constexpr std::array<double, 4> gl_w = {0.3626837833783620, 0.3137066458778873, 0.2223810344533745,
                                        0.1012285362903763};

// Dormand–Prince 5(4) (Hairer & Wanner's DOPRI5): the tableau, the error weights (5th − 4th
// order) and the coefficients of its 4th-order continuous extension (dense output).
namespace dp {
constexpr double a21 = 1.0 / 5;
constexpr double a31 = 3.0 / 40, a32 = 9.0 / 40;
constexpr double a41 = 44.0 / 45, a42 = -56.0 / 15, a43 = 32.0 / 9;
constexpr double a51 = 19372.0 / 6561, a52 = -25360.0 / 2187, a53 = 64448.0 / 6561, a54 = -212.0 / 729;
constexpr double a61 = 9017.0 / 3168, a62 = -355.0 / 33, a63 = 46732.0 / 5247, a64 = 49.0 / 176,
                 a65 = -5103.0 / 18656;
constexpr double a71 = 35.0 / 384, a73 = 500.0 / 1113, a74 = 125.0 / 192, a75 = -2187.0 / 6784, a76 = 11.0 / 84;
constexpr double e1 = 71.0 / 57600, e3 = -71.0 / 16695, e4 = 71.0 / 1920, e5 = -17253.0 / 339200, e6 = 22.0 / 525,
                 e7 = -1.0 / 40;
constexpr double d1 = -12715105075.0 / 11282082432, d3 = 87487479700.0 / 32700410799,
                 d4 = -10690763975.0 / 1880347072, d5 = 701980252875.0 / 199316789632,
                 d6 = -1453857185.0 / 822651844, d7 = 69997945.0 / 29380423;
}  // namespace dp

// The dense output of one accepted step at fraction u ∈ [0, 1] of it.
inline double dense(const double* c, std::size_t stride, double u) {
  const double v = 1.0 - u;
  return c[0] + u * (c[stride] + v * (c[2 * stride] + u * (c[3 * stride] + v * c[4 * stride])));
}

}  // namespace

EffectSimulator::EffectSimulator(std::vector<const Effect*> effects, double reading_per_rad_s)
    : effects_(std::move(effects)), k_(reading_per_rad_s) {
  bool only_closed = true;
  for (const Effect* e : effects_) {
    if (!e) throw std::invalid_argument("EffectSimulator: null effect");
    first_.push_back(size_);
    if (e->kind == EffectKind::sensor) sensors_.push_back(first_.size() - 1);
    if (e->kind == EffectKind::torque) {
      if (e->name == "viscous" && viscous_ < 0)
        viscous_ = size_;
      else if (e->name == "coulomb" && coulomb_ < 0)
        coulomb_ = size_;
      else
        only_closed = false;
    }
    size_ += e->size();
  }
  if (size_ > max_params) throw std::invalid_argument("EffectSimulator: too many parameters");
  if (!(k_ > 0) || !std::isfinite(k_)) throw std::invalid_argument("EffectSimulator: reading per rad/s must be > 0");
  closed_ = only_closed;
}

// T/J and its derivatives at ω as given: callers clamp to ω ≥ 0 where the physics needs it;
// the integrator uses the smooth continuation below 0 inside the step that reaches the stop.
void EffectSimulator::eval(std::span<const double> theta, double omega, Deriv& d, bool with_params) const {
  d.r = 0;
  d.r_w = 0;
  for (std::size_t i = 0; i < effects_.size(); ++i) {
    const Effect* e = effects_[i];
    if (e->kind != EffectKind::torque) continue;
    const int j = first_[i];
    double rw = 0;
    d.r += e->rate(theta.data() + j, omega, &rw, with_params ? d.r_p + j : nullptr);
    d.r_w += rw;
  }
}

double EffectSimulator::rate(std::span<const double> theta, double omega) const {
  Deriv d;
  eval(theta, std::max(omega, 0.0), d, false);
  return d.r;
}

// t = ∫₀^ω dw / R(w): exact time to coast from ω to rest (R(0) > 0 required).
double EffectSimulator::time_to_stop(std::span<const double> theta, double omega) const {
  const int panels = 8;
  const double hw = omega / panels / 2;
  double sum = 0;
  Deriv d;
  for (int p = 0; p < panels; ++p) {
    const double mid = (2 * p + 1) * hw;
    for (std::size_t i = 0; i < gl_x.size(); ++i) {
      eval(theta, mid - hw * gl_x[i], d, false);
      const double a = d.r;
      eval(theta, mid + hw * gl_x[i], d, false);
      sum += gl_w[i] * (1.0 / a + 1.0 / d.r);
    }
  }
  return sum * hw;
}

double EffectSimulator::stop_time(std::span<const double> theta) const {
  if (rate(theta, 0.0) <= 0) return inf;
  const double w0 = theta[0];
  if (closed_) {
    const double a = viscous_ >= 0 ? theta[viscous_] : 0.0;
    const double b = coulomb_ >= 0 ? theta[coulomb_] : 0.0;
    if (a <= 1e-12) return w0 / b;
    return std::log1p(a * w0 / b) / a;
  }
  return time_to_stop(theta, w0);
}

void EffectSimulator::simulate(std::span<const double> theta, std::span<const double> tau, std::span<double> reading,
                               std::span<double> jac) const {
  const std::size_t n = tau.size();
  const int P = size_;
  const bool want_jac = !jac.empty();
  if (theta.size() != static_cast<std::size_t>(P) || reading.size() != n ||
      (want_jac && jac.size() != n * static_cast<std::size_t>(P)))
    throw std::invalid_argument("EffectSimulator::simulate: sizes do not match");

  // Sensor terms: added to k·ω at the end (they do not depend on ω for the library's effects
  // but the interface allows it).
  auto finish = [&](std::size_t i, double w, const double* s) {
    double y = k_ * w;
    double* row = want_jac ? &jac[i * P] : nullptr;
    if (row)
      for (int j = 0; j < P; ++j) row[j] = k_ * s[j];
    for (const std::size_t e : sensors_) {
      const int j = first_[e];
      y += effects_[e]->reading(theta.data() + j, w, row ? row + j : nullptr);
    }
    reading[i] = y;
  };

  double s[max_params] = {};
  if (closed_) {
    const double a = viscous_ >= 0 ? theta[viscous_] : 0.0;
    const double b = coulomb_ >= 0 ? theta[coulomb_] : 0.0;
    // e^(−aτ) by steps from the previous sample: a millisecond clock has few distinct steps, so
    // exp runs once per distinct step; recomputed directly every 64 samples (error < 64·ε).
    double t_prev = 0, e_prev = 1;
    double step_dt[2] = {nan, nan}, step_e[2] = {1, 1};
    for (std::size_t i = 0; i < n; ++i) {
      const double t = std::max(tau[i], 0.0);
      const double x = a * t;
      double e;
      if (i % 64 == 0) {
        e = std::exp(-x);
      } else {
        const double dt = t - t_prev;
        int slot = dt == step_dt[0] ? 0 : dt == step_dt[1] ? 1 : -1;
        if (slot < 0) {
          step_dt[1] = step_dt[0];
          step_e[1] = step_e[0];
          step_dt[0] = dt;
          step_e[0] = std::exp(-a * dt);
          slot = 0;
        }
        e = e_prev * step_e[slot];
      }
      t_prev = t;
      e_prev = e;
      double p, dp;
      phi(x, e, p, dp);
      const double m = theta[0] * e - b * t * p;
      const bool moving = m > 0 || b <= 0;
      if (want_jac) {
        // Only ω0 and the closed-form parameters move ω; the rest of s stays 0.
        s[0] = moving ? e : 0.0;
        if (viscous_ >= 0) s[viscous_] = moving ? -theta[0] * t * e - b * t * t * dp : 0.0;
        if (coulomb_ >= 0) s[coulomb_] = moving ? -t * p : 0.0;
      }
      finish(i, moving ? std::max(m, 0.0) : 0.0, s);
    }
    return;
  }
  integrate(theta, tau, want_jac, finish);
}

// Adaptive Dormand–Prince 5(4) on z = (ω, ∂ω/∂θ): ω' = −R(ω), s' = −R_ω·s − ∂R/∂θ, error
// control on ω (absolute, tolerance·ω0: the readings' noise is absolute), the samples read
// from the dense output, so the smooth coast is crossed in a few large steps whatever the
// sample rate. The stop: the step in which ω reaches 0 is integrated on the smooth
// continuation of R below 0 and the root of its dense output is the stop time; from there
// ω = 0 and its sensitivities vanish (friction holds the shaft).
template <class Finish>
void EffectSimulator::integrate(std::span<const double> theta, std::span<const double> tau, bool want_jac,
                                Finish& finish) const {
  const std::size_t n = tau.size();
  const int P = size_;
  const int D = want_jac ? 1 + P : 1;
  constexpr int M = max_params + 1;
  double z[M] = {}, z_new[M] = {}, tmp[M] = {}, out_s[M] = {};
  double k[7][M] = {};
  double cont[5 * M] = {};
  Deriv d;
  auto rhs = [&](const double* zv, double* f) {
    eval(theta, zv[0], d, want_jac);
    f[0] = -d.r;
    for (int j = 1; j < D; ++j) f[j] = -d.r_w * zv[j] - d.r_p[j - 1];
  };
  const bool can_stop = rate(theta, 0.0) > 0;
  const double w0 = theta[0];
  z[0] = w0;
  if (want_jac) z[1] = 1.0;  // ∂ω/∂ω0 at the cut
  const double zero[max_params] = {};

  std::size_t i = 0;
  // Samples at (or, with jitter, before) the cut read the initial state.
  for (; i < n && tau[i] <= 0; ++i) finish(i, can_stop ? std::max(w0, 0.0) : w0, z + 1);
  if (i == n) return;
  if (w0 <= 0) {
    // Already at rest (held by friction), or a model that cannot move from here.
    for (; i < n; ++i) finish(i, can_stop ? 0.0 : w0, can_stop ? zero : z + 1);
    return;
  }

  const double atol = tolerance * w0;
  rhs(z, k[0]);
  const double r0 = std::abs(k[0][0]);
  // First step: a small fraction of the time scale ω0/R(ω0); the controller grows it.
  double h = r0 > 0 ? 0.05 * std::pow(tolerance, 0.2) * w0 / r0 : tau[n - 1];
  h = std::clamp(h, 1e-9, std::max(max_step_s, 1e-9));
  double t = 0;
  const double h_min = 1e-12 * (1.0 + tau[n - 1]);
  constexpr int max_attempts = 200000;  // far beyond any run; a bound, not a tuning knob
  for (int attempt = 0; i < n; ++attempt) {
    if (attempt >= max_attempts) {
      // Should never happen; an unusable simulation must not look like a good one.
      for (; i < n; ++i) {
        for (int j = 0; j < P; ++j) out_s[j] = nan;
        finish(i, nan, out_s);
      }
      return;
    }
    using namespace dp;
    for (int c = 0; c < D; ++c) tmp[c] = z[c] + h * a21 * k[0][c];
    rhs(tmp, k[1]);
    for (int c = 0; c < D; ++c) tmp[c] = z[c] + h * (a31 * k[0][c] + a32 * k[1][c]);
    rhs(tmp, k[2]);
    for (int c = 0; c < D; ++c) tmp[c] = z[c] + h * (a41 * k[0][c] + a42 * k[1][c] + a43 * k[2][c]);
    rhs(tmp, k[3]);
    for (int c = 0; c < D; ++c)
      tmp[c] = z[c] + h * (a51 * k[0][c] + a52 * k[1][c] + a53 * k[2][c] + a54 * k[3][c]);
    rhs(tmp, k[4]);
    for (int c = 0; c < D; ++c)
      tmp[c] = z[c] + h * (a61 * k[0][c] + a62 * k[1][c] + a63 * k[2][c] + a64 * k[3][c] + a65 * k[4][c]);
    rhs(tmp, k[5]);
    for (int c = 0; c < D; ++c)
      z_new[c] = z[c] + h * (a71 * k[0][c] + a73 * k[2][c] + a74 * k[3][c] + a75 * k[4][c] + a76 * k[5][c]);
    rhs(z_new, k[6]);
    const double err_w =
        h * (e1 * k[0][0] + e3 * k[2][0] + e4 * k[3][0] + e5 * k[4][0] + e6 * k[5][0] + e7 * k[6][0]);
    const double err = std::abs(err_w) / atol;
    if (!std::isfinite(err) || (err > 1.0 && h > h_min)) {
      h *= std::isfinite(err) ? std::max(0.2, 0.9 * std::pow(err, -0.2)) : 0.1;
      h = std::max(h, h_min);
      continue;
    }
    // Accepted: the dense output's coefficients, per component (stride M).
    for (int c = 0; c < D; ++c) {
      const double diff = z_new[c] - z[c];
      const double bspl = h * k[0][c] - diff;
      cont[c] = z[c];
      cont[M + c] = diff;
      cont[2 * M + c] = bspl;
      cont[3 * M + c] = diff - h * k[6][c] - bspl;
      cont[4 * M + c] =
          h * (d1 * k[0][c] + d3 * k[2][c] + d4 * k[3][c] + d5 * k[4][c] + d6 * k[5][c] + d7 * k[6][c]);
    }
    const double t_new = t + h;
    // The stop inside this step: the root of the dense ω on (0, 1] (ω(0) > 0 ≥ ω(1)), by the
    // Illinois variant of regula falsi.
    double t_stop = inf;
    if (z_new[0] <= 0) {
      double lo = 0, hi = 1, f_lo = z[0], f_hi = z_new[0];
      int side = 0;
      for (int it = 0; it < 100 && hi - lo > 1e-15; ++it) {
        const double u = (lo * f_hi - hi * f_lo) / (f_hi - f_lo);
        const double f = dense(cont, M, u);
        if (f > 0) {
          lo = u;
          f_lo = f;
          if (side == -1) f_hi *= 0.5;
          side = -1;
        } else {
          hi = u;
          f_hi = f;
          if (side == 1) f_lo *= 0.5;
          side = 1;
        }
        if (f == 0) break;
      }
      t_stop = t + hi * h;
    }
    for (; i < n && tau[i] <= t_new && tau[i] < t_stop; ++i) {
      const double u = (tau[i] - t) / h;
      const double w = dense(cont, M, u);
      for (int j = 0; j < D - 1; ++j) out_s[j] = dense(cont + 1 + j, M, u);
      finish(i, std::max(w, 0.0), out_s);
    }
    if (t_stop < inf) {
      // At rest from here on (a model that cannot stop only reaches 0 through round-off).
      for (; i < n; ++i) finish(i, 0.0, zero);
      return;
    }
    t = t_new;
    std::copy(z_new, z_new + D, z);
    std::copy(k[6], k[6] + D, k[0]);  // first same as last
    const double grow = err > 0 ? std::min(5.0, 0.9 * std::pow(err, -0.2)) : 5.0;
    h = std::min(h * std::max(grow, 0.2), max_step_s);
  }
}

std::vector<double> EffectSimulator::omega(std::span<const double> theta, std::span<const double> tau) const {
  std::vector<double> out(tau.size());
  // Readings minus sensor terms, divided by k: simulate with the sensor parameters as given
  // and subtract their contribution at ω (they are ω-independent in the library).
  simulate(theta, tau, out);
  double sensor = 0;
  for (std::size_t e = 0; e < effects_.size(); ++e)
    if (effects_[e]->kind == EffectKind::sensor)
      sensor += effects_[e]->reading(theta.data() + first_[e], 0.0, nullptr);
  for (double& v : out) v = (v - sensor) / k_;
  return out;
}

std::vector<const Effect*> friction_effects(const FrictionTerms& f) {
  std::vector<const Effect*> out;
  if (f.viscous != 0) out.push_back(find_effect("viscous"));
  if (f.coulomb != 0) out.push_back(find_effect("coulomb"));
  if (f.stribeck_static > 0 && f.stribeck_speed > 0) out.push_back(find_effect("stribeck"));
  if (f.windage != 0) out.push_back(find_effect("windage"));
  return out;
}

std::vector<double> friction_theta(const FrictionTerms& f, double inertia_kg_m2, double omega0) {
  std::vector<double> th{omega0};
  const double J = inertia_kg_m2;
  if (f.viscous != 0) th.push_back(f.viscous / J);
  if (f.coulomb != 0) th.push_back(f.coulomb / J);
  if (f.stribeck_static > 0 && f.stribeck_speed > 0) {
    th.push_back((f.stribeck_static - f.coulomb) / J);
    th.push_back(f.stribeck_speed);
  }
  if (f.windage != 0) th.push_back(f.windage / J);
  return th;
}

}  // namespace spindown
