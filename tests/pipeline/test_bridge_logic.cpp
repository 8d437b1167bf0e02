// spindown::SerialBridge driven directly: bytes in, samples_t/config_t/status_t out.
#include <gtest/gtest.h>
#include <fmt/format.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "spindown/read_recording.hpp"
#include "spindown/serial_bridge.hpp"

using namespace spindown;

namespace {

std::string fmt_sample(int millis, double value, char delimiter) {
  char line[64];
  std::snprintf(line, sizeof line, "%d%c%.4g\r\n", millis, delimiter, value);
  return line;
}

struct CaptureSink : BridgeSink {
  std::vector<samples_t> samples;
  std::vector<config_t> configs;
  std::vector<status_t> statuses;
  void publish(const samples_t& m) override { samples.push_back(m); }
  void publish(const config_t& m) override { configs.push_back(m); }
  void publish(const status_t& m) override { statuses.push_back(m); }

  struct Flat {
    std::int64_t seq;
    std::int32_t epoch;
    std::int64_t t_us;
    double value;
    std::int32_t adc;
  };
  std::vector<Flat> flat() const {
    std::vector<Flat> out;
    for (const auto& m : samples)
      for (int i = 0; i < m.n; ++i) out.push_back({m.seq + i, m.clock_epoch, m.device_time_us[i], m.value[i], m.raw_adc[i]});
    return out;
  }
};

std::int64_t counter(const status_t& s, const std::string& name) {
  for (int i = 0; i < s.ncounters; ++i)
    if (s.counter_name[i] == name) return s.counter_value[i];
  ADD_FAILURE() << "no counter " << name;
  return -1;
}
double gauge(const status_t& s, const std::string& name) {
  for (int i = 0; i < s.ngauges; ++i)
    if (s.gauge_name[i] == name) return s.gauge_value[i];
  ADD_FAILURE() << "no gauge " << name;
  return NAN;
}

BridgeSettings settings() {
  BridgeSettings s;
  s.bench = "b1";
  s.device = "/dev/ttyTEST";
  s.host = "testhost";
  s.pid = 42;
  return s;
}

constexpr std::int64_t T0 = 1'700'000'000'000'000;

// A bridge started and its port connected at T0, as after a board is plugged in.
void start_connected(SerialBridge& b) {
  b.start(T0);
  b.connected(T0);
}

}  // namespace

TEST(BridgeLogic, LabLinesBecomeSamplesWithGaplessSeq) {
  CaptureSink sink;
  SerialBridge b(settings(), sink);
  b.start(T0);
  b.connected(T0);
  b.feed("5234\t0.00\r\n5254\t2.8", T0 + 10);
  b.feed("1\r\n5274\t2.79\r\n", T0 + 20);
  const auto f = sink.flat();
  ASSERT_EQ(f.size(), 3u);
  for (std::size_t i = 0; i < f.size(); ++i) EXPECT_EQ(f[i].seq, std::int64_t(i));
  EXPECT_EQ(f[0].t_us, 5'234'000);
  EXPECT_EQ(f[1].t_us, 5'254'000);
  EXPECT_DOUBLE_EQ(f[1].value, 2.81);
  EXPECT_EQ(f[2].adc, -1);
  EXPECT_EQ(sink.samples[0].bench, "b1");
  EXPECT_EQ(int(sink.samples[0].quantity), int(samples_t::QUANTITY_BACK_EMF_V));
  EXPECT_EQ(sink.samples[0].host_time_us[0], T0 + 10);
  EXPECT_EQ(sink.samples[1].host_time_us[0], T0 + 20);  // the line completed in the second read
  EXPECT_EQ(b.protocol(), WireProtocol::lab);
  b.tick(T0 + 30);
  ASSERT_FALSE(sink.configs.empty());
  EXPECT_EQ(sink.configs.back().protocol, "lab-tsv");
  EXPECT_EQ(sink.configs.back().firmware, "lab sketch");
  EXPECT_DOUBLE_EQ(sink.configs.back().inertia_kg_m2, 1.12687602e-5);
  EXPECT_DOUBLE_EQ(sink.configs.back().sample_period_s, 0.020);
  EXPECT_DOUBLE_EQ(sink.configs.back().inertia_rel_error, 0.0);  // none given: J taken as exact
}

