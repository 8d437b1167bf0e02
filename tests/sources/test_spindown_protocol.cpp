#include <gtest/gtest.h>

#include "spindown/spindown_protocol.hpp"

using namespace spindown;

namespace {
std::string strip(std::string s) {
  while (!s.empty() && (s.back() == '\n' || s.back() == '\r')) s.pop_back();
  return s;
}
}  // namespace

TEST(SpindownProtocol, Crc8IsSmbus) {
  // CRC-8/SMBUS check value of "123456789" is 0xF4.
  EXPECT_EQ(spindown_crc8("123456789"), 0xF4);
  EXPECT_EQ(spindown_crc8(""), 0x00);
}

TEST(SpindownProtocol, SampleRoundTrips) {
  const auto text = format_spindown_sample(4294967295u, 123456789u, 1023);
  EXPECT_TRUE(text.ends_with("\r\n"));
  const auto l = parse_spindown_line(text.substr(0, text.size() - 1));  // CR tolerated
  ASSERT_EQ(l.kind, SpindownLine::Kind::sample) << l.why;
  EXPECT_EQ(l.seq, 4294967295u);
  EXPECT_EQ(l.time_us, 123456789u);
  EXPECT_EQ(l.adc, 1023);
}

TEST(SpindownProtocol, KnownLinesFromTheReadme) {
  // deploy/firmware/README.md quotes these exact lines.
  EXPECT_EQ(strip(format_spindown_sample(42, 1234567, 512)), "S,42,1234567,512*43");
  SpindownBanner b;
  b.firmware = "spindown-coast";
  b.version = "1.0.0";
  b.period_us = 5000;
  b.baud = 115200;
  EXPECT_EQ(strip(format_spindown_banner(b)),
            "#spindown-v1 firmware=spindown-coast version=1.0.0 time=us value=adc adc_bits=10 "
            "adc_ref_v=5.000 period_us=5000 baud=115200*05");
  const auto l = parse_spindown_line("S,42,1234567,512*43\r");
  ASSERT_EQ(l.kind, SpindownLine::Kind::sample);
  EXPECT_EQ(l.seq, 42u);
}

TEST(SpindownProtocol, BannerRoundTrips) {
  SpindownBanner b;
  b.firmware = "spindown-coast";
  b.version = "1.2.3";
  b.adc_bits = 10;
  b.adc_ref_v = 4.096;
  b.period_us = 5000;
  b.baud = 115200;
  const auto l = parse_spindown_line(strip(format_spindown_banner(b)));
  ASSERT_EQ(l.kind, SpindownLine::Kind::banner) << l.why;
  EXPECT_EQ(l.banner.firmware, "spindown-coast");
  EXPECT_EQ(l.banner.version, "1.2.3");
  EXPECT_EQ(l.banner.adc_bits, 10);
  EXPECT_DOUBLE_EQ(l.banner.adc_ref_v, 4.096);
  EXPECT_EQ(l.banner.period_us, 5000u);
  EXPECT_EQ(l.banner.baud, 115200);
  EXPECT_DOUBLE_EQ(l.banner.volts_per_count(), 4.096 / 1024);
}

TEST(SpindownProtocol, NoteIsNotABanner) {
  const std::string line = strip(format_spindown_note("period_us=5000 set"));  // text views into it
  const auto l = parse_spindown_line(line);
  ASSERT_EQ(l.kind, SpindownLine::Kind::note);
  EXPECT_EQ(l.text, "period_us=5000 set");
}

TEST(SpindownProtocol, RejectsCorruption) {
  const auto good = strip(format_spindown_sample(7, 1000, 300));
  std::string flipped = good;
  flipped[4] = flipped[4] == '1' ? '2' : '1';
  EXPECT_EQ(parse_spindown_line(flipped).kind, SpindownLine::Kind::garbled);
  EXPECT_EQ(parse_spindown_line(flipped).why, "checksum mismatch");
  EXPECT_EQ(parse_spindown_line("S,7,1000,300").why, "no '*' checksum");
  EXPECT_EQ(parse_spindown_line("S,7,1000,300*G1").why, "checksum is not two hex digits");
  EXPECT_EQ(parse_spindown_line("5234\t0.00").kind, SpindownLine::Kind::garbled);
  EXPECT_EQ(parse_spindown_line("").kind, SpindownLine::Kind::blank);
}

TEST(SpindownProtocol, RejectsBadFieldsEvenWithAValidChecksum) {
  auto with_crc = [](std::string body) {
    char b[4];
    std::snprintf(b, sizeof b, "%02X", spindown_crc8(body));
    return body + "*" + b;
  };
  EXPECT_EQ(parse_spindown_line(with_crc("S,1,2")).why, "sample has fewer than 3 fields");
  EXPECT_EQ(parse_spindown_line(with_crc("S,1,2,3,4")).why, "sample has more than 3 fields");
  EXPECT_EQ(parse_spindown_line(with_crc("S,-1,2,3")).why, "sequence number is not a uint32");
  EXPECT_EQ(parse_spindown_line(with_crc("S,1,4294967296,3")).why, "micros is not a uint32");
  EXPECT_EQ(parse_spindown_line(with_crc("S,1,2,70000")).why, "ADC count is not 0-65535");
  EXPECT_EQ(parse_spindown_line(with_crc("S,1, 2,3")).why, "micros is not a uint32");
  EXPECT_EQ(parse_spindown_line(with_crc("#spindown-v1 firmware=x")).why, "banner lacks a required field");
  EXPECT_EQ(parse_spindown_line(with_crc("#spindown-v1 firmware=x version=1 time=ms value=adc adc_bits=10 "
                                         "adc_ref_v=5 period_us=1 baud=1"))
                .why,
            "banner time unit is not 'us'");
}

TEST(SpindownProtocol, LooksLikeSpindownOnlyForItsPrefixes) {
  EXPECT_TRUE(looks_like_spindown_line("S,1"));
  EXPECT_TRUE(looks_like_spindown_line("#x"));
  EXPECT_FALSE(looks_like_spindown_line("5234\t0.00"));
  EXPECT_FALSE(looks_like_spindown_line("S"));
}
