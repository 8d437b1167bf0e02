#include "spindown/spindown_protocol.hpp"

#include <charconv>
#include <cmath>
#include <fmt/format.h>

namespace spindown {

namespace {

// Unsigned decimal of 1-10 digits that fits in uint32; no sign, no spaces.
bool parse_u32(std::string_view s, std::uint32_t& out) {
  if (s.empty() || s.size() > 10) return false;
  std::uint64_t v = 0;
  for (char c : s) {
    if (c < '0' || c > '9') return false;
    v = v * 10 + std::uint64_t(c - '0');
  }
  if (v > 0xFFFFFFFFull) return false;
  out = static_cast<std::uint32_t>(v);
  return true;
}

int hex_digit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  return -1;
}

// Splits "body*CC", checks the CRC. Returns the body or sets why.
bool check_crc(std::string_view line, std::string_view& body, std::string_view& why) {
  const auto star = line.rfind('*');
  if (star == std::string_view::npos) {
    why = "no '*' checksum";
    return false;
  }
  const auto cc = line.substr(star + 1);
  if (cc.size() != 2 || hex_digit(cc[0]) < 0 || hex_digit(cc[1]) < 0) {
    why = "checksum is not two hex digits";
    return false;
  }
  body = line.substr(0, star);
  const auto want = static_cast<std::uint8_t>(hex_digit(cc[0]) * 16 + hex_digit(cc[1]));
  if (spindown_crc8(body) != want) {
    why = "checksum mismatch";
    return false;
  }
  return true;
}

SpindownLine garbled_spindown_line(std::string_view why) {
  SpindownLine l;
  l.kind = SpindownLine::Kind::garbled;
  l.why = why;
  return l;
}

SpindownLine parse_sample(std::string_view body) {
  // body = "S,<seq>,<micros>,<adc>"
  body.remove_prefix(2);
  std::string_view f[3];
  for (int i = 0; i < 3; ++i) {
    const auto comma = body.find(',');
    if (i < 2) {
      if (comma == std::string_view::npos) return garbled_spindown_line("sample has fewer than 3 fields");
      f[i] = body.substr(0, comma);
      body.remove_prefix(comma + 1);
    } else {
      if (comma != std::string_view::npos) return garbled_spindown_line("sample has more than 3 fields");
      f[i] = body;
    }
  }
  SpindownLine l;
  std::uint32_t adc = 0;
  if (!parse_u32(f[0], l.seq)) return garbled_spindown_line("sequence number is not a uint32");
  if (!parse_u32(f[1], l.time_us)) return garbled_spindown_line("micros is not a uint32");
  if (!parse_u32(f[2], adc) || adc > 65535) return garbled_spindown_line("ADC count is not 0-65535");
  l.adc = static_cast<std::int32_t>(adc);
  l.kind = SpindownLine::Kind::sample;
  return l;
}

SpindownLine parse_banner(std::string_view body) {
  // body = "#spindown-v1 key=value key=value …"
  body.remove_prefix(1 + spindown_protocol_name.size());
  SpindownLine l;
  SpindownBanner& b = l.banner;
  bool have_fw = false, have_ver = false, have_time = false, have_value = false, have_bits = false,
       have_ref = false, have_period = false, have_baud = false;
  for (int guard = 0; guard < 64 && !body.empty(); ++guard) {
    while (!body.empty() && body.front() == ' ') body.remove_prefix(1);
    if (body.empty()) break;
    const auto sp = body.find(' ');
    const auto kv = body.substr(0, sp);
    body.remove_prefix(sp == std::string_view::npos ? body.size() : sp);
    const auto eq = kv.find('=');
    if (eq == std::string_view::npos || eq == 0) return garbled_spindown_line("banner field is not key=value");
    const auto key = kv.substr(0, eq);
    const auto val = kv.substr(eq + 1);
    std::uint32_t u = 0;
    if (key == "firmware") {
      if (val.empty()) return garbled_spindown_line("banner firmware is empty");
      b.firmware = val, have_fw = true;
    } else if (key == "version") {
      if (val.empty()) return garbled_spindown_line("banner version is empty");
      b.version = val, have_ver = true;
    } else if (key == "time") {
      if (val != "us") return garbled_spindown_line("banner time unit is not 'us'");
      have_time = true;
    } else if (key == "value") {
      if (val != "adc") return garbled_spindown_line("banner value unit is not 'adc'");
      have_value = true;
    } else if (key == "adc_bits") {
      if (!parse_u32(val, u) || u < 1 || u > 16) return garbled_spindown_line("banner adc_bits is not 1-16");
      b.adc_bits = int(u), have_bits = true;
    } else if (key == "adc_ref_v") {
      double v = 0;
      const auto r = std::from_chars(val.data(), val.data() + val.size(), v);
      if (r.ec != std::errc{} || r.ptr != val.data() + val.size() || !std::isfinite(v) || v <= 0 || v > 100)
        return garbled_spindown_line("banner adc_ref_v is not a voltage in (0, 100]");
      b.adc_ref_v = v, have_ref = true;
    } else if (key == "period_us") {
      if (!parse_u32(val, u) || u == 0) return garbled_spindown_line("banner period_us is not a positive integer");
      b.period_us = u, have_period = true;
    } else if (key == "baud") {
      if (!parse_u32(val, u) || u == 0 || u > 10'000'000) return garbled_spindown_line("banner baud is not a baud rate");
      b.baud = std::int32_t(u), have_baud = true;
    }  // unknown keys: later firmware may add fields
  }
  if (!(have_fw && have_ver && have_time && have_value && have_bits && have_ref && have_period && have_baud))
    return garbled_spindown_line("banner lacks a required field");
  l.kind = SpindownLine::Kind::banner;
  return l;
}

}  // namespace

