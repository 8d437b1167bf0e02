#pragma once
// The improved firmware's serial protocol "spindown-v1" (deploy/firmware/README.md is the
// normative text; this parser implements exactly that). One line per record, CR LF:
//   banner  #spindown-v1 firmware=NAME version=X.Y.Z time=us value=adc adc_bits=10
//           adc_ref_v=5.000 period_us=20000 baud=115200*CC
//   sample  S,<seq>,<micros>,<adc>*CC
//   note    #<free text>*CC
// CC = CRC-8 (poly 0x07, init 0, no reflection: CRC-8/SMBUS) of every byte before '*', two
// hex digits. seq and micros are the firmware's uint32 counters (both wrap at 2^32).
// A pure function so the bridge, tests and fuzzers share it.
#include <cstdint>
#include <string>
#include <string_view>

namespace spindown {

inline constexpr std::string_view spindown_protocol_name = "spindown-v1";

struct SpindownBanner {
  std::string firmware;          // e.g. "spindown-coast"
  std::string version;           // e.g. "1.0.0"
  int adc_bits = 10;
  double adc_ref_v = 5.0;
  std::uint32_t period_us = 0;   // nominal loop period
  std::int32_t baud = 0;
  // The largest count the converter gives (2^bits − 1).
  std::int32_t max_count() const { return (std::int32_t{1} << adc_bits) - 1; }
  // Volts per ADC count as the converter defines it: the ATmega328P datasheet's
  // ADC = V_in·1024/V_ref, so V = count·V_ref/2^bits (deploy/firmware/README.md). The lab
  // sketch's own `× 5.0 / 1023` reads 0.1 % high; that is its protocol's business, not this one's.
  double volts_per_count() const { return adc_ref_v / double(std::int32_t{1} << adc_bits); }
  // A sample's count in volts: the one conversion of spindown-v1 counts, shared by the serial
  // bridge and the file reader (spindown_text.hpp) so that both give the same numbers. Before
  // any banner, a default-constructed banner gives the protocol's defaults.
  double volts(std::int32_t adc) const { return adc * volts_per_count(); }
};

struct SpindownLine {
  enum class Kind { sample, banner, note, blank, garbled };
  Kind kind = Kind::garbled;
  std::uint32_t seq = 0;      // Kind::sample
  std::uint32_t time_us = 0;  // Kind::sample: micros() as printed
  std::int32_t adc = 0;       // Kind::sample: 0 … 65535 (the bridge checks adc_bits)
  SpindownBanner banner;      // Kind::banner
  std::string_view text;      // Kind::note: text between '#' and '*' (a view into the line)
  std::string_view why;       // Kind::garbled: what was wrong (static storage)
};

// CRC-8/SMBUS: poly 0x07, init 0x00, MSB first, no final xor.
std::uint8_t spindown_crc8(std::string_view bytes);

// True when the line is meant to be spindown-v1 ("S," or '#' first): the bridge then parses it
// with parse_spindown_line, otherwise with the lab parser.
bool looks_like_spindown_line(std::string_view line);

// Parses one line without its terminator (a trailing CR is tolerated).
SpindownLine parse_spindown_line(std::string_view line);

// The exact text the firmware prints, with "\r\n" (for the virtual bench and tests).
std::string format_spindown_sample(std::uint32_t seq, std::uint32_t time_us, int adc);
std::string format_spindown_banner(const SpindownBanner& banner);
std::string format_spindown_note(std::string_view text);

}  // namespace spindown
