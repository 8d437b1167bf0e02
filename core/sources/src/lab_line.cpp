#include "spindown/lab_line.hpp"

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <system_error>

// The shape fast path uses SSE2, always there on x86-64; elsewhere each line takes printed_line.
#if defined(__x86_64__)
#include <emmintrin.h>
#endif

namespace spindown {

namespace {

constexpr bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f';
}

constexpr bool is_digit(char c) { return c >= '0' && c <= '9'; }

// A sample line is ~12 characters; anything much longer is not one, and refusing it here
// keeps the parser O(1) on a 10 MB line with no newline.
constexpr std::size_t max_sample_line = 64;
// millis() and micros() are unsigned 32-bit counters.
constexpr std::uint64_t max_device_ticks = 0xFFFFFFFFull;
// Serial.print(float) prints "ovf" above this, so a larger number cannot come from the sketch.
constexpr double max_printable_value = 4294967040.0;
// Digits of a mantissa read exactly (below 2^53).
constexpr int max_plain_digits = 15;

// A plain decimal's value exactly as from_chars gives it: a mantissa below 2^53 divided by an
// exact power of ten is correctly rounded.
double plain_decimal_value(std::uint64_t mantissa, int fraction, bool negative) {
  static constexpr double pow10[] = {1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15};
  const double v = static_cast<double>(mantissa) / pow10[fraction < 0 ? 0 : fraction];
  return negative ? -v : v;
}

// The sketch prints values like "3.21" or "-0.01": digits, a point, digits. Those are read
// here exactly; anything else (exponents, long mantissas, errors) goes to from_chars.
bool parse_plain_decimal(const char* p, const char* end, double& value) {
  const bool negative = p < end && *p == '-';
  if (negative) ++p;
  std::uint64_t mantissa = 0;
  int digits = 0, fraction = -1;
  for (; p < end; ++p) {
    if (is_digit(*p)) {
      mantissa = mantissa * 10 + static_cast<unsigned>(*p - '0');
      ++digits;
      if (fraction >= 0) ++fraction;
    } else if (*p == '.' && fraction < 0) {
      fraction = 0;
    } else {
      return false;
    }
  }
  if (digits == 0 || digits > max_plain_digits) return false;
  value = plain_decimal_value(mantissa, fraction, negative);
  return true;
}

LabLine sample_line(std::uint64_t ticks, double value) {
  LabLine sample;
  sample.kind = LabLine::Kind::sample;
  sample.millis = static_cast<std::int64_t>(ticks);
  sample.value = value;
  return sample;
}

LabLine garbled_lab_line(std::string_view why) {
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
  if (e - b > max_sample_line) return garbled_lab_line("line too long to be a millis<TAB>volts sample");

  const char* p = line.data() + b;
  const char* const end = line.data() + e;
  if (*p == '-') return garbled_lab_line("negative time");

  std::uint64_t ticks = 0;
  auto [after_time, time_ec] = std::from_chars(p, end, ticks);
  if (time_ec == std::errc::invalid_argument) return garbled_lab_line("time is not a number");
  if (time_ec == std::errc::result_out_of_range || ticks > max_device_ticks)
    return garbled_lab_line("time beyond the range of millis() (2^32 ms)");
  if (after_time == end) return garbled_lab_line("missing value (only one field)");
  if (!is_space(*after_time)) {
    if (*after_time == '.' || *after_time == 'e' || *after_time == 'E')
      return garbled_lab_line("time is not a whole number of milliseconds");
    return garbled_lab_line("time is not a number");
  }

  const char* q = after_time;
  while (q < end && is_space(*q)) ++q;  // q < end: trailing space was trimmed above
  double value = 0;
  if (parse_plain_decimal(q, end, value) && std::fabs(value) <= max_printable_value) return sample_line(ticks, value);
  auto [after_value, value_ec] = std::from_chars(q, end, value);
  if (value_ec == std::errc::invalid_argument) return garbled_lab_line("value is not a number");
  if (value_ec == std::errc::result_out_of_range) return garbled_lab_line("value out of range");
  if (after_value != end) {
    if (is_space(*after_value)) return garbled_lab_line("extra field after the value");
    return garbled_lab_line("value is not a number");
  }
  if (!std::isfinite(value)) return garbled_lab_line("value is NaN or infinite");
  if (std::fabs(value) > max_printable_value) return garbled_lab_line("value larger than an Arduino can print");

  return sample_line(ticks, value);
}

namespace {

// Eight bytes of text as a little-endian word: byte 0 is the first character. The fast path
// reads digits eight at a time (SWAR, "SIMD within a register").
std::uint64_t load_word(const char* p) {
  std::uint64_t w;
  std::memcpy(&w, p, sizeof w);
  return w;
}

constexpr std::uint64_t every_byte(std::uint64_t b) { return b * 0x0101010101010101ull; }

// How many of the word's first bytes are ASCII digits (0 to 8). A byte is a digit when its
// high nibble is 3 and its low nibble at most 9; both tests are exact per byte (no carries).
int leading_digits(std::uint64_t w) {
  const std::uint64_t high_not_3 = (w & every_byte(0xF0)) ^ every_byte(0x30);
  const std::uint64_t low_over_9 = ((w & every_byte(0x0F)) + every_byte(0x06)) & every_byte(0x10);
  const std::uint64_t not_digit = high_not_3 | low_over_9;
  return not_digit == 0 ? 8 : std::countr_zero(not_digit) / 8;
}

// The number eight digit values (0 to 9, one a byte, the first in byte 0) spell.
std::uint64_t eight_digits_value(std::uint64_t w) {
  w = (w * 10 + (w >> 8)) & 0x00FF00FF00FF00FFull;
  w = (w * 100 + (w >> 16)) & 0x0000FFFF0000FFFFull;
  return (w * 10000 + (w >> 32)) & 0xFFFFFFFFull;
}

// The number the word's first n (1 to 8) digit bytes spell: they are moved to the top so the
// bytes below read as leading zeros, then pairs, fours and eights are combined.
std::uint64_t digits_value(std::uint64_t w, int n) { return eight_digits_value((w & every_byte(0x0F)) << (8 * (8 - n))); }

// The word without its byte k (0 to 7): the bytes after it move down one, a zero comes in on top.
std::uint64_t without_byte(std::uint64_t w, int k) {
  const std::uint64_t below = (std::uint64_t{1} << (8 * k)) - 1;
  return (w & below) | ((w >> 8) & ~below);
}

bool is_line_end(char c) { return c == '\r' || c == '\n'; }

// The words and bytes a printed line is read from lie within its first 18 bytes: with less text
// than this left (a file's last line or two) a line takes the slow path.
constexpr std::size_t enough_text = 24;

// The fast path for the line at begin (at least enough_text bytes readable): its length without
// the terminator, with ticks and value set; 0 when it is not a line as the sketch prints it.
// Inlined into both callers so the word constants stay in registers across a file's lines.
[[gnu::always_inline]] inline std::size_t printed_line(const char* begin, std::uint64_t& ticks, double& value) {
  // Time: 1 to 7 digits (up to 2.7 hours of millis(); later times take the slow path), then a
  // tab or a space.
  const std::uint64_t time_word = load_word(begin);
  const int time_digits = leading_digits(time_word);
  if (time_digits == 0 || time_digits == 8) return 0;
  if (begin[time_digits] != '\t' && begin[time_digits] != ' ') return 0;
  ticks = digits_value(time_word, time_digits);
  const char* q = begin + time_digits + 1;

  // The sketch's usual value, "d.dd" (volts from Serial.println(float)): three digits read one
  // by one, the same mantissa and power of ten as the general case below would take.
  const unsigned ones = static_cast<unsigned char>(q[0]) - unsigned{'0'};
  const unsigned tenths = static_cast<unsigned char>(q[2]) - unsigned{'0'};
  const unsigned hundredths = static_cast<unsigned char>(q[3]) - unsigned{'0'};
  if (ones <= 9 && q[1] == '.' && tenths <= 9 && hundredths <= 9 && is_line_end(q[4])) {
    value = plain_decimal_value(ones * 100 + tenths * 10 + hundredths, 2, false);
    return static_cast<std::size_t>(q + 4 - begin);
  }

  // Value: [-]digits[.digits], 1 to 7 digits in all, then CR or LF. With the point taken out
  // the digits are one run that digits_value reads at once.
  const bool negative = *q == '-';
  if (negative) ++q;
  std::uint64_t value_word = load_word(q);
  const int whole_digits = leading_digits(value_word);
  const bool point = whole_digits < 8 && q[whole_digits] == '.';
  if (point) value_word = without_byte(value_word, whole_digits);
  const int digits = leading_digits(value_word);  // at most 7 with a point (the top byte is 0)
  const char* const stop = q + digits + (point ? 1 : 0);
  if (digits == 0 || digits == 8 || !is_line_end(*stop)) return 0;
  value = plain_decimal_value(digits_value(value_word, digits), point ? digits - whole_digits : -1, negative);
  return static_cast<std::size_t>(stop - begin);
}

std::size_t terminator_length(const char* stop) { return stop[0] == '\r' && stop[1] == '\n' ? 2 : 1; }

// Lines printed alike: the same number of time digits, the same separator, the value as "d.dd"
// and the same terminator, e.g. "5234\t0.00\r\n". The sketch prints them by the thousand; one is
// checked against the shape with a few 16-byte SSE2 operations instead of a scan of its fields.
// XOR with the pattern turns a digit into its value (0 to 9) and a matching separator or
// terminator into 0, so the whole line is one comparison with the most each byte may be.
class PrintedShape {
 public:
  // No shape: fits nothing.
  PrintedShape() = default;

