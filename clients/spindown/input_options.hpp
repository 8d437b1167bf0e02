#pragma once
// The options the commands that read recordings share: the bench (J directly or from flywheel
// geometry + rotor inertia; K_b directly or from a speed constant), the columns and units of
// delimited text, and which bench a class's text file is from (a roster or a file-name pattern). One definition, so both commands accept and check them alike.
#include <functional>
#include <iosfwd>
#include <string>
#include <vector>

#include "spindown/bench.hpp"
#include "spindown/bench_file.hpp"
#include "spindown/bench_naming.hpp"
#include "spindown/fit.hpp"
#include "spindown/read_recording.hpp"

#include "lab_options.hpp"

namespace CLI {
class App;
}

namespace spindown::cli {

struct InputOptions {
  // A bench value counts only when its flag was given (the *_given flags).
  double inertia_kg_m2 = 0;
  double flywheel_radius_m = 0, flywheel_height_m = 0, flywheel_density_kg_m3 = 0, rotor_inertia_kg_m2 = 0;
  double kb_v_s_per_rad = 0;
  double speed_constant_rpm_per_v = 0;
  bool inertia_given = false, flywheel_given = false, kb_given = false, speed_constant_given = false;
  double inertia_error_pct = 0, kb_error_pct = 0;  // their standard uncertainties, % (0: exact)
  bool inertia_error_given = false, kb_error_given = false;

  // Delimited text: columns and units when they are not obvious from the header.
  std::string time_column, value_column, time_unit, value_unit, delimiter;
  double period_ms = 0;  // 0: not given

  // A class's text files: which bench (and student) each is from.
  std::string roster, bench_pattern;

  // --bench-config: per-bench TOML files or directories ([bench] J/K_b unless given as flags;
  // [motor], [baseline], [health] for the motor health verdict).
  std::vector<std::string> bench_configs;

  // LCM logs: whose messages are read (--lab, --key).
  LabOptions lab;
};

// Which groups a command takes: every command that reads recordings takes the bench group;
// --bench-config unless it names its bench file otherwise (baseline's --update); the text
// groups (columns and units, a class's roster) unless it reads LCM logs only (refit).
struct InputParts {
  bool bench_config = true;
  bool text = true;
};

// Adds the bench ("Bench" group), --bench-config and the delimited-text and class options to sub,
// bound to opt, the same flags and words for every command. Call the returned function in the
// subcommand's callback: it records which bench flags were given.
std::function<void()> add_input_options(CLI::App* sub, InputOptions& opt, InputParts parts = {});

// The --bench-config files, each read once (load_bench_files). What a file says that is doubtful
// (BenchFile::warnings) goes to err, once per file; a file that cannot be used is bad usage
// (CLI::ValidationError, exit 2).
BenchFiles bench_files_from(const InputOptions& opt, std::ostream& err);
// One bench file's warnings on err (a file given otherwise, as baseline's --update).
void print_bench_file_warnings(const BenchFile& file, std::ostream& err);

// The bench the options describe (lab defaults where not given). Bad usage throws
// CLI::ValidationError (exit code 2).
BenchParams bench_from(const InputOptions& opt);
// The command line's part of the J/K_b rule (choose_bench_params): its values and which it gave.
BenchChoice bench_choice_from(const InputOptions& opt);
// Which bench a text file is from (--roster, --bench-pattern; fixed_bench: a command's --bench).
// A roster that cannot be read or a bad pattern is bad usage (CLI::ValidationError).
BenchNaming naming_from(const InputOptions& opt, const std::string& fixed_bench = {});
// Reading options for the delimited-text columns and units. Bad usage throws CLI::ValidationError.
ReadOptions read_options_from(const InputOptions& opt);

// The models --models names, in order ("all" stands for every model, in place of those named
// before it). An unknown name throws CLI::ValidationError.
std::vector<ModelKind> models_from(const std::vector<std::string>& names);

[[noreturn]] void bad_usage(const std::string& why);

}  // namespace spindown::cli
