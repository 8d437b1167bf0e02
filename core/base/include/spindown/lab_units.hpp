#pragma once
// The lab report's units, for output only (design §1). Inside, everything is SI; the
// lab wrote inertia in g·cm², the viscous coefficient (c1, c3) in g·cm²·s⁻¹ and the
// Coulomb torque (c2, c4) in g·cm²·rad·s⁻². All three are the SI value times 1e7
// (1 kg·m² = 1e3 g · 1e4 cm²), since rad is dimensionless.
#include <optional>
#include <string_view>

namespace spindown {

struct LabUnit {
  double per_si = 1;          // multiply the SI value by this
  std::string_view ascii;     // for JSON and scripts: "g*cm^2/s"
  std::string_view pretty;    // for people: "g·cm²·s⁻¹"
};

// The lab's unit for an SI unit as spelled in Parameter::unit ("kg*m^2", "N*m*s/rad",
// "N*m"); nullopt when the lab used the SI unit itself (rad/s, V, 1/s …).
std::optional<LabUnit> lab_unit_for(std::string_view si_unit);

double inertia_to_g_cm2(double kg_m2);
double viscous_to_g_cm2_per_s(double n_m_s_per_rad);
double torque_to_g_cm2_rad_per_s2(double n_m);

// A human spelling of the suite's ASCII units: "N*m*s/rad" → "N·m·s/rad", "kg*m^2" → "kg·m²".
std::string_view pretty_unit(std::string_view ascii_unit);

}  // namespace spindown