  // The shape of a line printed_line took (length bytes before its terminator), if it has one.
  static PrintedShape of(const char* line, std::size_t length) {
    PrintedShape shape;
#if defined(__x86_64__)
    const int time_digits = leading_digits(load_word(line));
    const char* const value = line + time_digits + 1;
    if (length != static_cast<std::size_t>(time_digits) + 5 || !is_digit(value[0]) || value[1] != '.' ||
        !is_digit(value[2]) || !is_digit(value[3]))
      return shape;  // a value printed some other way ("-1.5", "-.25", "12.5")
    const char* const stop = line + length;
    const bool crlf = stop[0] == '\r' && stop[1] == '\n';
    if (!crlf && stop[0] != '\n') return shape;  // a lone CR: the next line's end could differ
    const std::size_t bytes = length + (crlf ? 2 : 1);
    alignas(16) unsigned char pattern[16] = {}, most[16];
    std::memset(most, 0xFF, sizeof most);  // bytes after the line: anything
    for (std::size_t i = 0; i < bytes; ++i) {
      const bool digit = is_digit(line[i]);
      pattern[i] = digit ? '0' : static_cast<unsigned char>(line[i]);
      most[i] = digit ? 9 : 0;
    }
    shape.pattern_ = _mm_load_si128(reinterpret_cast<const __m128i*>(pattern));
    shape.most_ = _mm_load_si128(reinterpret_cast<const __m128i*>(most));
    shape.time_digits_ = time_digits;
    shape.bytes_ = bytes;
#else
    (void)line;
    (void)length;
#endif
    return shape;
  }

