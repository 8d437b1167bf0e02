#pragma once
// The library of physical effects the discrepancy workflow can add to a model (design §6).
// Each effect is one self-contained entry: its name, what it means physically, its torque
// (or sensor) term, its parameters with units and bounds, and the signature it leaves in
// the residuals of a model that lacks it. Adding an effect = writing one make_<effect>()
// in effects.cpp and listing it in the table there.
//
// Internally the torque terms are divided by J (only c/J is identifiable from speed data):
// a torque coefficient c is fitted as a = c/J and reported in SI as a·J.
#include <limits>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace spindown {

// The scale of one run, for bounds and starting values (internal units).
struct RunScale {
  double omega0 = 300;      // rad/s at the cut (estimate)
  double duration_s = 30;   // coast duration (to the stop, or recorded)
  double reading_max = 3;   // largest reading, in the reading's unit
  // Where a sensor offset may lie (reading unit): between 0 and the zero level seen at standstill
  // (with that level's own uncertainty) when the run shows one; anywhere within ±reading_max/2 when
  // it does not.
  double offset_lo = -std::numeric_limits<double>::infinity();
  double offset_hi = std::numeric_limits<double>::infinity();
};

struct EffectParam {
  std::string_view name;     // internal: "c_v", "c_c", …; reported under the lab's names (effect_fit.hpp)
  std::string_view unit;     // SI unit of the reported value; "reading" = the recording's unit
  std::string_view meaning;
  bool per_inertia = true;   // reported SI value = internal value · J (a torque coefficient)
  // Bounds and a typical size (for scaling and starts) in internal units, for this run.
  double (*lower)(const RunScale&) = nullptr;
  double (*upper)(const RunScale&) = nullptr;
  double (*typical)(const RunScale&) = nullptr;
};

enum class EffectKind { torque, sensor };

struct Effect {
  std::string_view name;       // "viscous", "coulomb", "stribeck", "windage", "sensor_offset"
  std::string_view meaning;    // one line, physical
  std::string_view term;       // the formula, e.g. "T = c_v·ω"
  std::string_view signature;  // what a model without it leaves in the residuals (words)
  EffectKind kind = EffectKind::torque;
  std::vector<EffectParam> params;  // the first is a linear amplitude (used by starting regressions)

  // Torque effects: T/J (rad/s²) at ω ≥ 0 for internal parameters p; optional derivatives
  // d(T/J)/dω and d(T/J)/dp_j (p.size() entries). The simulator also evaluates it slightly
  // below 0 inside the integration step that reaches the stop: the formula must continue
  // smoothly there (finite, no kink at 0).
  double (*rate)(const double* p, double omega, double* d_omega, double* d_p) = nullptr;
  // Sensor effects: what is added to the reading (reading unit), with d/dp_j.
  double (*reading)(const double* p, double omega, double* d_p) = nullptr;
  // Torque effects whose amplitude enters linearly: T/J = p0·shape(ω; p1…). Used to regress
  // the integral form for a start; shape parameters come from shape_starts.
  double (*shape)(const double* p, double omega) = nullptr;
  std::vector<double> (*shape_starts)(const RunScale&) = nullptr;  // starting values for p1 (internal)

  int size() const { return static_cast<int>(params.size()); }
};

// Every known effect, in a fixed order (the order candidates are tried and reported).
std::span<const Effect> effect_library();
const Effect* find_effect(std::string_view name);
std::vector<std::string> effect_names();

// Parses "viscous", "coulomb", "combined" (= viscous,coulomb) or "EFFECT,EFFECT,…".
// Returns the effects in library order without duplicates; empty and *why on error.
std::vector<const Effect*> parse_effect_list(std::string_view text, std::string* why);

}  // namespace spindown
