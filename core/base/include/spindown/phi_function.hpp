#pragma once
// φ(x) = (1 − e^(−x))/x, the viscous coast's integral of e^(−x), and dφ/dx, from the one
// exponential e = e^(−x) already computed; a series where 1 − e would cancel. The fit's model
// reading (fit_family.hpp) and the effect simulator's closed form both use it.

namespace spindown {

inline void phi(double x, double e, double& p, double& dp) {
  if (x < 1e-3) {
    p = 1.0 - x / 2 + x * x / 6 - x * x * x / 24;
    dp = -0.5 + x / 3 - x * x / 8;
  } else {
    p = (1.0 - e) / x;
    dp = (e * (1.0 + x) - 1.0) / (x * x);
  }
}

}  // namespace spindown
