// Fuzz-style: 100,000+ random byte chunks (noise, fragments of valid lines of both protocols,
// corrupted lines, long runs without newline) through the line splitter, both parsers and the
// whole bridge logic. Invariants: no crash (run under ASan/UBSan too), bounded buffer, gapless
// seq, finite values, every line accounted for exactly once. Deterministic seed.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

#include "spindown/lab_line.hpp"
#include "spindown/serial_bridge.hpp"
#include "spindown/spindown_protocol.hpp"

using namespace spindown;

namespace {

struct CheckingSink : BridgeSink {
  std::int64_t next_seq = 0, samples = 0;
  bool ok = true;
  void publish(const samples_t& m) override {
    if (m.seq != next_seq || m.n <= 0 || std::size_t(m.n) != m.value.size() ||
        std::size_t(m.n) != m.device_time_us.size() || std::size_t(m.n) != m.raw_adc.size())
      ok = false;
    for (int i = 0; i < m.n; ++i)
      if (!std::isfinite(m.value[i]) || m.device_time_us[i] < 0) ok = false;
    next_seq += m.n;
    samples += m.n;
  }
  void publish(const config_t&) override {}
  void publish(const status_t&) override {}
};

std::string random_chunk(std::mt19937_64& rng) {
  std::uniform_int_distribution<int> kind(0, 9), byte(0, 255), len(0, 64);
  std::string out;
  switch (kind(rng)) {
    case 0:
    case 1: {  // raw noise
      const int n = len(rng);
      for (int i = 0; i < n; ++i) out += char(byte(rng));
      break;
    }
    case 2:  // a valid lab line
      out = std::to_string(rng() % 5'000'000'000ull) + "\t" + std::to_string(int(rng() % 600) / 100.0) + "\r\n";
      break;
    case 3:  // a valid spindown-v1 line
      out = format_spindown_sample(std::uint32_t(rng()), std::uint32_t(rng()), int(rng() % 1100));
      break;
    case 4: {  // a valid line with a byte flipped or cut
      out = (rng() % 2) ? format_spindown_sample(std::uint32_t(rng()), std::uint32_t(rng()), 5)
                        : std::to_string(rng() % 100000) + "\t1.23\r\n";
      const std::size_t at = rng() % out.size();
      if (rng() % 2) out[at] = char(byte(rng));
      else out.resize(at);
      break;
    }
    case 5: {  // a long run without newline
      out.assign(std::size_t(200 + rng() % 3000), char(byte(rng)) == '\n' ? 'x' : '7');
      break;
    }
    case 6: {  // banners, good and bad
      SpindownBanner b;
      b.firmware = "fw";
      b.version = "1";
      b.adc_bits = int(1 + rng() % 16);
      b.period_us = std::uint32_t(1 + rng() % 20000);
      b.baud = 115200;
      out = format_spindown_banner(b);
      if (rng() % 3 == 0) out[rng() % out.size()] = char(byte(rng));
      break;
    }
    case 7:  // newlines and CRs
      out = std::string(std::size_t(rng() % 4), '\n') + "\r" + std::string(std::size_t(rng() % 2), '\n');
      break;
    default: {  // printable junk with separators
      static const char alphabet[] = "0123456789.-+eE\t ,S#*nainfAF";
      const int n = len(rng);
      for (int i = 0; i < n; ++i) out += alphabet[rng() % (sizeof alphabet - 1)];
      if (rng() % 2) out += "\r\n";
    }
  }
  return out;
}

}  // namespace

TEST(BridgeFuzz, HundredThousandRandomChunks) {
  std::mt19937_64 rng(20240914);
  CheckingSink sink;
  BridgeSettings s;
  s.bench = "fuzz";
  s.device = "/dev/fuzz";
  s.max_line_bytes = 512;
  SerialBridge bridge(s, sink);
  bridge.start(0);
  CheckingSink steady_sink;  // a second bridge that never disconnects: its line counts are exact
  SerialBridge steady(s, steady_sink);
  steady.start(0);
  LineSplitter splitter(512);
  std::int64_t lines = 0, oversize = 0;
  const LineSplitter::Handler count = [&](const LineSplitter::Line& l) {
    ++lines;
    if (l.oversize) ++oversize;
    ASSERT_LE(l.text.size(), 512u);
    // Both parsers on every line: total functions, never throw, stay in range.
    const LabLine lab = parse_lab_line(l.text);
    if (lab.kind == LabLine::Kind::sample) {
      ASSERT_GE(lab.millis, 0);
      ASSERT_TRUE(std::isfinite(lab.value));
    } else if (lab.kind == LabLine::Kind::garbled) {
      ASSERT_FALSE(lab.why.empty());
    }
    const SpindownLine v1 = parse_spindown_line(l.text);
    if (v1.kind == SpindownLine::Kind::garbled) {
      ASSERT_FALSE(v1.why.empty());
    }
    if (v1.kind == SpindownLine::Kind::sample) {
      ASSERT_LE(v1.adc, 65535);
    }
  };
  constexpr int kChunks = 120'000;
  for (int i = 0; i < kChunks; ++i) {
    const std::string chunk = random_chunk(rng);
    // Parsers on the raw chunk too (it may hold several lines, or none).
    (void)parse_lab_line(chunk);
    (void)parse_spindown_line(chunk);
    splitter.feed(chunk, count);
    bridge.feed(chunk, std::int64_t(i) * 1000);
    steady.feed(chunk, std::int64_t(i) * 1000);
    if (i % 1000 == 0) {
      bridge.tick(std::int64_t(i) * 1000);
      if (i % 7000 == 0) bridge.disconnected(std::int64_t(i) * 1000, "fuzz unplug");
      if (i % 7000 == 0) bridge.connected(std::int64_t(i) * 1000);
    }
    ASSERT_LE(splitter.buffered(), 512u);
    ASSERT_LE(bridge.buffered_bytes(), 512u);
  }
  EXPECT_TRUE(sink.ok);
  const auto& c = bridge.counters();
  EXPECT_EQ(sink.samples, c.samples);
  EXPECT_GT(c.samples, 5000);       // the valid lines got through
  EXPECT_GT(c.lines_bad, 10000);    // and the junk was counted
  EXPECT_GT(c.oversize_lines, 100);
  EXPECT_GT(lines, 50000);
  EXPECT_GT(oversize, 100);
  // Every line is good, bad or blank, exactly once.
  EXPECT_TRUE(steady_sink.ok);
  const auto& sc = steady.counters();
  EXPECT_EQ(sc.lines_good + sc.lines_bad + sc.lines_blank, lines);
  EXPECT_EQ(sc.oversize_lines, oversize);
}