TEST(BridgeLogic, ConfigCarriesTheUncertaintyOfJAndKb) {
  CaptureSink sink;
  BridgeSettings s = settings();
  s.params.inertia_rel_error = 0.02;
  s.params.kb_rel_error = 0.05;
  SerialBridge b(s, sink);
  b.tick(T0);
  ASSERT_FALSE(sink.configs.empty());
  EXPECT_DOUBLE_EQ(sink.configs.back().inertia_rel_error, 0.02);
  EXPECT_DOUBLE_EQ(sink.configs.back().kb_rel_error, 0.05);
}

TEST(BridgeLogic, SpindownV1SamplesCarryRawCountsAndDetectLoss) {
  CaptureSink sink;
  SerialBridge b(settings(), sink);
  b.start(T0);
  SpindownBanner banner;
  banner.firmware = "spindown-coast";
  banner.version = "1.0.0";
  banner.period_us = 5000;
  banner.baud = 115200;
  std::string bytes = format_spindown_banner(banner);
  bytes += format_spindown_sample(0, 1'000'000, 512);
  bytes += format_spindown_sample(1, 1'005'000, 511);
  bytes += format_spindown_sample(4, 1'020'000, 508);  // 2 and 3 lost on the wire
  b.feed(bytes, T0 + 5);
  const auto f = sink.flat();
  ASSERT_EQ(f.size(), 3u);
  EXPECT_EQ(f[0].t_us, 1'000'000);
  EXPECT_EQ(f[2].t_us, 1'020'000);
  EXPECT_EQ(f[0].adc, 512);
  EXPECT_DOUBLE_EQ(f[0].value, 512 * 5.0 / 1024);
  EXPECT_EQ(f[2].seq, 2);  // bridge seq stays gapless: it numbers what it publishes
  EXPECT_EQ(b.counters().device_seq_gaps, 2);
  EXPECT_NE(b.last_error().find("from 1 to 4"), std::string::npos) << b.last_error();
  ASSERT_FALSE(sink.configs.empty());
  const auto& c = sink.configs.back();
  EXPECT_EQ(c.protocol, "spindown-v1");
  EXPECT_EQ(c.firmware, "spindown-coast 1.0.0");
  EXPECT_DOUBLE_EQ(c.sample_period_s, 0.005);
  EXPECT_DOUBLE_EQ(c.adc_volts_per_count, 5.0 / 1024);
}

TEST(BridgeLogic, ResetStartsANewEpochInItsOwnMessage) {
  CaptureSink sink;
  SerialBridge b(settings(), sink);
  b.start(T0);
  b.feed("60000\t1.00\r\n60020\t0.99\r\n3\t0.98\r\n23\t0.97\r\n", T0);
  const auto f = sink.flat();
  ASSERT_EQ(f.size(), 4u);
  EXPECT_EQ(f[1].epoch, 0);
  EXPECT_EQ(f[2].epoch, 1);
  EXPECT_EQ(f[2].t_us, 3000);
  EXPECT_EQ(f[3].seq, 3);
  ASSERT_EQ(sink.samples.size(), 2u);  // one clock epoch per message
  EXPECT_EQ(b.counters().device_resets, 1);
}

