#pragma once
// CSV cells as MATLAB's readtable and pandas read them: numbers with 10 significant digits
// (NaN, Inf, -Inf spelled out), text quoted only when it holds a comma, a quote or a line break.
// One spelling for every CSV spindown writes (export, fit --table).
#include <charconv>
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

// The number a csv_number cell reads back as (x itself when not finite): what `fit --table json`
// writes, in the shortest digits that read back as it, so the JSON and CSV tables hold the same
// numbers and no 3.4909999999999997 (a time computed as 3491 × 0.001) shows its last bits.
inline double csv_number_value(double x) {
  if (!std::isfinite(x)) return x;
  const std::string text = fmt::format("{:.10g}", x);
  double y = x;
  std::from_chars(text.data(), text.data() + text.size(), y);  // locale-free, as fmt wrote it
  return y;
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
