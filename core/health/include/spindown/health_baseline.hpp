#pragma once
// A motor's baseline: the friction it had when known good, averaged over good runs (each run's
// combined fit that converged), and the [baseline] section of a bench's TOML file that holds it.
//
//   c = Σ w_i c_i / Σ w_i with w_i = 1/σ_i²; its standard error 1/√Σw_i, widened by the Birge
//   ratio √(χ²/(n−1)) when the runs scatter more than their own errors say; the spread is the
//   runs' sample standard deviation (natural run-to-run variation, used by assess_health).
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
};

// The run's combined fit when it converged with finite coefficients; nullopt and *why otherwise.
std::optional<BaselineRun> baseline_run(const RunFit& fit, std::string source, std::string* why = nullptr);

// The weighted mean of the runs; nullopt and *why when there is none.
std::optional<HealthBaseline> make_baseline(std::span<const BaselineRun> runs, std::string date, std::string source,
                                            std::string* why = nullptr);

// "[baseline]\n…" with every key and a comment line saying how it was made.
std::string baseline_toml_section(const HealthBaseline& baseline);

// The TOML text with its [baseline] table replaced (or appended when there is none), every
// other line, key and comment kept. nullopt and *why when that cannot be done cleanly (a
// baseline written as dotted keys or an inline table, or the result would change other keys).
std::optional<std::string> with_baseline_section(const std::string& toml_text, const HealthBaseline& baseline,
                                                 std::string* why = nullptr);

}  // namespace spindown
