#pragma once
// CSV cells as MATLAB's readtable, pandas and Excel read them: numbers with 10 significant digits
// (NaN, Inf, -Inf spelled out), text quoted only when it holds the delimiter, a quote or a line
// break. One spelling for every CSV spindown writes (export, fit --table).
//
// Two styles: the default (',' between cells, a decimal point), and a European spreadsheet's
// (`--csv-locale de`: ';' between cells and decimal commas, as Excel set to German, French,
// Italian, Spanish… opens a CSV by a double click). A file written for a spreadsheet starts with
// a UTF-8 byte-order mark, without which Excel reads UTF-8 as Windows-1252 ("1.0Ã—", "SchÃ¤fer");
// readtable and pandas.read_csv skip it, Python's csv module needs encoding="utf-8-sig".
#include <charconv>
#include <cmath>
#include <fmt/format.h>
#include <optional>
#include <string>
#include <string_view>

namespace spindown {

struct CsvStyle {
  char delimiter = ',';
  bool decimal_comma = false;
  bool byte_order_mark = false;  // the file starts with EF BB BF
};

// "en" (the default) or "de" (';' and decimal commas; also at, fr, it, es, nl); nullopt otherwise.
inline std::optional<CsvStyle> csv_style_for_locale(std::string_view locale) {
  if (locale.empty() || locale == "en" || locale == "C" || locale == "us" || locale == "uk") return CsvStyle{};
  if (locale == "de" || locale == "at" || locale == "fr" || locale == "it" || locale == "es" || locale == "nl")
    return CsvStyle{';', true, false};
  return std::nullopt;
}

inline constexpr std::string_view utf8_byte_order_mark = "\xEF\xBB\xBF";

// What a CSV file starts with in this style: the byte-order mark, or nothing.
inline std::string_view csv_file_start(const CsvStyle& style) {
  return style.byte_order_mark ? utf8_byte_order_mark : std::string_view();
}

// A number in this style's decimal mark ("1,822e-07" with decimal commas).
inline std::string csv_decimal(std::string text, const CsvStyle& style) {
  if (style.decimal_comma)
    for (char& c : text)
      if (c == '.') c = ',';
  return text;
}

inline std::string csv_number(double x, const CsvStyle& style = {}) {
  if (std::isnan(x)) return "NaN";
  if (std::isinf(x)) return x > 0 ? "Inf" : "-Inf";
  return csv_decimal(fmt::format("{:.10g}", x), style);
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

inline std::string csv_field(std::string_view s, const CsvStyle& style = {}) {
  const char specials[] = {style.delimiter, '"', '\r', '\n', '\0'};
  if (s.find_first_of(specials) == std::string_view::npos) return std::string(s);
  std::string q = "\"";
  for (char c : s) {
    if (c == '"') q += '"';
    q += c;
  }
  return q + '"';
}

}  // namespace spindown
