#include "spindown/recording.hpp"

#include <algorithm>
#include <fmt/format.h>

namespace spindown {

std::string Diagnostic::to_string() const {
  const char* sev = severity == Severity::error ? "error" : severity == Severity::note ? "note" : "warning";
  if (line > 0) return fmt::format("{}:{}: {}: {}", source, line, sev, message);
  return fmt::format("{}: {}: {}", source, sev, message);
}

void Recording::warn(std::int64_t line, std::string message) {
  diagnostics.push_back({Diagnostic::Severity::warning, source, line, std::move(message)});
}
void Recording::note(std::int64_t line, std::string message) {
  diagnostics.push_back({Diagnostic::Severity::note, source, line, std::move(message)});
}
void Recording::error(std::int64_t line, std::string message) {
  diagnostics.push_back({Diagnostic::Severity::error, source, line, std::move(message)});
}
bool Recording::has_errors() const {
  return std::any_of(diagnostics.begin(), diagnostics.end(),
                     [](const Diagnostic& d) { return d.severity == Diagnostic::Severity::error; });
}

}  // namespace spindown
