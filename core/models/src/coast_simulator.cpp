#include "spindown/coast_simulator.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

namespace spindown {
namespace {

// Time to coast from ω down to 0: t = ∫₀^ω J/T(w) dw, exact for the stop event. 16-point
// Gauss–Legendre on a few panels; T(w) > 0 on [0, ω] is required (checked by the caller).
double time_to_stop(const FrictionTerms& f, double inv_j, double omega) {
  static constexpr std::array<double, 8> x = {0.0950125098376374, 0.2816035507792589,
                                              0.4580167776572274, 0.6178762444026438,
                                              0.7554044083550030, 0.8656312023878318,
                                              0.9445750230732326, 0.9894009349916499};
  static constexpr std::array<double, 8> w = {0.1894506104550685, 0.1826034150449236,
                                              0.1691565193950025, 0.1495959888165767,
                                              0.1246289712555339, 0.0951585116824928,
                                              0.0622535239386479, 0.0271524594117541};
  constexpr int panels = 4;
  const double hw = omega / panels / 2;
  double sum = 0;
  for (int p = 0; p < panels; ++p) {
    const double mid = (2 * p + 1) * hw;
    for (std::size_t i = 0; i < x.size(); ++i) {
      sum += w[i] * (1.0 / f.torque(mid - hw * x[i]) + 1.0 / f.torque(mid + hw * x[i]));
    }
  }
  return sum * hw / inv_j;
}

}  // namespace

CoastSimulator::CoastSimulator(FrictionTerms friction, double inertia_kg_m2, double omega0)
    : f_(friction), inv_j_(1.0 / inertia_kg_m2), omega_(omega0) {
  if (!(inertia_kg_m2 > 0) || !(omega0 >= 0)) throw std::invalid_argument("CoastSimulator: J must be > 0 and ω0 ≥ 0");
  stopped_ = omega0 == 0 && f_.breakaway() > 0;
}

double CoastSimulator::advance(double dt) {
  if (!(dt >= 0)) throw std::invalid_argument("CoastSimulator::advance: dt must be ≥ 0");
  const double t_end = t_ + dt;
  if (stopped_) {
    t_ = t_end;
    return 0.0;
  }
  // Dormand–Prince 5(4) on (ω, θ) with error control on ω; ω' = −T(ω)/J, θ' = ω.
  auto rhs = [&](double w) { return -f_.torque(std::max(w, 0.0)) * inv_j_; };
  double h = std::min(0.01, std::max(dt, 1e-6));
  while (t_ < t_end) {
    h = std::min(h, t_end - t_);
    const double w = omega_;
    const double k1 = rhs(w);
    const double k2 = rhs(w + h * (k1 / 5));
    const double k3 = rhs(w + h * (3 * k1 / 40 + 9 * k2 / 40));
    const double k4 = rhs(w + h * (44 * k1 / 45 - 56 * k2 / 15 + 32 * k3 / 9));
    const double k5 = rhs(w + h * (19372 * k1 / 6561 - 25360 * k2 / 2187 + 64448 * k3 / 6561 - 212 * k4 / 729));
    const double k6 = rhs(w + h * (9017 * k1 / 3168 - 355 * k2 / 33 + 46732 * k3 / 5247 + 49 * k4 / 176 - 5103 * k5 / 18656));
    const double w5 = w + h * (35 * k1 / 384 + 500 * k3 / 1113 + 125 * k4 / 192 - 2187 * k5 / 6784 + 11 * k6 / 84);
    const double k7 = rhs(w5);
    const double w4 = w + h * (5179 * k1 / 57600 + 7571 * k3 / 16695 + 393 * k4 / 640 - 92097 * k5 / 339200 + 187 * k6 / 2100 + k7 / 40);
    const double err = std::abs(w5 - w4);
    const double tol = 1e-9 + 1e-10 * std::abs(w);
    if (w5 <= 0 && f_.breakaway() > 0) {
      // The stop falls inside this step: land on it exactly by quadrature over ω.
      const double ts = time_to_stop(f_, inv_j_, w);
      if (ts <= t_end - t_) {
        angle_ += w * ts / 2 + 0.0;  // sub-millirad detail near the stop; ripple only needs the phase
        t_stop_ = t_ + ts;
        t_ = t_end;
        omega_ = 0;
        stopped_ = true;
        return 0.0;
      }
      h = std::max(ts * 0.9, 1e-9);  // approach the stop more carefully
      continue;
    }
    if (err <= tol || h <= 1e-9) {
      angle_ += h * (w + std::max(w5, 0.0)) / 2;
      t_ += h;
      omega_ = std::max(w5, 0.0);
      if (omega_ == 0 && f_.breakaway() > 0) {
        stopped_ = true;
        t_stop_ = t_;
      }
    }
    const double scale = err > 0 ? 0.9 * std::pow(tol / err, 0.2) : 5.0;
    h *= std::clamp(scale, 0.2, 5.0);
  }
  t_ = t_end;
  return omega_;
}

std::vector<double> simulate_coast(const FrictionTerms& friction, double inertia_kg_m2, double omega0,
                                   std::span<const double> tau) {
  CoastSimulator sim(friction, inertia_kg_m2, omega0);
  std::vector<double> out;
  out.reserve(tau.size());
  for (double t : tau) {
    out.push_back(t <= sim.time() ? sim.omega() : sim.advance(t - sim.time()));
  }
  return out;
}

}  // namespace spindown