  // Takes the lines printed this way from p on, at most room, while a line starts at or before
  // last (so 16 bytes are readable): writes their numbers, as printed_line gives them, to
  // millis and values and returns how many. A tight loop: the shape stays in registers.
  std::size_t take_alike(const char* p, const char* last, std::size_t room, double* millis, double* values) const {
    std::size_t n = 0;
#if defined(__x86_64__)
    if (bytes_ == 0 || p > last) return 0;
    const std::size_t most_lines = std::min(room, static_cast<std::size_t>(last - p) / bytes_ + 1);
    const __m128i pattern = pattern_, most = most_;
    const int time_shift = 8 * (8 - time_digits_);
    for (; n < most_lines; ++n, p += bytes_) {
      const __m128i x = _mm_xor_si128(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p)), pattern);
      if (_mm_movemask_epi8(_mm_cmpeq_epi8(_mm_min_epu8(x, most), x)) != 0xFFFF) break;  // a byte over its most
      // x's first bytes are the time's digit values; the shift drops the bytes after them.
      millis[n] = static_cast<double>(eight_digits_value(static_cast<std::uint64_t>(_mm_cvtsi128_si64(x)) << time_shift));
      const char* const v = p + time_digits_ + 1;  // "d.dd"
      const unsigned mantissa = (static_cast<unsigned char>(v[0]) - unsigned{'0'}) * 100 +
                                (static_cast<unsigned char>(v[2]) - unsigned{'0'}) * 10 +
                                (static_cast<unsigned char>(v[3]) - unsigned{'0'});
      values[n] = plain_decimal_value(mantissa, 2, false);
    }
#else
    (void)p;
    (void)last;
    (void)room;
    (void)millis;
    (void)values;
#endif
    return n;
  }

