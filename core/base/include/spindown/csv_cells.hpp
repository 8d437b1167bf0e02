#pragma once
// CSV cells as MATLAB's readtable and pandas read them: numbers with 10 significant digits
// (NaN, Inf, -Inf spelled out), text quoted only when it holds a comma, a quote or a line break.
// One spelling for every CSV spindown writes (export, fit --table).
#include <cmath>
#include <fmt/format.h>
#include <string>
#include <string_view>

namespace spindown {

inline std::string csv_number(double x) {
  if (std::isnan(x)) return "NaN";
  if (std::isinf(x)) return x > 0 ? "Inf" : "-Inf";
  return fmt::format("{:.10g}", x);
}

inline std::string csv_field(std::string_view s) {
  if (s.find_first_of(",\"\r\n") == std::string_view::npos) return std::string(s);
  std::string q = "\"";
  for (char c : s) {
    if (c == '"') q += '"';
    q += c;
  }
  return q + '"';
}

}  // namespace spindown
