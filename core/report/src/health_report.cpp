#include "spindown/health_report.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fmt/format.h>

#include "spindown/fit_report.hpp"

namespace spindown {

namespace {

std::string value_text(double value, double se, const std::string& unit) {
  if (!std::isfinite(value)) return std::isinf(value) ? "never" : "-";
  std::string u = unit == "N*m" ? "N·m" : unit == "N*m*s/rad" ? "N·m·s/rad" : unit == "kg*m^2" ? "kg·m²" : unit;
  if (unit == "s") return se > 0 ? fmt::format("{:.1f} ± {:.1f} s", value, se) : fmt::format("{:.1f} s", value);
  return format_value_error(value, se) + " " + u;
}

}  // namespace

std::string format_health_verdict(const HealthVerdict& v, std::string_view indent) {
  std::string level(health_level_name(v.level));
  std::transform(level.begin(), level.end(), level.begin(),
                 [](unsigned char c) { return c == '_' ? ' ' : char(std::toupper(c)); });
  std::string out = fmt::format("{}health: {}{} — {}\n", indent, level,
                                v.has_reference || v.level == HealthLevel::not_judged ? "" : " (no reference)", v.reason);
  for (const auto& f : v.findings) {
    if (!std::isfinite(f.value) && !std::isinf(f.value)) continue;  // words only: already in the reason
    std::string line = fmt::format("{}  {:<26} {}", indent, f.what, value_text(f.value, f.std_error, f.unit));
    if (std::isfinite(f.reference))
      line += fmt::format("  vs {} {}", f.reference_name, value_text(f.reference, f.reference_std_error, f.unit));
    if (f.ratio != 0 && f.unit != "s") line += "  ratio " + format_value_error(f.ratio, f.ratio_std_error);
    line += fmt::format("  [{}]", health_level_name(f.level));
    out += line + '\n';
  }
  return out;
}

}  // namespace spindown
