// The virtual bench's bytes, fed straight into the bridge logic (no pty, no LCM): what the
// bridge publishes is exactly what the bench says it sent, faults included.
#include <gtest/gtest.h>

#include <cmath>

#include "spindown/serial_bridge.hpp"
#include "spindown/virtual_bench.hpp"

using namespace spindown;

namespace {
struct CaptureSink : BridgeSink {
  std::vector<samples_t> samples;
  void publish(const samples_t& m) override { samples.push_back(m); }
  void publish(const config_t&) override {}
  void publish(const status_t&) override {}
};

// The bridge's settings for the virtual bench "vb".
BridgeSettings vb_settings(int baud = 0) {
  BridgeSettings s;
  s.bench = "vb";
  s.device = "/dev/vb";
  if (baud) s.baud = baud;
  return s;
}

void replay(const VirtualBench& bench, SerialBridge& bridge) {
  std::int64_t t = 0;
  bridge.start(t);
  bridge.connected(t);
  for (const auto& e : bench.emissions()) {
    t = std::int64_t(e.wire_s * 1e6);
    if (e.kind == BenchEmission::Kind::unplug) {
      bridge.disconnected(t, "unplugged");
      bridge.connected(t + 1);
      continue;
    }
    bridge.feed(e.bytes, t);
  }
}

void expect_same(const VirtualBench& bench, const CaptureSink& sink) {
  std::size_t k = 0;
  for (const auto& m : sink.samples)
    for (int i = 0; i < m.n; ++i, ++k) {
      ASSERT_LT(k, bench.sent().size());
      const auto& s = bench.sent()[k];
      ASSERT_EQ(m.seq + i, std::int64_t(k));
      ASSERT_EQ(m.clock_epoch, s.epoch) << "sample " << k;
      ASSERT_EQ(m.device_time_us[i], s.device_time_us) << "sample " << k;
      ASSERT_NEAR(m.value[i], s.value, 1e-12) << "sample " << k;
      ASSERT_EQ(m.raw_adc[i], s.raw_adc) << "sample " << k;
    }
  EXPECT_EQ(k, bench.sent().size());
}
}  // namespace

TEST(VirtualBench, LabRunsReplayExactly) {
  VirtualBenchOptions o;
  o.runs = 2;
  o.spec.lead_in = LeadIn::supply;
  VirtualBench bench(o);
  ASSERT_GT(bench.sent().size(), 1000u);
  EXPECT_EQ(bench.truth()["runs"].size(), 2u);
  EXPECT_TRUE(bench.truth()["runs"][0]["stopped"].get<bool>());
  CaptureSink sink;
  SerialBridge bridge(vb_settings(), sink);
  replay(bench, bridge);
  expect_same(bench, sink);
  EXPECT_EQ(bridge.counters().lines_bad, 0);
  // Paced at 9600 baud: a line's last byte leaves ≥ 10 bits per byte after the previous one.
  const auto& em = bench.emissions();
  for (std::size_t i = 1; i < em.size(); ++i)
    ASSERT_GE(em[i].wire_s - em[i - 1].wire_s, em[i].bytes.size() * 10.0 / 9600 - 1e-12);
}

// decimals < 0 is "full precision" (SyntheticRunSpec): every digit of the reading is printed,
// and the bridge reads back the very double; it printed whole volts ("3") before.
TEST(VirtualBench, FullPrecisionPrintsEveryDigit) {
  EXPECT_EQ(printed_value(2.75390625, 2), "2.75");
  EXPECT_EQ(printed_value(2.75390625, -1), "2.75390625");
  EXPECT_EQ(printed_value(0.1, -1), "0.1");
  VirtualBenchOptions o;
  o.spec.decimals = -1;
  VirtualBench bench(o);
  std::size_t fractional = 0;
  for (const auto& s : bench.sent()) fractional += s.value != std::round(s.value);
  EXPECT_GT(fractional, bench.sent().size() / 2) << "readings printed as whole volts";
  CaptureSink sink;
  SerialBridge bridge(vb_settings(), sink);
  replay(bench, bridge);
  expect_same(bench, sink);
}

TEST(VirtualBench, FaultsAreCountedAndSamplesStillMatch) {
  VirtualBenchOptions o;
  o.protocol = BenchProtocol::spindown_v1;
  o.spec.period_s = 0.010;
  o.runs = 2;
  o.garbage_every = 30;
  o.partial_every = 45;
  o.reset_at_s = {6.0};
  o.unplug_at_s = 12;
  o.long_line_at_s = 3;
  o.long_line_bytes = 100'000;
  VirtualBench bench(o);
  CaptureSink sink;
  SerialBridge bridge(vb_settings(115200), sink);
  replay(bench, bridge);
  expect_same(bench, sink);
  const auto& f = bench.truth()["faults"];
  const auto& c = bridge.counters();
  EXPECT_EQ(c.lines_bad, f["garbage_lines"].get<std::int64_t>() + f["partial_lines"].get<std::int64_t>() + 1);
  EXPECT_EQ(c.oversize_lines, 1);
  EXPECT_EQ(c.device_resets, 2);
  EXPECT_EQ(c.reconnects, 1);
  EXPECT_EQ(c.device_seq_gaps, f["partial_lines"].get<std::int64_t>());  // a cut line is a lost sample
}

TEST(VirtualBench, WrongBaudGarbageNeverBecomesSamples) {
  VirtualBenchOptions o;
  o.protocol = BenchProtocol::spindown_v1;
  VirtualBench bench(o);
  CaptureSink sink;
  SerialBridge bridge(vb_settings(), sink);
  bridge.start(0);
  std::uint64_t state = 1;
  for (int reader : {9600, 57600, 230400, 1000000})
    for (const auto& e : bench.emissions()) bridge.feed(garble_for_baud(e.bytes, 115200, reader, state), 0);
  EXPECT_TRUE(sink.samples.empty());
  EXPECT_GT(bridge.counters().lines_bad, 100);
}

TEST(VirtualBench, RejectsImpossibleOptions) {
  VirtualBenchOptions o;
  o.protocol = BenchProtocol::spindown_v1;
  o.spec.period_s = 0.05;  // the firmware does 1-20 ms
  EXPECT_THROW(VirtualBench{o}, std::invalid_argument);
  o = {};
  o.runs = 0;
  EXPECT_THROW(VirtualBench{o}, std::invalid_argument);
}
