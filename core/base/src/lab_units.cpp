#include "spindown/lab_units.hpp"

#include <array>
#include <utility>

#include "spindown/bench.hpp"

namespace spindown {

namespace {
constexpr double lab_per_si = g_cm2_per_kg_m2;  // the same 1e7 for all three lab units

constexpr LabUnit inertia_unit{lab_per_si, "g*cm^2", "g·cm²"};
constexpr LabUnit viscous_unit{lab_per_si, "g*cm^2/s", "g·cm²·s⁻¹"};
constexpr LabUnit torque_unit{lab_per_si, "g*cm^2*rad/s^2", "g·cm²·rad·s⁻²"};

constexpr std::array<std::pair<std::string_view, std::string_view>, 12> pretty_units{{
    {"N*m*s/rad", "N·m·s/rad"},
    {"N*m", "N·m"},
    {"kg*m^2", "kg·m²"},
    {"V*s/rad", "V·s/rad"},
    {"rad/s^2", "rad/s²"},
    {"V/s", "V/s"},
    {"1/s", "s⁻¹"},
    {"N*m*s^2/rad^2", "N·m·s²/rad²"},
    {"g*cm^2", "g·cm²"},
    {"g*cm^2/s", "g·cm²·s⁻¹"},
    {"g*cm^2*rad/s^2", "g·cm²·rad·s⁻²"},
    {"rpm/s", "rpm/s"},
}};
}  // namespace

std::optional<LabUnit> lab_unit_for(std::string_view si_unit) {
  if (si_unit == "kg*m^2") return inertia_unit;
  if (si_unit == "N*m*s/rad") return viscous_unit;
  if (si_unit == "N*m") return torque_unit;
  return std::nullopt;
}

double inertia_to_g_cm2(double kg_m2) { return kg_m2 * inertia_unit.per_si; }
double viscous_to_g_cm2_per_s(double n_m_s_per_rad) { return n_m_s_per_rad * viscous_unit.per_si; }
double torque_to_g_cm2_rad_per_s2(double n_m) { return n_m * torque_unit.per_si; }

std::string_view pretty_unit(std::string_view ascii_unit) {
  for (const auto& [ascii, pretty] : pretty_units)
    if (ascii == ascii_unit) return pretty;
  return ascii_unit;
}

}  // namespace spindown
