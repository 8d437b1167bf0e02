#pragma once
// Questions the reader tests ask of a Recording's diagnostics: those of a severity, the one at a
// line, whether any mentions a text, and all of them as text for a failure message.
#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include "spindown/recording.hpp"

namespace spindown::testing {

inline std::vector<const Diagnostic*> with(const Recording& r, Diagnostic::Severity s) {
  std::vector<const Diagnostic*> out;
  for (const auto& d : r.diagnostics)
    if (d.severity == s) out.push_back(&d);
  return out;
}

inline const Diagnostic* at_line(const Recording& r, std::int64_t line) {
  for (const auto& d : r.diagnostics)
    if (d.line == line) return &d;
  return nullptr;
}

inline bool mentions(const Recording& r, const std::string& text) {
  return std::any_of(r.diagnostics.begin(), r.diagnostics.end(),
                     [&](const Diagnostic& d) { return d.message.find(text) != std::string::npos; });
}

inline std::string all_diagnostics(const Recording& r) {
  std::string out;
  for (const auto& d : r.diagnostics) out += d.to_string() + "\n";
  return out;
}

}  // namespace spindown::testing
