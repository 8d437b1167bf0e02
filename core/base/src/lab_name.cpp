#include "spindown/lab_name.hpp"

#include <cstdlib>
#include <fmt/format.h>
#include <stdexcept>

#include "spindown/lcm_channels.hpp"

namespace spindown {

bool is_valid_lab_name(std::string_view name, std::string* why) {
  std::string inner;
  if (is_valid_bench_id(name, &inner)) return true;
  if (why) {
    // The bench id rule's words, about a lab name.
    if (const auto at = inner.find("bench id"); at != std::string::npos) inner.replace(at, 8, "lab name");
    *why = inner;
  }
  return false;
}

std::string choose_lab_name(const std::string& option, const std::optional<std::string>& env_value) {
  std::string why;
  if (!option.empty()) {
    if (!is_valid_lab_name(option, &why)) throw std::invalid_argument(fmt::format("--lab '{}': {}", option, why));
    return option;
  }
  if (env_value && !env_value->empty()) {
    if (!is_valid_lab_name(*env_value, &why))
      throw std::invalid_argument(fmt::format("SPINDOWN_LAB '{}': {}", *env_value, why));
    return *env_value;
  }
  return std::string(default_lab);
}

std::string choose_lab_name(const std::string& option) {
  const char* env = std::getenv("SPINDOWN_LAB");
  return choose_lab_name(option, env ? std::optional<std::string>(env) : std::nullopt);
}

}  // namespace spindown
