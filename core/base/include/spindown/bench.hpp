#pragma once
// The bench a run was measured on: the inertia J and the back-EMF constant K_b that turn
// curve constants into friction coefficients. Only c/J is identifiable from speed data;
// with J known, friction is reported in SI.
#include <string>

namespace spindown {

struct BenchParams {
  double inertia_kg_m2 = 1.12687602e-5;            // the lab's flywheel + rotor
  double kb_v_s_per_rad = 1.0 / 123.569311;        // the lab's motor: 1180 rpm/V
  std::string inertia_source = "lab default";      // how J was obtained, for reports
  std::string kb_source = "lab default";
  // Relative standard uncertainty of J and of K_b (0.02 = 2 %; 0: taken as exact). c1…c4 scale
  // with J and, for a back-EMF reading, c2 and c4 with 1/K_b too: fit_run carries these into each
  // coefficient's bench_error, beside its statistical standard error.
  double inertia_rel_error = 0;
  double kb_rel_error = 0;

  static BenchParams lab_default() { return {}; }
  bool is_valid(std::string* why) const;  // positive, finite, plausible
};

// Solid cylinder about its axis: m r² / 2 with m = ρ π r² h (SI in, kg·m² out).
double cylinder_inertia(double radius_m, double height_m, double density_kg_m3);
// K_b (V·s/rad) from a motor speed constant in rpm/V.
double kb_from_speed_constant(double rpm_per_volt);

// Lab units, for output only: 1 kg·m² = 1e7 g·cm².
inline constexpr double g_cm2_per_kg_m2 = 1e7;

}  // namespace spindown
