#pragma once
// One finding of `spindown doctor` (a check of what breaks LCM labs) and how a list of them is
// shown: one line per check — ok / warn / fail / skip, the check's name, what was found — and,
// when something is wrong, the command that fixes it. The exit code says the worst level.
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

namespace spindown {

// Ordered by severity; skip (not applicable here, or cannot be checked) counts as ok.
enum class CheckLevel { ok, skip, warn, fail };
std::string_view check_level_name(CheckLevel level);  // "ok" | "skip" | "warn" | "fail"

struct DoctorCheck {
  std::string name;    // "multicast route", "firewall", "serial bench-1", …
  CheckLevel level = CheckLevel::ok;
  std::string detail;  // what was found, in words a technician understands
  std::string fix;     // command(s) that fix it, one per line; empty when nothing to fix
};

// 0 every check ok (or skipped), 1 warnings, 2 failures.
int doctor_exit_code(const std::vector<DoctorCheck>& checks);

// One line per check ("ok    multicast route   239.255.76.67 goes out on lo …"), each fix line
// below it ("      fix: ip route add 224.0.0.0/4 dev lo"), then a summary line.
std::string render_doctor_text(const std::vector<DoctorCheck>& checks);

// {"checks":[{"name","level","detail","fix"}], "summary":{"ok","skip","warn","fail"}, "exit_code"}
nlohmann::json doctor_json(const std::vector<DoctorCheck>& checks);

}  // namespace spindown
