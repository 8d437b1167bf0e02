#include "spindown/friction.hpp"

#include <cmath>

namespace spindown {

double FrictionTerms::torque(double omega) const {
  double t = viscous * omega + coulomb + windage * omega * omega;
  if (stribeck_static > 0 && stribeck_speed > 0) {
    const double x = omega / stribeck_speed;
    t += (stribeck_static - coulomb) * std::exp(-x * x);
  }
  return t;
}

double FrictionTerms::breakaway() const { return torque(0.0); }

}  // namespace spindown
