#pragma once
// `spindown fit FILE...`: read each file, find its spin-down runs, fit the friction models,
// report per run a table like the lab report's (or design §5's JSON with --json).
#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace spindown::cli {

struct FitCommandOptions {
  std::vector<std::string> files;
  bool json = false;
  bool lab_units = false;
  bool verbose = false;  // every diagnostic, notes included
  std::vector<std::string> models;  // names; empty = all

  // The bench: J directly, or from flywheel geometry + rotor inertia; K_b directly or from
  // the speed constant. A value counts only when its flag was given (the *_given flags).
  double inertia_kg_m2 = 0;
  double flywheel_radius_m = 0, flywheel_height_m = 0, flywheel_density_kg_m3 = 0, rotor_inertia_kg_m2 = 0;
  double kb_v_s_per_rad = 0;
  double speed_constant_rpm_per_v = 0;
  bool inertia_given = false, flywheel_given = false, kb_given = false, speed_constant_given = false;

  // Delimited text: columns and units when they are not obvious from the header.
  std::string time_column, value_column, time_unit, value_unit, delimiter;
};

void setup_fit(CLI::App& app);
// Returns the exit code (0 ok, 1 a file or run could not be used); throws
// CLI::ValidationError for bad usage (exit code 2).
int run_fit(const FitCommandOptions& options);

}  // namespace spindown::cli
