#pragma once
// Friction torque on the coasting shaft, as the sum of the physical terms the suite knows.
// T(ω) for ω > 0; at ω = 0 the shaft stays stopped when the breakaway torque holds it.
namespace spindown {

struct FrictionTerms {
  double viscous = 0;          // c_v  N·m·s/rad   T = c_v·ω
  double coulomb = 0;          // c_c  N·m         T = c_c
  double stribeck_static = 0;  // c_s  N·m         T += (c_s − c_c)·exp(−(ω/w_s)²) when c_s > 0
  double stribeck_speed = 0;   // w_s  rad/s
  double windage = 0;          // c_w  N·m·s²/rad²  T = c_w·ω²

  double torque(double omega) const;  // N·m, ω ≥ 0
  // Torque that holds a stopped shaft (the limit ω → 0+); > 0 means the shaft can stop.
  double breakaway() const;
};

}  // namespace spindown
