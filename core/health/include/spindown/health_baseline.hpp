#pragma once
// A motor's baseline: the friction it had when known good, averaged over good runs (each run's
// combined fit that converged), and the [baseline] section of a bench's TOML file that holds it.
//
//   c = Σ w_i c_i / Σ w_i with w_i = 1/σ_i²; its standard error 1/√Σw_i, widened by the Birge
//   ratio √(χ²/(n−1)) when the runs scatter more than their own errors say, and never below the
//   run-to-run scatter's spread/√n; the spread is the runs' sample standard deviation (natural
//   run-to-run variation, used by assess_health).
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "spindown/fit.hpp"
#include "spindown/motor_health.hpp"

namespace spindown {

// One run's combined-model coefficients, as the baseline uses them.
struct BaselineRun {
  std::string source;  // "file run 2"
  double c_viscous = 0, c_viscous_stderr = 0;
  double c_coulomb = 0, c_coulomb_stderr = 0;
  double inertia_kg_m2 = 0;
  double omega0 = 0;  // speed at the cut (rad/s), as read
};

// The run's combined fit when it converged with finite coefficients on a whole coast (its cut
// seen, stopped); nullopt and *why otherwise.
std::optional<BaselineRun> baseline_run(const RunFit& fit, std::string source, std::string* why = nullptr);

// A run make_baseline left out of the mean, and why.
struct SetAsideRun {
  std::string source;
  std::string why;  // "dry friction 3.1× the others' median (412 standard errors): worn, or not this motor?"
};

// Runs that do not belong in a reference: with three runs or more, a run whose c_v or c_c lies
// more than outlier_sigma from the runs' median, counting its own standard error and the runs'
// natural scatter (1.4826 × the median absolute deviation, at least natural_scatter of the
// median). Their mean is made of the rest.
inline constexpr double baseline_outlier_sigma = 5.0;
inline constexpr double baseline_natural_scatter = 0.05;

// The weighted mean of the runs, runs that disagree set aside (*set_aside says which and why).
// nullopt and *why when there is no baseline to be had: no run, two runs that disagree beyond
// their errors and the natural scatter (which one is the motor's normal cannot be told), or
// fewer than half of the runs left.
std::optional<HealthBaseline> make_baseline(std::span<const BaselineRun> runs, std::string date, std::string source,
                                            std::string* why = nullptr, std::vector<SetAsideRun>* set_aside = nullptr);

// "[baseline]\n…" with every key and a comment line saying how it was made.
std::string baseline_toml_section(const HealthBaseline& baseline);

// The TOML text with its [baseline] table replaced (or appended when there is none), every
// other line, key and comment kept. nullopt and *why when that cannot be done cleanly (a
// baseline written as dotted keys or an inline table, or the result would change other keys).
std::optional<std::string> with_baseline_section(const std::string& toml_text, const HealthBaseline& baseline,
                                                 std::string* why = nullptr);

}  // namespace spindown
