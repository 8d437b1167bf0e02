#pragma once
// `spindown explain FILE...`: for each spin-down run, fit the base model (the user's belief),
// find where it and the measurement disagree, name the missing effect, add it, and repeat
// (design §6); the story as text, design §5's JSON with --json, a figure with --svg.
#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace spindown::cli {

struct ExplainCommandOptions {
  std::vector<std::string> files;
  std::string base = "viscous";  // viscous|coulomb|combined|EFFECT,EFFECT…
  bool json = false;
  std::string svg;               // output file, empty = none
  bool verbose = false;

  // The bench, as for `spindown fit`: a value counts only when its flag was given.
  double inertia_kg_m2 = 0;
  double flywheel_radius_m = 0, flywheel_height_m = 0, flywheel_density_kg_m3 = 0, rotor_inertia_kg_m2 = 0;
  double kb_v_s_per_rad = 0;
  double speed_constant_rpm_per_v = 0;
  bool inertia_given = false, flywheel_given = false, kb_given = false, speed_constant_given = false;

  std::string time_column, value_column, time_unit, value_unit, delimiter;
};

void setup_explain(CLI::App& app);
// Returns the exit code (0 ok, 1 a file or run could not be used); throws
// CLI::ValidationError for bad usage (exit code 2).
int run_explain(const ExplainCommandOptions& options);

}  // namespace spindown::cli