TEST(BridgeLogic, MillisWrapIsUnwrapped) {
  CaptureSink sink;
  SerialBridge b(settings(), sink);
  b.start(T0);
  b.feed("4294967290\t1.00\r\n14\t1.00\r\n", T0);
  const auto f = sink.flat();
  ASSERT_EQ(f.size(), 2u);
  EXPECT_EQ(f[1].epoch, 0);
  EXPECT_EQ(f[1].t_us - f[0].t_us, 20'000);
}

TEST(BridgeLogic, GarbageIsCountedReportedAndNeverPublished) {
  CaptureSink sink;
  SerialBridge b(settings(), sink);
  b.start(T0);
  using namespace std::string_literals;  // the garbage holds a NUL byte
  b.feed("\xfe\x80\x00zz\r\n12\r\n\r\nS,1,2,3*00\r\n#hello*00\r\n"s, T0);
  EXPECT_TRUE(sink.samples.empty());
  EXPECT_EQ(b.counters().lines_bad, 4);
  EXPECT_EQ(b.counters().lines_blank, 1);
  EXPECT_EQ(b.counters().lines_good, 0);
  EXPECT_EQ(b.last_error(), "/dev/ttyTEST line 5: checksum mismatch: \"#hello*00\"");
  b.feed("\x01\x02\tx\r\n", T0);
  EXPECT_NE(b.last_error().find("\\x01\\x02\\tx"), std::string::npos) << b.last_error();
  EXPECT_EQ(b.protocol(), WireProtocol::unknown);
}

TEST(BridgeLogic, TenMegabyteLineKeepsMemoryBounded) {
  CaptureSink sink;
  BridgeSettings s = settings();
  s.max_line_bytes = 256;
  SerialBridge b(s, sink);
  start_connected(b);
  const std::string chunk(64 * 1024, '7');  // digits: would be "a number" if kept
  for (int i = 0; i < 160; ++i) {  // 10 MiB, no newline
    b.feed(chunk, T0);
    ASSERT_LE(b.buffered_bytes(), 256u);
  }
  EXPECT_FALSE(b.looks_like_wrong_baud()) << b.state();  // text, only too long
  b.feed("\r\n100\t1.00\r\n", T0);
  EXPECT_EQ(b.counters().oversize_lines, 1);
  EXPECT_EQ(b.counters().lines_bad, 1);
  ASSERT_EQ(sink.flat().size(), 1u);
  EXPECT_EQ(sink.flat()[0].t_us, 100'000);
  EXPECT_NE(b.last_error().find("longer than 256 bytes"), std::string::npos);
}

// The lab sketch at 9600 baud read at 115200: every byte garbled (what a real port shows), no
// line valid. The state says so once 256 bytes came without a valid line, and goes back to
// "connected" with the first valid line.
TEST(BridgeLogic, WrongBaudIsSaidInTheStateUntilAValidLineArrives) {
  CaptureSink sink;
  BridgeSettings s = settings();
  s.baud = 115200;
  SerialBridge b(s, sink);
  b.start(T0);
  b.connected(T0);
  using namespace std::string_literals;
  const std::string garbled = "\xc0\xf0\x80\xfe\x00\xe0\xf8\xfc\x80\xc0\xf0\x00\xfe\xff\x80\xe0"s;  // 16 bytes
  for (int i = 0; i < 15; ++i) b.feed(garbled, T0 + i);  // 240 bytes
  EXPECT_FALSE(b.looks_like_wrong_baud());
  EXPECT_EQ(b.state(), "connected");
  b.feed(garbled + "\n" + garbled, T0 + 100);  // a stray newline: one garbled line, still nothing valid
  ASSERT_TRUE(b.looks_like_wrong_baud());
  EXPECT_EQ(b.state(), "no valid line in 273 bytes at 115200 baud — wrong baud? the lab sketch uses 9600");
  b.tick(T0 + 100);  // as spindown-bridge does after every read
  ASSERT_FALSE(sink.statuses.empty());
  EXPECT_EQ(sink.statuses.back().state, b.state());  // published at once, not at the next beat
  EXPECT_NE(b.last_error().find("/dev/ttyTEST: no valid line in 273 bytes"), std::string::npos) << b.last_error();
  EXPECT_TRUE(sink.samples.empty());
  for (int i = 0; i < 100; ++i) b.feed(garbled, T0 + 200);  // said once: the state does not change
  EXPECT_EQ(b.state(), "no valid line in 273 bytes at 115200 baud — wrong baud? the lab sketch uses 9600");

  b.feed("\r\n5234\t0.00\r\n5254\t2.81\r\n", T0 + 300);  // the baud fixed on the other side
  EXPECT_FALSE(b.looks_like_wrong_baud());
  EXPECT_EQ(b.state(), "connected");
  b.tick(T0 + 300);
  EXPECT_EQ(sink.statuses.back().state, "connected");
  EXPECT_EQ(sink.flat().size(), 2u);

  BridgeSettings lab = settings();  // 9600: the other way round
  SerialBridge b2(lab, sink);
  b2.start(T0);
  b2.connected(T0);
  for (int i = 0; i < 20; ++i) b2.feed(garbled, T0);
  EXPECT_NE(b2.state().find("at 9600 baud — wrong baud? spindown-v1 firmware uses 115200"), std::string::npos)
      << b2.state();
  b2.disconnected(T0 + 1, "unplugged");
  EXPECT_FALSE(b2.looks_like_wrong_baud());
  EXPECT_EQ(b2.state(), "disconnected");
}

TEST(BridgeLogic, DisconnectDropsThePartialLineAndReconnectIsCounted) {
  CaptureSink sink;
  SerialBridge b(settings(), sink);
  b.start(T0);
  b.connected(T0);
  b.feed("100\t1.00\r\n120\t0.9", T0);
  b.disconnected(T0 + 1000, "/dev/ttyTEST disconnected: end of file");
  EXPECT_FALSE(b.is_connected());
  EXPECT_EQ(sink.statuses.back().state, "disconnected");
  EXPECT_EQ(sink.statuses.back().last_error, "/dev/ttyTEST disconnected: end of file");
  b.open_failed(T0 + 2000, "cannot open /dev/ttyTEST: No such file or directory");
  b.connected(T0 + 3000);
  EXPECT_EQ(sink.statuses.back().state, "connected");
  // Issue 44: plugged back, the device's error is over; the heartbeat (and the pages) stop saying it.
  EXPECT_EQ(sink.statuses.back().last_error, "");
  b.feed("8\t0.50\r\n", T0 + 4000);  // without the reset the two halves would merge
  const auto f = sink.flat();
  ASSERT_EQ(f.size(), 2u);
  EXPECT_EQ(f[1].t_us, 8000);
  EXPECT_EQ(f[1].epoch, 1);  // the board rebooted when plugged back
  const auto& st = sink.statuses.back();
  b.tick(T0 + 10'000'000);
  const auto& last = sink.statuses.back();
  EXPECT_EQ(counter(last, "reconnects"), 1);
  EXPECT_EQ(counter(last, "disconnects"), 1);
  EXPECT_EQ(counter(last, "open_failures"), 1);
  EXPECT_EQ(counter(last, "partial_lines"), 1);
  EXPECT_EQ(counter(last, "samples"), 2);
  EXPECT_EQ(gauge(last, "connected"), 1.0);
  (void)st;
}

TEST(BridgeLogic, HeartbeatEverySecondConfigEveryFewSeconds) {
  CaptureSink sink;
  SerialBridge b(settings(), sink);
  b.start(T0);
  for (std::int64_t t = 0; t <= 10'000'000; t += 50'000) b.tick(T0 + t);
  EXPECT_EQ(sink.statuses.size(), 11u);  // 0, 1, …, 10 s
  EXPECT_EQ(sink.configs.size(), 4u);    // 0, 3, 6, 9 s
  EXPECT_EQ(sink.statuses.back().service, "bridge");
  EXPECT_EQ(sink.statuses.back().instance, "b1");
  EXPECT_EQ(sink.statuses.back().pid, 42);
  EXPECT_NEAR(sink.statuses.back().uptime_s, 10.0, 1e-9);
}

TEST(BridgeLogic, RateGaugeCountsSamplesPerSecond) {
  CaptureSink sink;
  SerialBridge b(settings(), sink);
  b.start(T0);
  std::string lines;
  for (int i = 0; i < 50; ++i) lines += std::to_string(1000 + 20 * i) + "\t1.00\r\n";
  b.feed(lines, T0 + 500'000);
  b.tick(T0 + 1'000'000);
  EXPECT_NEAR(gauge(sink.statuses.back(), "rate_hz"), 50.0, 1e-9);
}

TEST(BridgeLogic, BatchesAreBoundedAndContiguous) {
  CaptureSink sink;
  BridgeSettings s = settings();
  s.max_batch = 8;
  SerialBridge b(s, sink);
  b.start(T0);
  std::string lines;
  for (int i = 0; i < 100; ++i) lines += std::to_string(1000 + 20 * i) + "\t1.00\r\n";
  b.feed(lines, T0);
  std::int64_t next = 0;
  for (const auto& m : sink.samples) {
    EXPECT_LE(m.n, 8);
    EXPECT_EQ(m.seq, next);
    EXPECT_EQ(std::size_t(m.n), m.device_time_us.size());
    next += m.n;
  }
  EXPECT_EQ(next, 100);
}

TEST(BridgeLogic, ProtocolSwitchStartsANewEpoch) {
  CaptureSink sink;
  SerialBridge b(settings(), sink);
  b.start(T0);
  b.feed("100\t1.00\r\n", T0);
  b.feed(format_spindown_sample(0, 5'000'000, 100), T0);
  const auto f = sink.flat();
  ASSERT_EQ(f.size(), 2u);
  EXPECT_EQ(f[1].epoch, 1);
  EXPECT_EQ(b.protocol(), WireProtocol::spindown_v1);
  EXPECT_EQ(b.counters().device_resets, 1);
  b.tick(T0 + 1);
  EXPECT_EQ(sink.configs.back().protocol, "spindown-v1");
}

TEST(BridgeSettings, TomlFileSetsTheBench) {
  const std::string path = ::testing::TempDir() + "bridge_settings_test.toml";
  std::ofstream(path) << "bench_id = \"bench-7\"\n[serial]\ndevice = \"/dev/ttyACM3\"\nbaud = 115200\n"
                         "[bench]\nflywheel_radius_m = 0.02\nflywheel_height_m = 0.015\n"
                         "flywheel_density_kg_m3 = 2700\nrotor_inertia_kg_m2 = 1.09e-6\n"
                         "speed_constant_rpm_per_v = 1180\nquantity = \"rpm\"\ninertia_error_pct = 2\n"
                         "kb_error_pct = 5\n[lab]\nperiod_s = 0.01\n";
  BridgeSettings s;
  load_bridge_settings(path, s);
  EXPECT_DOUBLE_EQ(s.params.inertia_rel_error, 0.02);  // their uncertainties, carried to the CONFIG
  EXPECT_DOUBLE_EQ(s.params.kb_rel_error, 0.05);
  EXPECT_EQ(s.bench, "bench-7");
  EXPECT_EQ(s.device, "/dev/ttyACM3");
  EXPECT_EQ(s.baud, 115200);
  EXPECT_NEAR(s.params.inertia_kg_m2, cylinder_inertia(0.02, 0.015, 2700) + 1.09e-6, 1e-15);
  EXPECT_NEAR(s.params.kb_v_s_per_rad, 1.0 / 123.569311, 1e-9);
  EXPECT_EQ(s.params.kb_source, "speed constant 1180 rpm/V");
  EXPECT_EQ(s.quantity, Quantity::rpm);
  EXPECT_DOUBLE_EQ(s.lab_period_s, 0.01);
  std::remove(path.c_str());
}

TEST(BridgeSettings, BadFileNamesFileKeyAndProblem) {
  const std::string path = ::testing::TempDir() + "bridge_settings_bad.toml";
  std::ofstream(path) << "[bench]\nquantity = \"furlongs\"\n";
  BridgeSettings s;
  try {
    load_bridge_settings(path, s);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), path + ": key 'bench.quantity': unknown quantity 'furlongs' (want V, rpm or rad/s)");
  }
  std::ofstream(path) << "[serial]\nbaud = \"fast\"\n";
  EXPECT_THROW(load_bridge_settings(path, s), std::runtime_error);
  std::ofstream(path) << "[bench]\ninertia_error_pct = 150\n";
  try {
    load_bridge_settings(path, s);
    FAIL() << "an uncertainty of 150 % was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), path + ": key 'bench.inertia_error_pct': 150 is not a percentage in 0-100");
  }
  std::ofstream(path) << "[serial\n";
  try {
    load_bridge_settings(path, s);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()).rfind(path + ":1:", 0), 0u) << e.what();
  }
  std::remove(path.c_str());
}

