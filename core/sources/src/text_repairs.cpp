#include "spindown/text_repairs.hpp"

#include <cstddef>
#include <cstdint>
#include <fmt/format.h>

namespace spindown {

namespace {

constexpr std::size_t head_bytes = 8192;  // what the checks look at
constexpr bool is_digit(char c) { return c >= '0' && c <= '9'; }

enum class Utf16 { none, little_endian, big_endian };

// A byte-order mark, or (no mark) ASCII text every other byte of which is NUL.
Utf16 utf16_kind(std::string_view text, bool* has_bom) {
  *has_bom = false;
  if (text.size() >= 2) {
    const auto b0 = static_cast<unsigned char>(text[0]), b1 = static_cast<unsigned char>(text[1]);
    if (b0 == 0xFF && b1 == 0xFE) return *has_bom = true, Utf16::little_endian;
    if (b0 == 0xFE && b1 == 0xFF) return *has_bom = true, Utf16::big_endian;
  }
  const std::size_t n = std::min(text.size(), std::size_t{512}) & ~std::size_t{1};
  if (n < 16) return Utf16::none;
  std::size_t even_nul = 0, odd_nul = 0;
  for (std::size_t i = 0; i < n; i += 2) {
    even_nul += text[i] == '\0';
    odd_nul += text[i + 1] == '\0';
  }
  const std::size_t pairs = n / 2;
  if (odd_nul * 10 >= pairs * 9 && even_nul * 20 <= pairs) return Utf16::little_endian;
  if (even_nul * 10 >= pairs * 9 && odd_nul * 20 <= pairs) return Utf16::big_endian;
  return Utf16::none;
}

void append_utf8(std::string& out, std::uint32_t cp) {
  if (cp < 0x80) {
    out += static_cast<char>(cp);
  } else if (cp < 0x800) {
    out += static_cast<char>(0xC0 | (cp >> 6));
    out += static_cast<char>(0x80 | (cp & 0x3F));
  } else if (cp < 0x10000) {
    out += static_cast<char>(0xE0 | (cp >> 12));
    out += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
    out += static_cast<char>(0x80 | (cp & 0x3F));
  } else {
    out += static_cast<char>(0xF0 | (cp >> 18));
    out += static_cast<char>(0x80 | ((cp >> 12) & 0x3F));
    out += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
    out += static_cast<char>(0x80 | (cp & 0x3F));
  }
}

// UTF-16 to UTF-8; a lone surrogate or an odd last byte becomes U+FFFD.
std::string utf16_to_utf8(std::string_view text, Utf16 kind, bool skip_bom) {
  std::string out;
  out.reserve(text.size() / 2 + 16);
  const auto unit = [&](std::size_t i) -> std::uint32_t {
    const auto a = static_cast<unsigned char>(text[i]), b = static_cast<unsigned char>(text[i + 1]);
    return kind == Utf16::little_endian ? (std::uint32_t(b) << 8 | a) : (std::uint32_t(a) << 8 | b);
  };
  std::size_t i = skip_bom ? 2 : 0;
  for (; i + 1 < text.size(); i += 2) {
    const std::uint32_t u = unit(i);
    if (u >= 0xD800 && u <= 0xDBFF && i + 3 < text.size()) {
      const std::uint32_t lo = unit(i + 2);
      if (lo >= 0xDC00 && lo <= 0xDFFF) {
        append_utf8(out, 0x10000 + ((u - 0xD800) << 10) + (lo - 0xDC00));
        i += 2;
        continue;
      }
    }
    append_utf8(out, u >= 0xD800 && u <= 0xDFFF ? 0xFFFD : u);
  }
  if (i < text.size()) append_utf8(out, 0xFFFD);
  return out;
}

// "10:21:38.234 -> ": the Arduino IDE serial monitor's "Show timestamp". Its length, or 0.
std::size_t timestamp_prefix(std::string_view line) {
  constexpr std::string_view shape = "00:00:00.000 -> ";
  if (line.size() < shape.size()) return 0;
  for (std::size_t i = 0; i < shape.size(); ++i) {
    if (shape[i] == '0' ? !is_digit(line[i]) : line[i] != shape[i]) return 0;
  }
  return shape.size();
}

// A line of the lab's two columns whose value has a decimal comma: "<digits><TAB|spaces>[-]
// <digits>,<digits>" and trailing space or CR. Sets *comma to the comma's offset.
bool comma_sample(std::string_view line, std::size_t* comma) {
  std::size_t i = 0;
  while (i < line.size() && line[i] == ' ') ++i;
  const std::size_t t0 = i;
  while (i < line.size() && is_digit(line[i])) ++i;
  if (i == t0 || i == line.size() || (line[i] != '\t' && line[i] != ' ')) return false;
  while (i < line.size() && (line[i] == '\t' || line[i] == ' ')) ++i;
  if (i < line.size() && line[i] == '-') ++i;
  const std::size_t v0 = i;
  while (i < line.size() && is_digit(line[i])) ++i;
  if (i == v0 || i == line.size() || line[i] != ',') return false;
  *comma = i++;
  const std::size_t f0 = i;
  while (i < line.size() && is_digit(line[i])) ++i;
  if (i == f0) return false;
  while (i < line.size() && (line[i] == ' ' || line[i] == '\r')) ++i;
  return i == line.size();
}

// The same line with a decimal point: "5234\t2.45".
bool point_sample(std::string_view line) {
  std::size_t i = 0;
  while (i < line.size() && is_digit(line[i])) ++i;
  if (i == 0 || i == line.size() || (line[i] != '\t' && line[i] != ' ')) return false;
  while (i < line.size() && (line[i] == '\t' || line[i] == ' ')) ++i;
  if (i < line.size() && line[i] == '-') ++i;
  const std::size_t v0 = i;
  while (i < line.size() && is_digit(line[i])) ++i;
  return i > v0 && i < line.size() && line[i] == '.';
}

template <class F>
void each_line(std::string_view text, std::size_t limit, F&& f) {
  std::size_t pos = 0;
  while (pos < text.size() && pos < limit) {
    std::size_t nl = text.find('\n', pos);
    if (nl == std::string_view::npos) nl = text.size();
    f(text.substr(pos, nl - pos), pos);
    pos = nl + 1;
  }
}

struct HeadCounts {
  std::size_t lines = 0, timestamped = 0, comma = 0, point = 0;
};

HeadCounts count_head(std::string_view text) {
  HeadCounts c;
  each_line(text, head_bytes, [&](std::string_view line, std::size_t) {
    if (line.empty() || line == "\r") return;
    ++c.lines;
    const std::size_t skip = timestamp_prefix(line);
    c.timestamped += skip > 0;
    line.remove_prefix(skip);
    std::size_t comma = 0;
    c.comma += comma_sample(line, &comma);
    c.point += point_sample(line);
  });
  return c;
}

bool timestamps_to_strip(const HeadCounts& c) { return c.timestamped >= 3 && c.timestamped * 2 >= c.lines; }
bool commas_to_read(const HeadCounts& c) { return c.comma >= 5 && c.point == 0; }

}  // namespace

bool needs_text_repair(std::string_view text) {
  bool bom = false;
  if (utf16_kind(text, &bom) != Utf16::none) return true;
  const HeadCounts c = count_head(text);
  return timestamps_to_strip(c) || commas_to_read(c);
}

std::vector<std::string> repair_text(std::string& text) {
  std::vector<std::string> notes;
  bool bom = false;
  if (const Utf16 kind = utf16_kind(text, &bom); kind != Utf16::none) {
    text = utf16_to_utf8(text, kind, bom);
    notes.push_back(fmt::format("read as UTF-16 ({}{}), as a Windows editor saves \"Unicode\" text",
                                kind == Utf16::little_endian ? "little-endian" : "big-endian",
                                bom ? ", with a byte-order mark" : ", no byte-order mark"));
  }
  const HeadCounts c = count_head(text);
  const bool strip = timestamps_to_strip(c), commas = commas_to_read(c);
  if (!strip && !commas) return notes;
  std::string out;
  out.reserve(text.size());
  std::size_t stripped = 0, converted = 0;
  each_line(text, text.size(), [&](std::string_view line, std::size_t pos) {
    const bool newline = pos + line.size() < text.size();  // the line ended in '\n'
    if (strip) {
      const std::size_t skip = timestamp_prefix(line);
      stripped += skip > 0;
      line.remove_prefix(skip);
    }
    std::size_t comma = 0;
    if (commas && comma_sample(line, &comma)) {
      out.append(line.substr(0, comma));
      out += '.';
      out.append(line.substr(comma + 1));
      ++converted;
    } else {
      out.append(line);
    }
    if (newline) out += '\n';
  });
  text.swap(out);
  if (strip)
    notes.push_back(fmt::format("Arduino IDE serial monitor timestamps (\"10:21:38.234 -> \") removed from {} lines; "
                                "each sample's own millis is its time",
                                stripped));
  if (commas)
    notes.push_back(fmt::format("decimal commas read as points in {} lines (\"2,45\" is 2.45)", converted));
  return notes;
}

}  // namespace spindown
