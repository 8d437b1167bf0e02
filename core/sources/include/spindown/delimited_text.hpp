#pragma once
// Delimited text with a time column and a value column: CSV, semicolon CSV (decimal comma
// allowed), TSV or whitespace-separated, with or without a header row. The user names the
// columns and units when they are not obvious; otherwise they are detected from header
// names ("time", "t", "millis", "ms" / "volts", "V", "emf", "rpm", "omega", units in
// brackets like "time (s)" or suffixes like "time_ms") and a clear error says what is
// ambiguous.
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

#include "spindown/quantity.hpp"
#include "spindown/recording.hpp"

namespace spindown {

enum class TimeUnit { s, ms, us };
std::string_view time_unit_name(TimeUnit unit);                // "s", "ms", "us"
std::optional<TimeUnit> parse_time_unit(std::string_view unit);  // s, sec, ms, millis, us, µs, micros…
double time_units_per_second(TimeUnit unit);

struct DelimitedTextOptions {
  // Column by header name (case-insensitive; "time" also matches "time (s)") or 1-based
  // index ("2"). Empty: detect.
  std::string time_column;
  std::string value_column;
  std::optional<TimeUnit> time_unit;  // empty: from the header, else from the data (a note says so)
  std::optional<Quantity> quantity;   // empty: from the header, else volts without a header
  char delimiter = 0;                 // ',', ';', '\t' or ' ' (any run of blanks); 0: detect
  std::optional<bool> header;         // empty: a first row with a non-number is a header
  std::size_t max_line_reports = 20;  // bad lines reported one by one before only a count

  // True when the user named anything about the columns (then a text file is read as
  // delimited text, not as Arduino text).
  bool names_columns() const;
  bool is_valid(std::string* why) const;
};

Recording read_delimited_text(std::string_view text, std::string source, const DelimitedTextOptions& options = {});
Recording read_delimited_text_file(const std::string& path, const DelimitedTextOptions& options = {});

}  // namespace spindown
