#pragma once
// Motor health: does this run's friction say the motor needs attention? A fit is compared with
// the references the bench's TOML file (one file per bench, the one spindown-bridge reads) may
// carry, and judged ok / check / service with a reason a student understands:
//
//   [motor]    the datasheet: speed_constant_rpm_per_v, no_load_speed_rpm, no_load_current_a,
//              torque_constant_nm_per_a, rotor_inertia_kg_m2. Expected friction torque at the
//              no-load speed is k_M·I0 (torque constant × no-load current); the fitted one is
//              c_v·ω_nl + c_c with its uncertainty from the fit's standard errors.
//   [baseline] the fitted coefficients when the motor was known good (`spindown baseline`):
//              c_viscous_n_m_s, c_viscous_stderr, c_coulomb_n_m, c_coulomb_stderr, runs, date, …
//              c_v and c_c are compared as ratios with uncertainty.
//   [health]   thresholds: check_ratio, service_ratio, significance_sigma, and the lab report's
//              two diagnosis rules as explicit limits: max_slowdown_s (too long to slow down:
//              time to lose slowdown_fraction of the speed) and max_stop_s (too long to stop).
//
// A ratio is flagged only when it is past its threshold and significant: it differs from 1 by
// more than significance_sigma standard errors (a ratio past the threshold by noise is not). Without a datasheet or a baseline the
// verdict says there is no reference (has_reference = false) instead of inventing one; the lab's
// time rules still apply.
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "spindown/fit.hpp"

namespace spindown {

// not_judged: nothing to judge the run against (no datasheet, no baseline) and nothing else
// flagged it; never shown as OK. Ordered by concern: a bench's worst run is the maximum.
enum class HealthLevel { not_judged, ok, check, service };
std::string_view health_level_name(HealthLevel level);  // "not_judged" | "ok" | "check" | "service"
std::optional<HealthLevel> parse_health_level(std::string_view name);

// The motor's datasheet; every value optional (SI except where the unit says rpm).
struct MotorDatasheet {
  std::optional<double> speed_constant_rpm_per_v;
  std::optional<double> no_load_speed_rpm;
  std::optional<double> no_load_current_a;
  std::optional<double> torque_constant_nm_per_a;
  std::optional<double> rotor_inertia_kg_m2;

  // k_M in N·m/A: as given, else from the speed constant (k_M = K_b in SI units).
  std::optional<double> torque_constant() const;
  // k_M·I0 in N·m: the friction torque the datasheet implies at no-load speed.
  std::optional<double> no_load_friction_torque() const;
  bool empty() const;
};

// Friction of the motor when it was known good: the combined model's c_v (N·m·s/rad) and c_c
// (N·m) averaged over good runs.
struct HealthBaseline {
  double c_viscous = 0, c_viscous_stderr = 0;  // weighted mean and its standard error
  double c_coulomb = 0, c_coulomb_stderr = 0;
  double c_viscous_spread = 0;  // standard deviation across the runs (0 for one run)
  double c_coulomb_spread = 0;
  int runs = 0;                 // runs averaged
  std::string date;             // when it was made (ISO 8601)
  double inertia_kg_m2 = 0;     // J the runs were fitted with (0 = not recorded)
  std::string source;           // what it was made from (file, bench)
  // The runs' mean speed at the cut as read (rad/s; 0 = not recorded): the lab's supply drives
  // the motor to about the same speed every run, so a run that reads another speed at the cut
  // with its dry friction changed by the same factor has a reading scaled, not friction changed.
  double omega0 = 0, omega0_spread = 0;
};

struct HealthThresholds {
  double check_ratio = 1.5;         // friction this many times the reference: "check"
  double service_ratio = 2.5;       // … this many times: "service"
  double significance_sigma = 2.0;  // a ratio must differ from 1 by this many standard errors
  // The lab report's rules. Too long to slow down: the motor needs more than max_slowdown_s to
  // lose slowdown_fraction of its speed at the cut. Too long to stop: more than max_stop_s from
  // the cut to standstill (measured stop, else the best model's prediction).
  double max_slowdown_s = 30.0;
  double slowdown_fraction = 0.5;
  double max_stop_s = 60.0;
  // A stop time this fraction sooner or later than the baseline predicts from the run's own
  // speed at the cut is a "check", whatever the friction ratios say.
  double stop_change_fraction = 0.25;
  bool is_valid(std::string* why) const;
};

struct MotorHealthConfig {
  std::optional<MotorDatasheet> datasheet;
  std::optional<HealthBaseline> baseline;
  HealthThresholds thresholds;
  std::string source;  // the file it was read from ("" when built in code)
};

// One comparison behind a verdict.
struct HealthFinding {
  std::string what;       // "dry friction", "viscous friction", "friction at no-load speed", …
  HealthLevel level = HealthLevel::ok;
  std::string reason;     // student words: "dry friction 2.4× the baseline: check bearings and alignment"
  double value = 0;       // this run's number (NaN/inf when it has none, e.g. never stops)
  double std_error = 0;   // its standard error (0 when not known)
  double reference = 0;   // what it is compared with (baseline, datasheet, limit)
  double reference_std_error = 0;  // its uncertainty (baseline standard error with the run-to-run spread)
  std::string reference_name;      // "baseline", "datasheet", "lab limit"
  double ratio = 0;       // value / reference (0 when the comparison is not a ratio)
  double ratio_std_error = 0;
  std::string unit;       // ASCII SI unit of value and reference: "N*m", "N*m*s/rad", "s"
};

struct HealthVerdict {
  HealthLevel level = HealthLevel::ok;
  std::string reason;                  // the flagged findings' reasons, worst first; or why all is well
  std::vector<HealthFinding> findings;
  bool has_reference = false;          // false: no datasheet or baseline configured
};

HealthVerdict assess_health(const RunFit& fit, const MotorHealthConfig& cfg);

// The combined model's friction, as assess_health compares it with a baseline: c_v (c3,
// N·m·s/rad) and c_c (c4, N·m) with their standard errors (0 when the fit gave none).
struct FrictionEstimate {
  double c_viscous = 0, c_viscous_stderr = 0, c_coulomb = 0, c_coulomb_stderr = 0;
};
// nullopt when the combined model did not converge or has no finite c3, c4.
std::optional<FrictionEstimate> combined_friction(const RunFit& fit);

}  // namespace spindown
