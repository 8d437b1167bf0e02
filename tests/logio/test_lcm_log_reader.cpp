#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <iterator>
#include <lcm/lcm-cpp.hpp>
#include <limits>
#include <string>
#include <sys/stat.h>
#include <unistd.h>
#include <vector>

#include "spindown/lcm_log_reader.hpp"
#include "spindown/synthetic_run.hpp"

#include "lab_messages.hpp"

using namespace spindown;
using Severity = Diagnostic::Severity;

namespace {

std::string temp_path(const std::string& name) {
  return ::testing::TempDir() + "spindown_lcmlog_" + std::to_string(::getpid()) + "_" + name + ".lcm";
}

// Writes LCM event logs the way lcm-logger does, through lcm::LogFile in "w" mode.
class LogWriter {
 public:
  explicit LogWriter(const std::string& path) : log_(path, "w") { EXPECT_TRUE(log_.good()) << path; }
  template <class M>
  void write(const std::string& channel, const M& m, std::int64_t utime = 0) {
    std::vector<std::uint8_t> buf(static_cast<std::size_t>(m.getEncodedSize()));
    m.encode(buf.data(), 0, static_cast<int>(buf.size()));
    write_raw(channel, buf, utime);
  }
  void write_raw(const std::string& channel, std::vector<std::uint8_t> bytes, std::int64_t utime = 0) {
    lcm::LogEvent e;
    e.eventnum = 0;
    e.timestamp = utime ? utime : next_utime_;
    next_utime_ += 20000;
    e.channel = channel;
    e.datalen = static_cast<std::int32_t>(bytes.size());
    e.data = bytes.data();
    EXPECT_EQ(log_.writeEvent(&e), 0);
  }

