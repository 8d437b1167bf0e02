#include "spindown/doctor_check.hpp"

#include <algorithm>
#include <fmt/format.h>

namespace spindown {

std::string_view check_level_name(CheckLevel level) {
  switch (level) {
    case CheckLevel::ok: return "ok";
    case CheckLevel::skip: return "skip";
    case CheckLevel::warn: return "warn";
    case CheckLevel::fail: return "fail";
  }
  return "?";
}

int doctor_exit_code(const std::vector<DoctorCheck>& checks) {
  int code = 0;
  for (const auto& c : checks) {
    if (c.level == CheckLevel::fail) return 2;
    if (c.level == CheckLevel::warn) code = 1;
  }
  return code;
}

namespace {
std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> out;
  std::size_t start = 0;
  while (start <= text.size()) {
    const auto end = text.find('\n', start);
    out.push_back(text.substr(start, end == std::string::npos ? std::string::npos : end - start));
    if (end == std::string::npos) break;
    start = end + 1;
  }
  return out;
}

std::string plural(std::size_t n, std::string_view one, std::string_view many) {
  return fmt::format("{} {}", n, n == 1 ? one : many);
}
}  // namespace

std::string render_doctor_text(const std::vector<DoctorCheck>& checks) {
  std::size_t width = 0;
  for (const auto& c : checks) width = std::max(width, c.name.size());
  width = std::min<std::size_t>(width, 28);
  std::string out;
  std::size_t count[4] = {0, 0, 0, 0};
  for (const auto& c : checks) {
    ++count[static_cast<int>(c.level)];
    out += fmt::format("{:<5} {:<{}}  {}\n", check_level_name(c.level), c.name, width, c.detail);
    if (c.fix.empty()) continue;
    bool first = true;
    for (const auto& line : lines_of(c.fix)) {
      out += fmt::format("      {} {}\n", first ? "fix:" : "    ", line);
      first = false;
    }
  }
  out += fmt::format("doctor: {} ok, {}, {}{}\n", count[0], plural(count[2], "warning", "warnings"),
                     plural(count[3], "failure", "failures"),
                     count[1] ? fmt::format(", {} skipped", count[1]) : std::string());
  return out;
}

nlohmann::json doctor_json(const std::vector<DoctorCheck>& checks) {
  nlohmann::json list = nlohmann::json::array();
  nlohmann::json summary = {{"ok", 0}, {"skip", 0}, {"warn", 0}, {"fail", 0}};
  for (const auto& c : checks) {
    const std::string level(check_level_name(c.level));
    list.push_back({{"name", c.name}, {"level", level}, {"detail", c.detail}, {"fix", c.fix}});
    summary[level] = summary[level].get<int>() + 1;
  }
  return {{"checks", list}, {"summary", summary}, {"exit_code", doctor_exit_code(checks)}};
}

}  // namespace spindown