std::uint8_t spindown_crc8(std::string_view bytes) {
  std::uint8_t crc = 0;
  for (char ch : bytes) {
    crc ^= static_cast<std::uint8_t>(ch);
    for (int i = 0; i < 8; ++i) crc = (crc & 0x80) ? static_cast<std::uint8_t>((crc << 1) ^ 0x07) : static_cast<std::uint8_t>(crc << 1);
  }
  return crc;
}

bool looks_like_spindown_line(std::string_view line) {
  return line.starts_with("S,") || line.starts_with('#');
}

SpindownLine parse_spindown_line(std::string_view line) {
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  if (line.empty()) {
    SpindownLine l;
    l.kind = SpindownLine::Kind::blank;
    return l;
  }
  if (!looks_like_spindown_line(line)) return garbled_spindown_line("not a spindown-v1 line (want 'S,' or '#')");
  std::string_view body, why;
  if (!check_crc(line, body, why)) return garbled_spindown_line(why);
  if (line.front() == 'S') return parse_sample(body);
  if (body.substr(1).starts_with(spindown_protocol_name) &&
      (body.size() == 1 + spindown_protocol_name.size() || body[1 + spindown_protocol_name.size()] == ' '))
    return parse_banner(body);
  SpindownLine l;
  l.kind = SpindownLine::Kind::note;
  l.text = body.substr(1);
  return l;
}

namespace {
std::string with_crc(std::string body) {
  const auto crc = spindown_crc8(body);
  return fmt::format("{}*{:02X}\r\n", body, crc);
}
}  // namespace

std::string format_spindown_sample(std::uint32_t seq, std::uint32_t time_us, int adc) {
  return with_crc(fmt::format("S,{},{},{}", seq, time_us, adc));
}

std::string format_spindown_banner(const SpindownBanner& b) {
  return with_crc(fmt::format("#{} firmware={} version={} time=us value=adc adc_bits={} adc_ref_v={:.3f} "
                              "period_us={} baud={}",
                              spindown_protocol_name, b.firmware, b.version, b.adc_bits, b.adc_ref_v,
                              b.period_us, b.baud));
}

std::string format_spindown_note(std::string_view text) { return with_crc(fmt::format("#{}", text)); }

}  // namespace spindown
