#pragma once
// The lab a program serves: its name is in every message it sends (the `lab` field), and a
// message of another lab is counted and named, never used — two labs on one network stay two
// labs (issue 31; docs/lab-setup.md). `--lab NAME`, else $SPINDOWN_LAB (in /etc/spindown/lcm.env
// for the services), else "lab".
#include <optional>
#include <string>
#include <string_view>

namespace spindown {

inline constexpr std::string_view default_lab = "lab";

// True when name matches [A-Za-z0-9_-]{1,32} (the bench id rule); otherwise false and *why.
bool is_valid_lab_name(std::string_view name, std::string* why = nullptr);

// The lab name a program uses: option when not empty, else env_value ($SPINDOWN_LAB) when not
// empty, else "lab". Throws std::invalid_argument naming where an invalid name came from.
std::string choose_lab_name(const std::string& option, const std::optional<std::string>& env_value);
// The same with $SPINDOWN_LAB read from the environment.
std::string choose_lab_name(const std::string& option);

}  // namespace spindown
