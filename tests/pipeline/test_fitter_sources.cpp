// FitterCore and the sources of a bench's samples (issue 31), judged against the generator's
// truth (find_runs on the clean stream) and against a clean feed of the same samples:
// - a restarted bridge (a replugged board: a new session from sequence 0, device time 0) is a new
//   stream: every run of both sessions is fitted, none of its samples is "repeated";
// - a restart mid-coast closes that run there, with its reason ("a new source …");
// - one forged datagram with sequence 2^40 changes no fit and is named;
// - a second bridge (another motor) on the same channel at once is named and never fitted;
// - another lab's samples are counted and never fitted; with the lab key, unsigned and wrongly
//   signed ones too.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "fitter_test_support.hpp"
#include "spindown/fitter_core.hpp"
#include "spindown/lcm_status.hpp"
#include "spindown/message_stamp.hpp"
#include "spindown/runs.hpp"

namespace spindown {
namespace {

using namespace test;

constexpr std::int64_t t0 = 1'700'000'000'000'000;

// One bridge process feeding samples of a stream, one per message, 20 ms of host time apart.
struct Bridge {
  MessageStamp stamp;
  std::int64_t seq = 0;
  explicit Bridge(std::uint64_t session, std::string lab = "lab", std::optional<LabKey> key = std::nullopt,
                  std::string host = "bench-pc")
      : stamp(SourceIdentity{std::move(lab), "239.255.76.67:7667", std::move(host), session, t0}, std::move(key)) {}
  // Samples [from, to) of s, device times shifted by shift_us; utime advances 20 ms per sample.
  void feed(FitterCore& core, const Stream& s, std::size_t from, std::size_t to, std::int64_t& utime,
            std::int64_t shift_us = 0, const std::string& bench = "a") {
    for (std::size_t i = from; i < to && i < s.t_us.size(); ++i) {
      samples_t m = batch(bench, s, i, 1, seq++);
      m.device_time_us[0] += shift_us;
      m.utime = utime + 20000;
      utime += 20000;
      send(core, m, utime, bench);
    }
  }
  void send_config(FitterCore& core, double j, std::int64_t utime, const std::string& bench = "a") {
    const std::string channel = "SPINDOWN." + bench + ".CONFIG";
    config_t c = lab_config(bench, j);
    c.utime = utime;
    const auto bytes = stamp.encode(channel, c);
    core.on_message(channel, bytes.data(), static_cast<std::int64_t>(bytes.size()), utime);
  }
  void send(FitterCore& core, const samples_t& m, std::int64_t utime, const std::string& bench = "a") {
    const std::string channel = "SPINDOWN." + bench + ".SAMPLE";
    const auto bytes = stamp.encode(channel, m);
    core.on_message(channel, bytes.data(), static_cast<std::int64_t>(bytes.size()), utime);
  }
};

std::vector<Run> truth_runs(const Stream& s) {
  Recording rec;
  for (std::size_t i = 0; i < s.t_us.size(); ++i) rec.push(double(s.t_us[i]) / 1e6, s.v[i]);
  return find_runs(rec).runs;
}

double param(const FitResult& r, const char* model, const char* name) {
  for (const auto& m : r.fit.models)
    if (model_name(m.kind) == std::string_view(model))
      for (const auto& p : m.params)
        if (p.name == name) return p.value;
  return std::nan("");
}

FitterOptions with_lab(std::string lab, std::optional<LabKey> key = std::nullopt) {
  FitterOptions o;
  o.gate.lab = std::move(lab);
  o.gate.key = std::move(key);
  return o;
}

LabKey key_of(unsigned char fill) {
  std::array<unsigned char, lab_key_bytes> b{};
  b.fill(fill);
  return lab_key_from_bytes(b);
}

// The board replugged between runs: the new bridge numbers from 0 and its board's clock starts at
// 0 again. Before issue 31, 1 of its 2 runs was fitted and thousands of samples were "repeated".
TEST(FitterSources, EveryRunOfAReplugedBoardIsFitted) {
  const Stream s1 = make_stream(2, 41), s2 = make_stream(2, 42);
  const auto truth1 = truth_runs(s1), truth2 = truth_runs(s2);
  ASSERT_EQ(truth1.size(), 2u);
  ASSERT_EQ(truth2.size(), 2u);
  CollectingSink sink;
  FitterCore core(with_lab("lab"), sink);
  std::int64_t utime = t0;
  Bridge before(0xa1);
  before.send_config(core, 1.1e-5, utime);
  before.feed(core, s1, 0, s1.t_us.size(), utime);
  utime += 3'000'000;  // unplugged, plugged in again, the bridge restarted (its CONFIG first)
  Bridge after(0xb2);
  after.send_config(core, 1.3e-5, utime);
  after.feed(core, s2, 0, s2.t_us.size(), utime);
  core.finish(utime);
  const FitterCounters& c = core.counters();
  EXPECT_EQ(c.duplicates, 0);
  EXPECT_EQ(c.new_sources, 1);
  EXPECT_EQ(c.two_sources, 0);
  ASSERT_EQ(sink.fits.size(), 4u);
  for (std::size_t i = 0; i < 4; ++i) {
    const spindown::Run& truth = i < 2 ? truth1[i] : truth2[i - 2];
    EXPECT_NEAR(sink.fits[i].fit.run.t_cut_s, truth.t_cut_s, 0.03) << "run " << i;
    EXPECT_TRUE(sink.fits[i].fit.run.stopped);
    EXPECT_EQ(sink.fits[i].bridge_session, i < 2 ? 0xa1u : 0xb2u);
    EXPECT_EQ(sink.fits[i].fit.bench.inertia_kg_m2, i < 2 ? 1.1e-5 : 1.3e-5) << "each session's own CONFIG";
    EXPECT_EQ(sink.fits[i].bridge_host, "bench-pc");
  }
  // RUN messages name the bridge too.
  EXPECT_EQ(sink.runs.back().bridge_session, static_cast<std::int64_t>(0xb2));
}

// The bridge restarted in the middle of a coast: the run is closed there with the reason.
TEST(FitterSources, ARestartMidCoastClosesTheRunWithItsReason) {
  const Stream s = make_stream(2, 43);
  const auto truth = truth_runs(s);
  ASSERT_EQ(truth.size(), 2u);
  const std::size_t mid = (truth[0].cut_index + truth[0].stop_index) / 2;
  CollectingSink sink;
  FitterCore core({}, sink);
  std::int64_t utime = t0;
  Bridge before(1);
  before.feed(core, s, 0, mid, utime);
  utime += 2'000'000;
  Bridge after(2);
  after.feed(core, s, truth[0].stop_index + 60, s.t_us.size(), utime);
  core.finish(utime);
  ASSERT_GE(sink.fits.size(), 2u);
  EXPECT_EQ(sink.fits[0].fit.run.end, Run::End::new_source);
  EXPECT_FALSE(sink.fits[0].fit.run.stopped);
  bool said = false;
  for (const auto& r : sink.runs) said |= r.note.find("a new source: host bench-pc (session 0000000000000002)") != std::string::npos;
  EXPECT_TRUE(said) << "the run's closing RUN names the new source";
  EXPECT_NEAR(sink.fits.back().fit.run.t_cut_s, truth[1].t_cut_s, 0.03);
  EXPECT_STREQ(end_name(Run::End::new_source), "new source");
}

// One datagram on the bench's channel, with the bridge's own source and sequence 2^40, in the
// middle of a coast: every fit is bit for bit the clean feed's, and the datagram is named.
TEST(FitterSources, AForgedDatagramChangesNoFit) {
  const Stream s = make_stream(2, 44);
  const auto truth = truth_runs(s);
  ASSERT_EQ(truth.size(), 2u);
  const std::size_t mid = (truth[0].cut_index + truth[0].stop_index) / 2;
  CollectingSink clean_sink, sink;
  FitterCore clean(FitterOptions{}, clean_sink), core(FitterOptions{}, sink);
  std::int64_t u1 = t0, u2 = t0;
  Bridge a1(7), a2(7);
  a1.feed(clean, s, 0, s.t_us.size(), u1);
  a2.feed(core, s, 0, mid, u2);
  samples_t forged = batch("a", s, mid, 1, std::int64_t{1} << 40);
  forged.device_time_us[0] = std::int64_t{1} << 45;
  forged.value[0] = 0.0;
  a2.send(core, forged, u2);
  a2.feed(core, s, mid, s.t_us.size(), u2);
  clean.finish(u1);
  core.finish(u2);
  ASSERT_EQ(sink.fits.size(), clean_sink.fits.size());
  ASSERT_EQ(sink.fits.size(), 2u);
  for (std::size_t i = 0; i < sink.fits.size(); ++i) {
    EXPECT_EQ(param(sink.fits[i], "combined", "c3"), param(clean_sink.fits[i], "combined", "c3"));
    EXPECT_EQ(param(sink.fits[i], "combined", "c4"), param(clean_sink.fits[i], "combined", "c4"));
    EXPECT_EQ(sink.fits[i].fit.run.t_cut_s, clean_sink.fits[i].fit.run.t_cut_s);
  }
  const FitterCounters& c = core.counters();
  EXPECT_EQ(c.seq_jumps, 1);
  EXPECT_EQ(c.seq_jump_samples, 1);
  EXPECT_EQ(c.duplicates, 0);
  EXPECT_EQ(c.samples, clean.counters().samples);
  EXPECT_NE(core.last_error().find("forged or damaged"), std::string::npos) << core.last_error();
}

// A second bridge with the same bench id, on another motor, sending at the same time: named,
// counted, and never fitted as the first one's.
TEST(FitterSources, TwoSourcesAtOnceAreNamedAndNeverMixed) {
  const Stream s = make_stream(2, 45);
  const Stream other = make_stream(2, 46, 3.4);
  CollectingSink clean_sink, sink;
  FitterCore clean(FitterOptions{}, clean_sink), core(FitterOptions{}, sink);
  std::int64_t u1 = t0, u2 = t0;
  Bridge a1(1), a(1), b(2, "lab", std::nullopt, "laptop");
  a1.send_config(clean, 1.2e-5, u1);
  a.send_config(core, 1.2e-5, u2);
  a1.feed(clean, s, 0, s.t_us.size(), u1);
  for (std::size_t i = 0; i < s.t_us.size(); ++i) {
    if (i == 150) b.send_config(core, 3.0e-5, u2 + 1000);  // the second source's J is not the first's
    a.feed(core, s, i, i + 1, u2);
    if (i >= 100 && i < other.t_us.size()) {
      std::int64_t ub = u2 + 5000;
      b.feed(core, other, i, i + 1, ub);
    }
  }
  clean.finish(u1);
  core.finish(u2);
  ASSERT_EQ(sink.fits.size(), clean_sink.fits.size());
  for (std::size_t i = 0; i < sink.fits.size(); ++i) {
    EXPECT_EQ(param(sink.fits[i], "combined", "c4"), param(clean_sink.fits[i], "combined", "c4"));
    EXPECT_EQ(sink.fits[i].bench_source, "config");
    EXPECT_EQ(sink.fits[i].fit.bench.inertia_kg_m2, 1.2e-5);
  }
  const FitterCounters& c = core.counters();
  EXPECT_EQ(c.two_sources, 1);
  EXPECT_GT(c.other_source_samples, 100);
  EXPECT_EQ(c.new_sources, 0);
  const status_t st = core.make_status(u2, "fitter", "h", 1, "running", 1);
  EXPECT_EQ(find_counter(st, "two_sources"), 1);
  bool named = false;
  for (const auto& p : sink.problems)
    named |= p.find("SPINDOWN.a.SAMPLE has two sources: host bench-pc (session 0000000000000001) and host laptop "
                    "(session 0000000000000002)") != std::string::npos;
  EXPECT_TRUE(named);
}

// Two labs on one network, the same bench names: each fitter fits only its own lab's samples.
TEST(FitterSources, AnotherLabsSamplesAreNeverFitted) {
  const Stream mine = make_stream(2, 47), theirs = make_stream(2, 48, 3.3);
  CollectingSink sink;
  FitterCore core(with_lab("physics-a"), sink);
  std::int64_t utime = t0;
  Bridge a(1, "physics-a"), b(2, "physics-b");
  for (std::size_t i = 0; i < mine.t_us.size(); ++i) {
    a.feed(core, mine, i, i + 1, utime);
    std::int64_t ub = utime + 1000;
    b.feed(core, theirs, i, i + 1, ub);
  }
  core.finish(utime);
  ASSERT_EQ(sink.fits.size(), 2u);
  for (const auto& f : sink.fits) EXPECT_EQ(f.bridge_session, 1u);
  const FitterCounters& c = core.counters();
  EXPECT_GT(c.other_lab, 1000);
  EXPECT_EQ(c.two_sources, 0);
  EXPECT_NE(core.last_error().find("a message of lab 'physics-b', this program serves lab 'physics-a'"),
            std::string::npos)
      << core.last_error();
}

// With the lab key: only signed samples are fitted; a laptop's unsigned stream and one signed
// with another key are counted and named.
TEST(FitterSources, WithTheKeyOnlySignedSamplesAreFitted) {
  const Stream s = make_stream(2, 49);
  const LabKey key = key_of(1);
  CollectingSink sink;
  FitterCore core(with_lab("lab", key), sink);
  std::int64_t utime = t0;
  Bridge good(1, "lab", key), laptop(2, "lab"), stranger(3, "lab", key_of(2));
  for (std::size_t i = 0; i < s.t_us.size(); ++i) {
    good.feed(core, s, i, i + 1, utime);
    std::int64_t u = utime;
    laptop.feed(core, s, i, i + 1, u);
    u = utime;
    stranger.feed(core, s, i, i + 1, u);
  }
  core.finish(utime);
  EXPECT_EQ(sink.fits.size(), 2u);
  const FitterCounters& c = core.counters();
  EXPECT_EQ(c.unsigned_messages, static_cast<std::int64_t>(s.t_us.size()));
  EXPECT_EQ(c.bad_signatures, static_cast<std::int64_t>(s.t_us.size()));
  EXPECT_EQ(c.two_sources, 0);  // refused before they were ever a source
  // The same signed messages again (a replay) are refused.
  Bridge replay(1, "lab", key);
  std::int64_t u = t0;
  replay.feed(core, s, 0, 50, u);
  EXPECT_EQ(core.counters().replays, 50);
}

}  // namespace
}  // namespace spindown
