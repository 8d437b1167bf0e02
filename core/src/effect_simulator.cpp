#include "spindown/effect_simulator.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

namespace spindown {
namespace {

constexpr double inf = std::numeric_limits<double>::infinity();

// φ(x) = (1 − e^(−x))/x and dφ/dx, a series where 1 − e would cancel (as in fit.cpp).
inline void phi(double x, double e, double& p, double& dp) {
  if (x < 1e-3) {
    p = 1.0 - x / 2 + x * x / 6 - x * x * x / 24;
    dp = -0.5 + x / 3 - x * x / 8;
  } else {
    p = (1.0 - e) / x;
    dp = (e * (1.0 + x) - 1.0) / (x * x);
  }
}

// 8-point Gauss–Legendre nodes/weights on [−1, 1] (positive half).
constexpr std::array<double, 4> gl_x = {0.1834346424956498, 0.5255324099163290, 0.7966664774136267,
                                        0.9602898564975363};
constexpr std::array<double, 4> gl_w = {0.3626837833783620, 0.3137066458778873, 0.2223810344533745,
                                        0.1012285362903763};

}  // namespace

EffectSimulator::EffectSimulator(std::vector<const Effect*> effects, double reading_per_rad_s)
    : effects_(std::move(effects)), k_(reading_per_rad_s) {
  bool only_closed = true;
  for (const Effect* e : effects_) {
    if (!e) throw std::invalid_argument("EffectSimulator: null effect");
    first_.push_back(size_);
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

void EffectSimulator::eval(std::span<const double> theta, double omega, Deriv& d, bool with_params) const {
  d.r = 0;
  d.r_w = 0;
  const double w = std::max(omega, 0.0);
  for (std::size_t i = 0; i < effects_.size(); ++i) {
    const Effect* e = effects_[i];
    if (e->kind != EffectKind::torque) continue;
    const int j = first_[i];
    double rw = 0;
    d.r += e->rate(theta.data() + j, w, &rw, with_params ? d.r_p + j : nullptr);
    d.r_w += rw;
  }
}

double EffectSimulator::rate(std::span<const double> theta, double omega) const {
  Deriv d;
  eval(theta, omega, d, false);
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
    for (std::size_t e = 0; e < effects_.size(); ++e) {
      if (effects_[e]->kind != EffectKind::sensor) continue;
      const int j = first_[e];
      y += effects_[e]->reading(theta.data() + j, w, row ? row + j : nullptr);
    }
    reading[i] = y;
  };

  double s[max_params] = {};
  if (closed_) {
    const double a = viscous_ >= 0 ? theta[viscous_] : 0.0;
    const double b = coulomb_ >= 0 ? theta[coulomb_] : 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      const double t = std::max(tau[i], 0.0);
      const double x = a * t;
      const double e = std::exp(-x);
      double p, dp;
      phi(x, e, p, dp);
      const double m = theta[0] * e - b * t * p;
      const bool moving = m > 0 || b <= 0;
      if (want_jac) {
        std::fill(s, s + P, 0.0);
        if (moving) {
          s[0] = e;
          if (viscous_ >= 0) s[viscous_] = -theta[0] * t * e - b * t * t * dp;
          if (coulomb_ >= 0) s[coulomb_] = -t * p;
        }
      }
      finish(i, moving ? std::max(m, 0.0) : 0.0, s);
    }
    return;
  }

  // RK4 on z = (ω, ∂ω/∂θ): ω' = −R(ω), s' = −R_ω·s − ∂R/∂θ.
  const bool can_stop = rate(theta, 0.0) > 0;
  double w = theta[0], t = 0;
  bool stopped = w <= 0 && can_stop;
  std::fill(s, s + P, 0.0);
  s[0] = 1.0;
  Deriv d;
  double ks[4][max_params + 1];
  auto stage = [&](double wv, const double* sv, double* out) {
    eval(theta, wv, d, want_jac);
    out[0] = -d.r;
    if (want_jac)
      for (int j = 0; j < P; ++j) out[1 + j] = -d.r_w * sv[j] - d.r_p[j];
  };
  double sv[max_params];
  for (std::size_t i = 0; i < n; ++i) {
    const double target = tau[i];
    while (!stopped && t < target) {
      const double remaining = target - t;
      const int parts = static_cast<int>(std::ceil(remaining / max_step_s - 1e-9));
      const double h = parts > 1 ? remaining / parts : remaining;
      if (can_stop) {
        eval(theta, 0.0, d, false);
        const double r0 = d.r;
        eval(theta, w, d, false);
        if (w <= 1.5 * h * std::max(r0, d.r)) {
          const double ts = time_to_stop(theta, w);
          if (ts <= h) {
            stopped = true;
            t += ts;
            w = 0;
            std::fill(s, s + P, 0.0);
            break;
          }
        }
      }
      stage(w, s, ks[0]);
      for (int j = 0; j < P; ++j) sv[j] = s[j] + 0.5 * h * ks[0][1 + j];
      stage(w + 0.5 * h * ks[0][0], sv, ks[1]);
      for (int j = 0; j < P; ++j) sv[j] = s[j] + 0.5 * h * ks[1][1 + j];
      stage(w + 0.5 * h * ks[1][0], sv, ks[2]);
      for (int j = 0; j < P; ++j) sv[j] = s[j] + h * ks[2][1 + j];
      stage(w + h * ks[2][0], sv, ks[3]);
      double w_next = w + h / 6 * (ks[0][0] + 2 * ks[1][0] + 2 * ks[2][0] + ks[3][0]);
      if (want_jac)
        for (int j = 0; j < P; ++j) s[j] += h / 6 * (ks[0][1 + j] + 2 * ks[1][1 + j] + 2 * ks[2][1 + j] + ks[3][1 + j]);
      if (w_next <= 0) {
        if (can_stop) {
          // RK4 overshot the stop although the quadrature says it lies beyond this step: ω at
          // (ts − h) before the stop, by Newton on ∫₀^ω dw/R = ts − h.
          const double left = std::max(time_to_stop(theta, w) - h, 0.0);
          eval(theta, 0.0, d, false);
          double wn = d.r * left;
          for (int it = 0; it < 3 && wn > 0; ++it) {
            eval(theta, wn, d, false);
            wn -= (time_to_stop(theta, wn) - left) * d.r;
            wn = std::max(wn, 0.0);
          }
          w_next = wn;
        } else {
          w_next = 0;
        }
      }
      w = w_next;
      t += h;
    }
    finish(i, stopped ? 0.0 : w, s);
  }
}

std::vector<double> EffectSimulator::omega(std::span<const double> theta, std::span<const double> tau) const {
  std::vector<double> out(tau.size());
  // Readings minus sensor terms, divided by k: simulate with the sensor parameters as given
  // and subtract their contribution at ω (they are ω-independent in the library).
  simulate(theta, tau, out);
  for (std::size_t i = 0; i < out.size(); ++i) {
    double sensor = 0;
    for (std::size_t e = 0; e < effects_.size(); ++e)
      if (effects_[e]->kind == EffectKind::sensor)
        sensor += effects_[e]->reading(theta.data() + first_[e], 0.0, nullptr);
    out[i] = (out[i] - sensor) / k_;
  }
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
