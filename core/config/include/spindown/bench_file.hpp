#pragma once
// The per-bench TOML files of a lab (deploy/benches/<bench>.toml, installed as
// /etc/spindown/benches/<bench>.toml): one file per bench, read by spindown-bridge ([serial],
// [bench], …) and by the fitters for J/K_b and the motor health references ([motor],
// [baseline], [health]). A bench's id is its bench_id key, else the file name without ".toml".
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "spindown/bench.hpp"
#include "spindown/motor_health.hpp"

namespace spindown {

struct BenchFile {
  std::string path;
  std::string bench;           // bench id
  BenchParams params;          // [bench] J and K_b (lab defaults where the file sets none)
  bool sets_inertia = false;   // the file gives J (inertia_kg_m2 or flywheel geometry)
  bool sets_kb = false;        // the file gives K_b (kb_v_s_per_rad or speed_constant_rpm_per_v)
  bool sets_inertia_error = false, sets_kb_error = false;  // [bench] inertia_error_pct, kb_error_pct
  MotorHealthConfig health;    // [motor], [baseline], [health]
  // Usable but doubtful (BridgeSettings::warnings: a [bench] K_b the [motor] datasheet contradicts),
  // each a whole line "PATH: warning: …"; every command that reads the file prints them.
  std::vector<std::string> warnings;
};

struct BenchFiles {
  std::map<std::string, BenchFile, std::less<>> files;  // by bench id
  // The file for a recording of bench (an LCM log's bench id, a text file's from the roster or
  // --bench-pattern); a recording that names no bench ("") takes the only file given, if one.
  const BenchFile* for_bench(std::string_view bench) const;
};

// J and K_b for one recording, by the one rule every offline command follows (fit, explain,
// baseline, report), each parameter on its own: the command line (--inertia or --flywheel…,
// --kb or --speed-constant), else the bench's file ([bench] of its --bench-config TOML), else
// the log's CONFIG, else the lab's defaults. inertia_source and kb_source name where each came
// from. Their uncertainties follow the same rule, each on its own (--inertia-error/--kb-error,
// [bench] inertia_error_pct/kb_error_pct, the CONFIG's; else 0: taken as exact). (refit and export reproduce the live fitter, which takes CONFIG, else its defaults.)
struct BenchChoice {
  BenchParams given;  // the lab's defaults with the command line's values applied
  bool inertia_given = false, kb_given = false;
  bool inertia_error_given = false, kb_error_given = false;
};
BenchParams choose_bench_params(const BenchChoice& cli, const BenchFile* file, const std::optional<BenchParams>& config);

// Reads one bench file. Throws std::runtime_error naming the file and key.
BenchFile load_bench_file(const std::string& path);
// Each path is a file or a directory (every *.toml in it, sorted). Throws std::runtime_error
// naming the file for an unreadable or bad file, or when two files describe the same bench.
BenchFiles load_bench_files(const std::vector<std::string>& paths);

}  // namespace spindown
