#include "spindown/bench.hpp"

#include <cmath>
#include <fmt/format.h>
#include <numbers>

namespace spindown {

bool BenchParams::is_valid(std::string* why) const {
  auto fail = [&](std::string msg) {
    if (why) *why = std::move(msg);
    return false;
  };
  // Bounds wide enough for any bench motor, tight enough to catch unit mistakes (g·cm² as kg·m²).
  if (!std::isfinite(inertia_kg_m2) || inertia_kg_m2 <= 0 || inertia_kg_m2 >= 10)
    return fail(fmt::format("inertia {} kg·m² is not a positive value below 10 kg·m²", inertia_kg_m2));
  if (!std::isfinite(kb_v_s_per_rad) || kb_v_s_per_rad <= 0 || kb_v_s_per_rad >= 10)
    return fail(fmt::format("K_b {} V·s/rad is not a positive value below 10 V·s/rad", kb_v_s_per_rad));
  return true;
}

double cylinder_inertia(double radius_m, double height_m, double density_kg_m3) {
  const double mass = density_kg_m3 * std::numbers::pi * radius_m * radius_m * height_m;
  return 0.5 * mass * radius_m * radius_m;
}

double kb_from_speed_constant(double rpm_per_volt) {
  return 1.0 / (rpm_per_volt * 2.0 * std::numbers::pi / 60.0);
}

}  // namespace spindown