  // The line's bytes, its terminator included.
  std::size_t bytes() const { return bytes_; }

 private:
#if defined(__x86_64__)
  __m128i pattern_ = _mm_setzero_si128();
  __m128i most_ = _mm_setzero_si128();
#endif
  int time_digits_ = 0;
  std::size_t bytes_ = 0;  // 0: no shape
};

}  // namespace

std::size_t parse_printed_sample(std::string_view text, LabLine& sample) {
  if constexpr (std::endian::native != std::endian::little) return 0;
  if (text.size() < enough_text) return 0;
  std::uint64_t ticks = 0;
  double value = 0;
  const std::size_t length = printed_line(text.data(), ticks, value);
  if (length > 0) sample = sample_line(ticks, value);
  return length;
}

PrintedLines parse_printed_lines(std::string_view text, std::size_t max_lines, std::vector<double>& millis,
                                 std::vector<double>& values) {
  PrintedLines taken;
  if constexpr (std::endian::native != std::endian::little) return taken;
  const char* p = text.data();
  const char* const end = p + text.size();
  std::uint64_t ticks = 0;
  double value = 0;
  // A line the fast path does not take (a header, garble) costs only this one try: no room made.
  std::size_t length = max_lines > 0 && text.size() >= enough_text ? printed_line(p, ticks, value) : 0;
  if (length == 0) return taken;
  // Room for every line that can be taken (each is at least 4 bytes, "0 0\n"), written through
  // plain pointers, then cut to what was taken: cheaper than a push_back per line.
  const std::size_t room = std::min(max_lines, text.size() / 4);
  const std::size_t base = millis.size();
  millis.resize(base + room);
  values.resize(base + room);
  double* const millis_out = millis.data() + base;
  double* const values_out = values.data() + base;
  const char* const last = end - enough_text;  // the last line start the fast path may read from
  while (true) {
    millis_out[taken.lines] = static_cast<double>(ticks);
    values_out[taken.lines] = value;
    ++taken.lines;
    // The sketch's next lines are usually printed like this one: taken by its shape, in a run.
    const PrintedShape shape = PrintedShape::of(p, length);
    p += length + terminator_length(p + length);
    const std::size_t alike =
        shape.take_alike(p, last, room - taken.lines, millis_out + taken.lines, values_out + taken.lines);
    taken.lines += alike;
    p += alike * shape.bytes();
    if (taken.lines == room || p > last) break;
    length = printed_line(p, ticks, value);
    if (length == 0) break;
  }
  millis.resize(base + taken.lines);
  values.resize(base + taken.lines);
  taken.bytes = static_cast<std::size_t>(p - text.data());
  return taken;
}

}  // namespace spindown