// What `spindown fit` reads of a capture is what the bridge publishes of the same bytes (issue
// 43): sketches that print "millis,value" with a comma, or a header and three columns, were 100 %
// bad lines at the bridge while fit read the file. The bridge learns the layout from the first
// lines with the file reader and reads every line by it: the same samples, time and value.
namespace {
std::vector<std::pair<double, double>> fit_reads(const std::string& bytes) {
  const std::string path = ::testing::TempDir() + "/bridge_same_bytes.txt";
  std::ofstream(path, std::ios::binary) << bytes;
  const auto recs = read_recordings(path);
  std::vector<std::pair<double, double>> out;
  if (recs.size() == 1)
    for (std::size_t i = 0; i < recs[0].size(); ++i) out.emplace_back(recs[0].t_s[i], recs[0].value[i]);
  std::remove(path.c_str());
  return out;
}
void expect_bridge_reads_as_fit(const std::string& bytes, std::size_t rows) {
  CaptureSink sink;
  SerialBridge b(settings(), sink);
  b.start(T0);
  b.connected(T0);
  std::int64_t t = T0;
  for (std::size_t at = 0; at < bytes.size(); at += 7) b.feed(bytes.substr(at, 7), t += 1000);  // as a port delivers
  b.stop(t);
  const auto fit = fit_reads(bytes);
  const auto live = sink.flat();
  ASSERT_EQ(fit.size(), rows);
  ASSERT_EQ(live.size(), fit.size()) << b.last_error();
  for (std::size_t i = 0; i < fit.size(); ++i) {
    EXPECT_EQ(live[i].seq, std::int64_t(i));
    EXPECT_NEAR(1e-6 * double(live[i].t_us), fit[i].first, 1e-9) << "sample " << i;
    EXPECT_DOUBLE_EQ(live[i].value, fit[i].second) << "sample " << i;
  }
  EXPECT_EQ(b.counters().lines_bad, 0) << b.last_error();
}
}  // namespace