 private:
  lcm::LogFile log_;
  std::int64_t next_utime_ = 1694686893000000;
};

samples_t batch(const std::string& bench, std::int64_t seq, std::int64_t t0_us, int n, double v0 = 2.0,
                std::int32_t epoch = 0) {
  samples_t m{};
  m.utime = 1;
  m.bench = bench;
  m.seq = seq;
  m.clock_epoch = epoch;
  m.quantity = samples_t::QUANTITY_BACK_EMF_V;
  m.n = n;
  for (int i = 0; i < n; ++i) {
    m.device_time_us.push_back(t0_us + 20000LL * i);
    m.host_time_us.push_back(1694686893000000 + 20000LL * i);
    m.value.push_back(v0 - 0.01 * i);
    m.raw_adc.push_back(-1);
  }
  return m;
}

std::vector<char> file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void put_file(const std::string& path, const std::vector<char>& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

std::string all_diagnostics(const std::vector<Diagnostic>& ds) {
  std::string out;
  for (const auto& d : ds) out += d.to_string() + "\n";
  return out;
}

std::size_t count(const std::vector<Diagnostic>& ds, Severity s) {
  return std::count_if(ds.begin(), ds.end(), [&](const Diagnostic& d) { return d.severity == s; });
}

bool mentions(const std::vector<Diagnostic>& ds, const std::string& text) {
  return std::any_of(ds.begin(), ds.end(), [&](const Diagnostic& d) { return d.message.find(text) != std::string::npos; });
}

const BenchLog* find_bench(const LcmLogContents& c, const std::string& id) {
  for (const auto& b : c.benches)
    if (b.bench == id) return &b;
  return nullptr;
}

struct TempFile {
  std::string path;
  explicit TempFile(const std::string& name) : path(temp_path(name)) {}
  ~TempFile() { std::filesystem::remove(path); }
};

}  // namespace

TEST(LcmLogReader, TwoBenchesWithConfigAndOtherChannels) {
  TempFile f("two");
  {
    LogWriter w(f.path);
    w.write("SPINDOWN.a.CONFIG", test::lab_config("a", 1e-5));
    w.write("SPINDOWN.a.SAMPLE", batch("a", 0, 5'234'000, 10));
    w.write("SPINDOWN.b.SAMPLE", batch("b", 100, 1'000'000, 5, 3.0));
    w.write("SPINDOWN.a.STATUS", batch("a", 0, 0, 1));  // not read as samples
    w.write("OTHER_CHANNEL", test::lab_config("x"));
    w.write("SPINDOWN.a.SAMPLE", batch("a", 10, 5'434'000, 10));
    w.write("SPINDOWN.a.CONFIG", test::lab_config("a", 2e-5));
    w.write("SPINDOWN.b.SAMPLE", batch("b", 105, 1'100'000, 5, 3.0));
  }
  const LcmLogContents c = read_lcm_log(f.path);
  SCOPED_TRACE(all_diagnostics(c.diagnostics));
  EXPECT_FALSE(c.has_errors());
  EXPECT_EQ(c.events, 8);
  ASSERT_EQ(c.benches.size(), 2u);
  EXPECT_EQ(c.benches[0].bench, "a");  // order of first appearance
  const BenchLog* a = find_bench(c, "a");
  const BenchLog* b = find_bench(c, "b");
  ASSERT_TRUE(a && b);
  SCOPED_TRACE(all_diagnostics(a->recording.diagnostics) + all_diagnostics(b->recording.diagnostics));
  ASSERT_EQ(a->recording.size(), 20u);
  EXPECT_DOUBLE_EQ(a->recording.t_s[0], 5.234);
  EXPECT_DOUBLE_EQ(a->recording.t_s[19], 5.614);
  EXPECT_DOUBLE_EQ(a->recording.value[1], 1.99);
  EXPECT_EQ(a->recording.quantity, Quantity::back_emf_volts);
  ASSERT_TRUE(a->config.has_value());
  EXPECT_DOUBLE_EQ(a->config->inertia_kg_m2, 2e-5);  // the latest
  EXPECT_EQ(a->config_messages, 2);
  EXPECT_TRUE(mentions(a->recording.diagnostics, "bench parameters change"));
  EXPECT_EQ(count(a->recording.diagnostics, Severity::warning), 0u);
  EXPECT_EQ(b->recording.size(), 10u);
  EXPECT_FALSE(b->config.has_value());
  EXPECT_NE(b->recording.source.find("SPINDOWN.b.SAMPLE"), std::string::npos);
  EXPECT_EQ(c.other_channels.at("SPINDOWN.a.STATUS"), 1);
  EXPECT_EQ(c.other_channels.at("OTHER_CHANNEL"), 1);

  auto params = bench_params_from_config(*a->config);
  ASSERT_TRUE(params);
  EXPECT_DOUBLE_EQ(params->inertia_kg_m2, 2e-5);
  EXPECT_DOUBLE_EQ(params->inertia_rel_error, 0.0);
  config_t uncertain = *a->config;  // the bench file's inertia_error_pct / kb_error_pct, via the bridge
  uncertain.inertia_rel_error = 0.02;
  uncertain.kb_rel_error = 0.05;
  EXPECT_DOUBLE_EQ(bench_params_from_config(uncertain)->inertia_rel_error, 0.02);
  EXPECT_DOUBLE_EQ(bench_params_from_config(uncertain)->kb_rel_error, 0.05);
  uncertain.kb_rel_error = std::nan("");  // nonsense is not used: K_b taken as exact
  EXPECT_DOUBLE_EQ(bench_params_from_config(uncertain)->kb_rel_error, 0.0);
  config_t bad = *a->config;
  bad.inertia_kg_m2 = -1;
  std::string why;
  EXPECT_FALSE(bench_params_from_config(bad, &why));
  EXPECT_NE(why.find("inertia"), std::string::npos);
}

TEST(LcmLogReader, SyntheticRunSurvivesTheLog) {
  SyntheticRunSpec spec;
  spec.seed = 11;
  const SyntheticRun run = make_synthetic_run(spec);
  TempFile f("synthetic");
  {
    LogWriter w(f.path);
    w.write("SPINDOWN.lab1.CONFIG", test::lab_config("lab1"));
    for (std::size_t i = 0; i < run.t_ms.size(); i += 10) {
      samples_t m{};
      m.bench = "lab1";
      m.seq = static_cast<std::int64_t>(i);
      m.quantity = samples_t::QUANTITY_BACK_EMF_V;
      for (std::size_t k = i; k < std::min(run.t_ms.size(), i + 10); ++k) {
        m.device_time_us.push_back(static_cast<std::int64_t>(run.t_ms[k]) * 1000);
        m.host_time_us.push_back(0);
        m.value.push_back(run.volts[k]);
        m.raw_adc.push_back(run.adc[k]);
      }
      m.n = static_cast<std::int32_t>(m.value.size());
      w.write("SPINDOWN.lab1.SAMPLE", m);
    }
  }
  const LcmLogContents c = read_lcm_log(f.path);
  ASSERT_EQ(c.benches.size(), 1u);
  const Recording& r = c.benches[0].recording;
  ASSERT_EQ(r.size(), run.t_ms.size()) << all_diagnostics(r.diagnostics);
  for (std::size_t i = 0; i < r.size(); ++i) {
    ASSERT_DOUBLE_EQ(r.t_s[i], run.t_ms[i] / 1000.0);
    ASSERT_EQ(r.value[i], run.volts[i]);
  }
  EXPECT_EQ(count(r.diagnostics, Severity::warning), 0u);
}

TEST(LcmLogReader, SequenceGapsAreCountedAsLostSamples) {
  TempFile f("gap");
  {
    LogWriter w(f.path);
    w.write("SPINDOWN.a.SAMPLE", batch("a", 0, 0, 10));
    w.write("SPINDOWN.a.SAMPLE", batch("a", 17, 340'000, 10));  // 7 lost
    w.write("SPINDOWN.a.SAMPLE", batch("a", 27, 540'000, 10));
  }
  const LcmLogContents c = read_lcm_log(f.path);
  ASSERT_EQ(c.benches.size(), 1u);
  const BenchLog& a = c.benches[0];
  EXPECT_EQ(a.samples_lost, 7);
  EXPECT_EQ(a.recording.size(), 30u);
  ASSERT_EQ(count(a.recording.diagnostics, Severity::warning), 1u) << all_diagnostics(a.recording.diagnostics);
  const auto w = std::find_if(a.recording.diagnostics.begin(), a.recording.diagnostics.end(),
                              [](const Diagnostic& d) { return d.severity == Severity::warning; });
  EXPECT_EQ(w->line, 2);  // event number
  EXPECT_NE(w->message.find("7 samples lost"), std::string::npos);
}

TEST(LcmLogReader, ClockEpochChangeIsAClockRestart) {
  TempFile f("epoch");
  {
    LogWriter w(f.path);
    w.write("SPINDOWN.a.SAMPLE", batch("a", 0, 30'000'000, 10, 2.0, 0));
    w.write("SPINDOWN.a.SAMPLE", batch("a", 10, 150'000, 10, 2.0, 1));
  }
  const LcmLogContents c = read_lcm_log(f.path);
  const Recording& r = c.benches.at(0).recording;
  ASSERT_EQ(r.size(), 20u) << all_diagnostics(r.diagnostics);
  ASSERT_EQ(r.clock_restarts.size(), 1u);
  EXPECT_EQ(r.clock_restarts[0], 10u);
  EXPECT_DOUBLE_EQ(r.t_s[10], 0.15);
  EXPECT_TRUE(mentions(r.diagnostics, "clock epoch 0 -> 1"));
}

TEST(LcmLogReader, RepeatedMessagesNonFiniteValuesAndBackwardTimes) {
  TempFile f("dups");
  {
    LogWriter w(f.path);
    w.write("SPINDOWN.a.SAMPLE", batch("a", 0, 0, 10));
    w.write("SPINDOWN.a.SAMPLE", batch("a", 0, 0, 10));  // logged twice
    samples_t odd = batch("a", 10, 200'000, 4);
    odd.value[1] = std::numeric_limits<double>::quiet_NaN();
    odd.device_time_us[3] = 100'000;  // goes back in the same epoch
    w.write("SPINDOWN.a.SAMPLE", odd);
  }
  const LcmLogContents c = read_lcm_log(f.path);
  const Recording& r = c.benches.at(0).recording;
  SCOPED_TRACE(all_diagnostics(r.diagnostics));
  EXPECT_EQ(r.size(), 12u);
  EXPECT_TRUE(mentions(r.diagnostics, "already received"));
  EXPECT_TRUE(mentions(r.diagnostics, "NaN or infinite"));
  EXPECT_TRUE(mentions(r.diagnostics, "does not advance"));
  EXPECT_TRUE(std::is_sorted(r.t_s.begin(), r.t_s.end()));
}

TEST(LcmLogReader, UndecodableEventsAreReportedAndSkipped) {
  TempFile f("undecodable");
  {
    LogWriter w(f.path);
    w.write("SPINDOWN.a.SAMPLE", batch("a", 0, 0, 10));
    w.write("SPINDOWN.a.SAMPLE", test::lab_config("a"));  // wrong type on the channel: event 2
    auto bytes = std::vector<std::uint8_t>(static_cast<std::size_t>(batch("a", 10, 200'000, 10).getEncodedSize()));
    batch("a", 10, 200'000, 10).encode(bytes.data(), 0, static_cast<int>(bytes.size()));
    bytes.resize(bytes.size() - 30);  // truncated payload: event 3
    w.write_raw("SPINDOWN.a.SAMPLE", bytes);
    auto huge = std::vector<std::uint8_t>(static_cast<std::size_t>(batch("a", 10, 200'000, 2).getEncodedSize()));
    batch("a", 10, 200'000, 2).encode(huge.data(), 0, static_cast<int>(huge.size()));
    const std::size_t n_at = 8 + 8 + 4 + 2 + 8 + 4 + 1;  // hash utime len "a\0" seq epoch quantity
    huge[n_at] = 0x7F;  // n = 2^31-ish: must not allocate gigabytes: event 4
    w.write_raw("SPINDOWN.a.SAMPLE", huge);
    w.write_raw("SPINDOWN.a.CONFIG", {1, 2, 3});  // too short: event 5
    w.write("SPINDOWN.a.SAMPLE", batch("a", 10, 200'000, 10));
  }
  const LcmLogContents c = read_lcm_log(f.path);
  const Recording& r = c.benches.at(0).recording;
  SCOPED_TRACE(all_diagnostics(r.diagnostics));
  EXPECT_EQ(r.size(), 20u);
  auto at = [&](std::int64_t event) -> std::string {
    for (const auto& d : r.diagnostics)
      if (d.line == event && d.severity == Severity::warning) return d.message;
    return "";
  };
  EXPECT_NE(at(2).find("SPINDOWN.a.SAMPLE"), std::string::npos);
  EXPECT_NE(at(2).find("not a samples_t"), std::string::npos);
  EXPECT_NE(at(3).find("truncated"), std::string::npos);
  EXPECT_NE(at(4).find("sample count"), std::string::npos);
  EXPECT_NE(at(5).find("too short for config_t"), std::string::npos);
  EXPECT_FALSE(c.benches[0].config.has_value());
}

TEST(LcmLogReader, TruncatedLastEventIsReported) {
  TempFile f("truncated");
  {
    LogWriter w(f.path);
    for (int i = 0; i < 5; ++i) w.write("SPINDOWN.a.SAMPLE", batch("a", 10 * i, 200'000LL * i, 10));
  }
  auto bytes = file_bytes(f.path);
  bytes.resize(bytes.size() - 50);  // the logger died mid-write
  put_file(f.path, bytes);
  const LcmLogContents c = read_lcm_log(f.path);
  SCOPED_TRACE(all_diagnostics(c.diagnostics));
  EXPECT_EQ(c.events, 4);
  EXPECT_EQ(c.benches.at(0).recording.size(), 40u);
  ASSERT_EQ(c.diagnostics.size(), 1u);
  EXPECT_NE(c.diagnostics[0].message.find("truncated"), std::string::npos);
  EXPECT_NE(c.diagnostics[0].message.find("SPINDOWN.a.SAMPLE"), std::string::npos);
  EXPECT_NE(c.diagnostics[0].message.find("is lost"), std::string::npos);
}

TEST(LcmLogReader, GarbageBetweenEventsIsSkipped) {
  TempFile f("garbage");
  std::vector<std::size_t> ends;
  {
    LogWriter w(f.path);
    for (int i = 0; i < 6; ++i) w.write("SPINDOWN.a.SAMPLE", batch("a", 10 * i, 200'000LL * i, 10));
  }
  auto bytes = file_bytes(f.path);
  const std::size_t event_size = bytes.size() / 6;
  // Junk after event 3 (skipped; event 3 itself is sound and kept) and a damaged header on event 5.
  std::vector<char> junk(37, '\x5A');
  bytes.insert(bytes.begin() + static_cast<std::ptrdiff_t>(3 * event_size), junk.begin(), junk.end());
  const std::size_t event5 = 4 * event_size + junk.size();
  bytes[event5 + 20] = '\x7F';  // channel length far too large
  put_file(f.path, bytes);

  const LcmLogContents c = read_lcm_log(f.path);
  SCOPED_TRACE(all_diagnostics(c.diagnostics));
  const Recording& r = c.benches.at(0).recording;
  // Events 1 to 4 and 6 survive (lcm::LogFile used to drop 3 for the junk after it); 5 is lost to its header.
  EXPECT_EQ(r.size(), 50u);
  EXPECT_EQ(c.events, 5);
  EXPECT_TRUE(mentions(c.diagnostics, "37 bytes at offset"));
  EXPECT_TRUE(mentions(c.diagnostics, "not an LCM event; skipped to the next event"));
  EXPECT_TRUE(mentions(c.diagnostics, "damaged event header"));
  EXPECT_TRUE(mentions(r.diagnostics, "samples lost"));  // the sequence gaps show the loss too
  EXPECT_EQ(r.clock_restarts.size(), 0u);
}

// The reader parses events in place in 1 MiB blocks: events that straddle a block boundary and
// an event larger than a block must come out whole and in order.
TEST(LcmLogReader, EventsAcrossBlockBoundariesAndLargerThanABlock) {
  TempFile f("blocks");
  std::int64_t seq = 0;
  {
    LogWriter w(f.path);
    auto put = [&](int n) {
      w.write("SPINDOWN.a.SAMPLE", batch("a", seq, seq * 20000LL, n));
      seq += n;
    };
    for (int i = 0; i < 800; ++i) put(100);  // ~2.3 MB: two block boundaries inside events
    put(50'000);                              // ~1.4 MB in one event: more than a block
    for (int i = 0; i < 10; ++i) put(100);
  }
  ASSERT_GT(std::filesystem::file_size(f.path), 3u << 20);
  const LcmLogContents c = read_lcm_log(f.path);
  SCOPED_TRACE(all_diagnostics(c.diagnostics));
  EXPECT_TRUE(c.diagnostics.empty());
  EXPECT_EQ(c.events, 811);
  ASSERT_EQ(c.benches.size(), 1u);
  EXPECT_EQ(c.benches[0].recording.size(), static_cast<std::size_t>(seq));
  EXPECT_EQ(c.benches[0].samples_lost, 0);

  LcmLogReader reader(f.path);
  LcmLogEvent e;
  std::int64_t last_offset = -1, n = 0, next_seq = 0;
  for (int guard = 0; guard < 1000 && reader.next(e); ++guard) {
    ASSERT_EQ(e.kind, LcmLogEvent::Kind::samples) << e.problem;
    EXPECT_GT(e.file_offset, last_offset);
    EXPECT_EQ(e.samples.seq, next_seq);
    next_seq += e.samples.n;
    last_offset = e.file_offset;
    ++n;
  }
  EXPECT_EQ(n, 811);
}

// Garbage straddling a block boundary, full of partial event markers, is skipped to the next
// real marker; the events on both sides are kept.
TEST(LcmLogReader, GarbageAcrossABlockBoundaryWithPartialMarkersIsSkipped) {
  TempFile f("garbage_block");
  {
    LogWriter w(f.path);
    for (int i = 0; i < 500; ++i) w.write("SPINDOWN.a.SAMPLE", batch("a", 100 * i, 2'000'000LL * i, 100));
  }
  auto bytes = file_bytes(f.path);
  const std::size_t event_size = bytes.size() / 500;
  const std::size_t k = (std::size_t{1} << 20) / event_size;  // the event boundary just before 1 MiB
  std::vector<char> junk;
  for (int i = 0; i < 2000; ++i) junk.insert(junk.end(), {'\xED', '\xA1', '\xDA', '\x00'});
  bytes.insert(bytes.begin() + static_cast<std::ptrdiff_t>(k * event_size), junk.begin(), junk.end());
  put_file(f.path, bytes);

  const LcmLogContents c = read_lcm_log(f.path);
  SCOPED_TRACE(all_diagnostics(c.diagnostics));
  EXPECT_EQ(c.events, 500);
  EXPECT_EQ(c.benches.at(0).recording.size(), 50'000u);
  ASSERT_EQ(c.diagnostics.size(), 1u);
  EXPECT_NE(c.diagnostics[0].message.find(fmt::format("{} bytes at offset {}", junk.size(), k * event_size)),
            std::string::npos);
  EXPECT_NE(c.diagnostics[0].message.find(fmt::format("next event at offset {}", k * event_size + junk.size())),
            std::string::npos);
}

// A few bytes after the last event (less than a marker) are reported, not read as an event.
TEST(LcmLogReader, ShortTailAfterTheLastEventIsReported) {
  TempFile f("short_tail");
  {
    LogWriter w(f.path);
    for (int i = 0; i < 3; ++i) w.write("SPINDOWN.a.SAMPLE", batch("a", 10 * i, 200'000LL * i, 10));
  }
  auto bytes = file_bytes(f.path);
  bytes.insert(bytes.end(), {'\xED', '\xA1'});
  put_file(f.path, bytes);
  const LcmLogContents c = read_lcm_log(f.path);
  SCOPED_TRACE(all_diagnostics(c.diagnostics));
  EXPECT_EQ(c.events, 3);
  EXPECT_EQ(c.benches.at(0).recording.size(), 30u);
  EXPECT_TRUE(mentions(c.diagnostics, "2 bytes at offset"));
  EXPECT_TRUE(mentions(c.diagnostics, "no event follows"));
}

// The reader decodes samples_t itself (not with lcm-gen's decoder): every field must come out
// as lcm-gen encoded it, for one sample, many, and none; channels interleaved and repeated.
TEST(LcmLogReader, SamplesDecodeExactlyAsEncoded) {
  TempFile f("decode_exact");
  std::vector<samples_t> sent;
  {
    LogWriter w(f.path);
    for (int i = 0; i < 9; ++i) {
      samples_t m = batch(i % 3 == 0 ? "b-1" : "bench_two", 1000 + i, -5'000'000LL + i, i % 4 == 3 ? 0 : 1 + 7 * i,
                          -1.5e-300 * (i + 1), -i);
      m.utime = -42 - i;
      m.quantity = static_cast<std::int8_t>(i % 3);
      for (std::size_t k = 0; k < m.raw_adc.size(); ++k) m.raw_adc[k] = static_cast<std::int32_t>(k) * -70000 + i;
      sent.push_back(m);
      w.write(i % 3 == 0 ? "SPINDOWN.b-1.SAMPLE" : "SPINDOWN.bench_two.SAMPLE", m);
    }
  }
  LcmLogReader reader(f.path);
  LcmLogEvent e;
  std::size_t i = 0;
  for (int guard = 0; guard < 100 && reader.next(e); ++guard, ++i) {
    ASSERT_LT(i, sent.size());
    ASSERT_EQ(e.kind, LcmLogEvent::Kind::samples) << e.problem;
    const samples_t& a = e.samples;
    const samples_t& b = sent[i];
    EXPECT_EQ(a.utime, b.utime);
    EXPECT_EQ(a.bench, b.bench);
    EXPECT_EQ(e.bench, i % 3 == 0 ? "b-1" : "bench_two");
    EXPECT_EQ(a.seq, b.seq);
    EXPECT_EQ(a.clock_epoch, b.clock_epoch);
    EXPECT_EQ(a.quantity, b.quantity);
    EXPECT_EQ(a.n, b.n);
    EXPECT_EQ(a.device_time_us, b.device_time_us);
    EXPECT_EQ(a.host_time_us, b.host_time_us);
    EXPECT_EQ(a.value, b.value);
    EXPECT_EQ(a.raw_adc, b.raw_adc);
    EXPECT_GE(e.channel_id, 0);
  }
  EXPECT_EQ(i, sent.size());
}

TEST(LcmLogReader, StreamingReaderHandsOutEventsInOrder) {
  TempFile f("stream");
  {
    LogWriter w(f.path);
    w.write("SPINDOWN.a.CONFIG", test::lab_config("a"), 1000);
    w.write("SPINDOWN.a.SAMPLE", batch("a", 0, 0, 3), 2000);
    w.write("SOMETHING", test::lab_config("a"), 3000);
    w.write("SPINDOWN.bad id!.SAMPLE", batch("a", 0, 0, 3), 4000);  // not a valid bench id
  }
  LcmLogReader reader(f.path);
  ASSERT_TRUE(reader.good()) << reader.open_error();
  LcmLogEvent e;
  std::vector<LcmLogEvent::Kind> kinds;
  std::vector<std::int64_t> utimes;
  for (int guard = 0; guard < 100 && reader.next(e); ++guard) {
    kinds.push_back(e.kind);
    utimes.push_back(e.log_utime);
    EXPECT_EQ(e.number, static_cast<std::int64_t>(kinds.size()));
    if (e.kind == LcmLogEvent::Kind::samples) {
      EXPECT_EQ(e.bench, "a");
      EXPECT_EQ(e.samples.n, 3);
    }
    if (e.kind == LcmLogEvent::Kind::other) {
      EXPECT_GT(e.data_size, 8);
    }
  }
  using K = LcmLogEvent::Kind;
  EXPECT_EQ(kinds, (std::vector<K>{K::config, K::samples, K::other, K::other}));
  EXPECT_EQ(utimes, (std::vector<std::int64_t>{1000, 2000, 3000, 4000}));  // the log's own times
  EXPECT_EQ(reader.events_read(), 4);
  EXPECT_FALSE(reader.next(e));
}

TEST(LcmLogReader, ChannelNames) {
  auto n = split_spindown_channel("SPINDOWN.lab-2_B.SAMPLE");
  ASSERT_TRUE(n);
  EXPECT_EQ(n->bench, "lab-2_B");
  EXPECT_EQ(n->kind, "SAMPLE");
  EXPECT_FALSE(split_spindown_channel("SPINDOWN..SAMPLE"));
  EXPECT_FALSE(split_spindown_channel("SPINDOWN.a b.SAMPLE"));
  EXPECT_FALSE(split_spindown_channel("SPINDOWN.abc"));
  EXPECT_FALSE(split_spindown_channel("OTHER.a.SAMPLE"));
  EXPECT_FALSE(split_spindown_channel("SPINDOWN." + std::string(33, 'x') + ".SAMPLE"));
  EXPECT_TRUE(split_spindown_channel("SPINDOWN." + std::string(32, 'x') + ".SAMPLE"));
  EXPECT_EQ(quantity_from_samples_code(samples_code_of(Quantity::rpm)), Quantity::rpm);
  EXPECT_FALSE(quantity_from_samples_code(9));
}

TEST(LcmLogReader, MissingEmptyAndNonLogFiles) {
  const LcmLogContents missing = read_lcm_log("/nonexistent/x.lcm");
  ASSERT_TRUE(missing.has_errors());
  EXPECT_NE(missing.diagnostics[0].message.find("No such file or directory"), std::string::npos);
  EXPECT_NE(missing.diagnostics[0].message.find("/nonexistent/x.lcm"), std::string::npos);

  TempFile empty("empty");
  put_file(empty.path, {});
  const LcmLogContents e = read_lcm_log(empty.path);
  EXPECT_FALSE(e.has_errors());
  EXPECT_EQ(e.events, 0);
  EXPECT_TRUE(e.benches.empty());

  TempFile text("text");
  const std::string t = "1000\t2.00\r\n1020\t1.99\r\n";
  put_file(text.path, std::vector<char>(t.begin(), t.end()));
  const LcmLogContents tx = read_lcm_log(text.path);
  EXPECT_EQ(tx.events, 0);
  EXPECT_TRUE(mentions(tx.diagnostics, "not an LCM event and no event follows"));
}

// Found by tests/integration/hostile_inputs.sh: `spindown refit` on a FIFO without a writer
// waited forever in fopen(). A log must be a regular file (lcm::LogFile seeks); say so at once.
TEST(LcmLogReader, AFifoOrDeviceIsRefusedNotWaitedOn) {
  const std::string fifo = ::testing::TempDir() + "spindown_lcm_fifo_" + std::to_string(::getpid());
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const LcmLogContents f = read_lcm_log(fifo);
  std::filesystem::remove(fifo);
  ASSERT_TRUE(f.has_errors());
  EXPECT_TRUE(mentions(f.diagnostics, "not a regular file"));
  const LcmLogContents null = read_lcm_log("/dev/null");
  ASSERT_TRUE(null.has_errors());
  EXPECT_TRUE(mentions(null.diagnostics, "not a regular file"));
}

// Found by fuzz_config_t: a config_t whose string length is INT_MIN made lcm-gen's decoder
// compute INT_MIN - 1 (signed overflow, UBSan) in the reader and in FitterCore; a length of 0
// made std::string throw. The layout is now walked first and the event reported.
TEST(LcmLogReader, ConfigWithABadStringLengthIsReportedNotDecoded) {
  TempFile f("bad_string");
  {
    LogWriter w(f.path);
    w.write("SPINDOWN.a.SAMPLE", batch("a", 0, 0, 10));
    for (const std::uint32_t len : {0x80000000u, 0u, 0x7fffffffu}) {
      std::vector<std::uint8_t> bytes(static_cast<std::size_t>(test::lab_config("a").getEncodedSize()));
      test::lab_config("a").encode(bytes.data(), 0, static_cast<int>(bytes.size()));
      for (int k = 0; k < 4; ++k) bytes[16 + k] = static_cast<std::uint8_t>(len >> (24 - 8 * k));  // bench's length
      w.write_raw("SPINDOWN.a.CONFIG", bytes);
    }
  }
  const LcmLogContents c = read_lcm_log(f.path);
  ASSERT_EQ(c.benches.size(), 1u);
  EXPECT_FALSE(c.benches[0].config.has_value());
  std::size_t reported = 0;
  for (const auto& d : c.benches[0].recording.diagnostics)
    reported += d.message.find("string bench has length") != std::string::npos;
  EXPECT_EQ(reported, 3u) << all_diagnostics(c.benches[0].recording.diagnostics);
}
