#pragma once
// The motor-health sections of a bench's TOML file ([motor], [baseline], [health]) and its
// bench id. The model and the judgement are motor_health.hpp's.
#include <string>

#include "spindown/motor_health.hpp"

namespace spindown {

// Reads [motor], [baseline], [health] from the bench's TOML file (keys it does not set keep
// their defaults; other sections are left to their readers). Throws std::runtime_error naming
// the file, the key and what was wrong (also for unknown keys in these three sections).
MotorHealthConfig load_motor_health_config(const std::string& toml_path);

// The bench a TOML file describes: its bench_id key, else the file name without ".toml".
// Throws std::runtime_error naming the file when it cannot be read.
std::string bench_id_of_config(const std::string& toml_path);

}  // namespace spindown