TEST(BridgeLogic, CommaSeparatedSketchLinesAreReadAsFitReadsThem) {
  std::string bytes;
  for (int i = 0; i < 60; ++i) bytes += fmt_sample(2281 + 20 * i, i < 20 ? -0.0005 : 2.8 - 0.01 * (i - 20), ',');
  expect_bridge_reads_as_fit(bytes, 60);
}

TEST(BridgeLogic, AHeaderAndThreeColumnsAreReadAsFitReadsThem) {
  std::string bytes = "ms\traw\tvolts\r\n";
  for (int i = 0; i < 60; ++i) {
    const double v = i < 20 ? 0.0 : 2.8 - 0.01 * (i - 20);
    char line[64];
    std::snprintf(line, sizeof line, "%d\t%d\t%.2f\r\n", 20 * i, int(std::lround(v / 5.0 * 1023)), v);
    bytes += line;
  }
  expect_bridge_reads_as_fit(bytes, 60);
}

TEST(BridgeLogic, ABootMessageBeforeTheLabLinesIsNoTable) {
  CaptureSink sink;
  SerialBridge b(settings(), sink);
  b.start(T0);
  b.connected(T0);
  std::string bytes = "ets Jun  8 2016 00:22:57\r\nrst:0x1 (POWERON_RESET),boot:0x13 (SPI_FAST_FLASH_BOOT)\r\n";
  for (int i = 0; i < 10; ++i) bytes += fmt_sample(100 + 20 * i, 1.0, '\t');
  b.feed(bytes, T0);
  EXPECT_EQ(b.counters().lines_bad, 2);
  EXPECT_EQ(sink.flat().size(), 10u);
  EXPECT_EQ(b.protocol(), WireProtocol::lab);
}

