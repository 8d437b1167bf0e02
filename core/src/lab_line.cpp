#include "spindown/lab_line.hpp"

#include <charconv>
#include <cmath>
#include <cstdint>
#include <system_error>

namespace spindown {

namespace {

constexpr bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f';
}

// A sample line is ~12 characters; anything much longer is not one, and refusing it here
// keeps the parser O(1) on a 10 MB line with no newline.
constexpr std::size_t max_sample_line = 64;
// millis() and micros() are unsigned 32-bit counters.
constexpr std::uint64_t max_device_ticks = 0xFFFFFFFFull;
// Serial.print(float) prints "ovf" above this, so a larger number cannot come from the sketch.
constexpr double max_printable_value = 4294967040.0;

// The sketch prints values like "3.21" or "-0.01": digits, a point, digits. Those are read
// here exactly as from_chars would (a mantissa below 2^53 divided by an exact power of ten
// is correctly rounded); anything else (exponents, long mantissas, errors) goes to from_chars.
bool parse_plain_decimal(const char* p, const char* end, double& value) {
  static constexpr double pow10[] = {1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15};
  const bool negative = p < end && *p == '-';
  if (negative) ++p;
  std::uint64_t mantissa = 0;
  int digits = 0, fraction = -1;
  for (; p < end; ++p) {
    if (*p >= '0' && *p <= '9') {
      mantissa = mantissa * 10 + static_cast<unsigned>(*p - '0');
      ++digits;
      if (fraction >= 0) ++fraction;
    } else if (*p == '.' && fraction < 0) {
      fraction = 0;
    } else {
      return false;
    }
  }
  if (digits == 0 || digits > 15) return false;
  const double v = static_cast<double>(mantissa) / pow10[fraction < 0 ? 0 : fraction];
  value = negative ? -v : v;
  return true;
}

LabLine sample_line(std::uint64_t ticks, double value) {
  LabLine sample;
  sample.kind = LabLine::Kind::sample;
  sample.millis = static_cast<std::int64_t>(ticks);
  sample.value = value;
  return sample;
}

LabLine garbled(std::string_view why) {
  LabLine line;
  line.kind = LabLine::Kind::garbled;
  line.why = why;
  return line;
}

}  // namespace

LabLine parse_lab_line(std::string_view line) {
  std::size_t b = 0, e = line.size();
  while (e > b && is_space(line[e - 1])) --e;
  while (b < e && is_space(line[b])) ++b;
  if (b == e) {
    LabLine blank;
    blank.kind = LabLine::Kind::blank;
    return blank;
  }
  if (e - b > max_sample_line) return garbled("line too long to be a millis<TAB>volts sample");

  const char* p = line.data() + b;
  const char* const end = line.data() + e;
  if (*p == '-') return garbled("negative time");

  std::uint64_t ticks = 0;
  auto [after_time, time_ec] = std::from_chars(p, end, ticks);
  if (time_ec == std::errc::invalid_argument) return garbled("time is not a number");
  if (time_ec == std::errc::result_out_of_range || ticks > max_device_ticks)
    return garbled("time beyond the range of millis() (2^32 ms)");
  if (after_time == end) return garbled("missing value (only one field)");
  if (!is_space(*after_time)) {
    if (*after_time == '.' || *after_time == 'e' || *after_time == 'E')
      return garbled("time is not a whole number of milliseconds");
    return garbled("time is not a number");
  }

  const char* q = after_time;
  while (q < end && is_space(*q)) ++q;  // q < end: trailing space was trimmed above
  double value = 0;
  if (parse_plain_decimal(q, end, value) && std::fabs(value) <= max_printable_value) return sample_line(ticks, value);
  auto [after_value, value_ec] = std::from_chars(q, end, value);
  if (value_ec == std::errc::invalid_argument) return garbled("value is not a number");
  if (value_ec == std::errc::result_out_of_range) return garbled("value out of range");
  if (after_value != end) {
    if (is_space(*after_value)) return garbled("extra field after the value");
    return garbled("value is not a number");
  }
  if (!std::isfinite(value)) return garbled("value is NaN or infinite");
  if (std::fabs(value) > max_printable_value) return garbled("value larger than an Arduino can print");

  return sample_line(ticks, value);
}

}  // namespace spindown