TEST(BridgeLogic, SerialPlotterLabelsAreReadAsFitReadsThem) {
  std::string bytes;
  for (int i = 0; i < 60; ++i) {
    char line[64];
    std::snprintf(line, sizeof line, "millis:%d,volts:%.2f\r\n", 2020 + 20 * i, i < 20 ? 0.0 : 2.8 - 0.01 * (i - 20));
    bytes += line;
  }
  expect_bridge_reads_as_fit(bytes, 60);
}

// spindown-v1's port with lines broken on the wire ("12,345678,512*3F" without its "S,"): never
// taken for a sketch's table; the protocol stays spindown-v1.
TEST(BridgeLogic, BrokenSpindownLinesAreNoTable) {
  CaptureSink sink;
  BridgeSettings s = settings();
  s.baud = 115200;
  SerialBridge b(s, sink);
  start_connected(b);
  b.feed("# spindown-coast v1 adc_bits=10 vref=5.000\r\n", T0);
  for (int i = 0; i < 12; ++i) b.feed(fmt::format("{},{},{}*3F\r\n", i, 1000 + 2000 * i, 512 - i), T0 + i);
  EXPECT_NE(b.protocol(), WireProtocol::lab);
  EXPECT_TRUE(sink.flat().empty());
}

// A sketch printing micros() instead of millis(): the bridge reads µs as spindown fit does (a step
// of 4000-200000 ticks), across micros()'s wrap at 2^32 µs (71.6 min after reset).
TEST(BridgeLogic, MicrosInTheLabsColumnsAreReadAsMicroseconds) {
  // The samples a newly plugged-in bridge publishes from lines, and its last error.
  const auto published = [](const std::string& lines, std::string* error = nullptr) {
    CaptureSink sink;
    SerialBridge b(settings(), sink);
    start_connected(b);
    b.feed(lines, T0 + 10);
    if (error) *error = b.last_error();
    return sink.flat();
  };
  std::string lines, error;
  for (int k = 0; k < 6; ++k) lines += fmt::format("{}\t2.{:02d}\r\n", (4294927296ull + 20000ull * k) % 4294967296ull, 80 - k);
  const auto f = published(lines, &error);
  ASSERT_EQ(f.size(), 6u);
  for (std::size_t i = 1; i < f.size(); ++i) {
    EXPECT_EQ(f[i].t_us - f[i - 1].t_us, 20'000) << i;  // µs, unwrapped: not 20 s
    EXPECT_EQ(f[i].epoch, f[0].epoch) << i;
  }
  EXPECT_NE(error.find("micros()"), std::string::npos) << error;
  // Right after a reset micros() reads small: taken for millis() at its first sample, told at the
  // second; the first stays alone in its epoch, the rest are µs.
  const auto g = published("2000000\t0.00\r\n2020000\t0.00\r\n2040000\t0.00\r\n");
  ASSERT_EQ(g.size(), 3u);
  EXPECT_NE(g[1].epoch, g[0].epoch);
  EXPECT_EQ(g[2].t_us - g[1].t_us, 20'000);
  // Joined mid-line: the first "sample" is the end of one ("96" of "4270987596"); the rest are µs.
  const auto h = published("96\t0.00\r\n4270987664\t0.00\r\n4271008004\t0.00\r\n4271028356\t0.00\r\n");
  ASSERT_EQ(h.size(), 4u);
  EXPECT_EQ(h[2].t_us - h[1].t_us, 20'340);
  EXPECT_EQ(h[3].t_us - h[2].t_us, 20'352);
  EXPECT_EQ(h[3].epoch, h[1].epoch);
}
