// A bench's SAMPLE stream and its sources (issue 31): a restarted bridge is a new stream whose
// samples are all taken (never "repeated"); two sources at once are named and the second refused;
// a forged message far from the stream (sequence 2^40) is held and dropped, never a new position.
// The live fitter, the log reader and watch all take samples through SampleStream.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "spindown/sample_stream.hpp"

namespace spindown {
namespace {

constexpr std::int64_t t0 = 1'700'000'000'000'000;
constexpr std::int64_t ms = 1000;

struct Counting {
  std::vector<std::pair<SampleProblem, std::string>> problems;
  std::vector<std::int64_t> counts;
  std::vector<std::int64_t> seqs, times;
  void problem(SampleProblem kind, std::int64_t count, std::string text) {
    problems.emplace_back(kind, std::move(text));
    counts.push_back(count);
  }
  void sample(std::int64_t seq, std::int64_t t, double) {
    seqs.push_back(seq);
    times.push_back(t);
  }
  int count(SampleProblem kind) const {
    int n = 0;
    for (const auto& p : problems) n += p.first == kind;
    return n;
  }
  std::int64_t total(SampleProblem kind) const {
    std::int64_t n = 0;
    for (std::size_t i = 0; i < problems.size(); ++i)
      if (problems[i].first == kind) n += counts[i];
    return n;
  }
  std::string text(SampleProblem kind) const {
    for (const auto& p : problems)
      if (p.first == kind) return p.second;
    return {};
  }
};

// One bridge process: its session, host, sequence and device clock (a sample every 20 ms).
struct Bridge {
  std::uint64_t session;
  std::string host;
  std::int64_t seq = 0;
  std::int32_t epoch = 0;
  std::int64_t device_us = 0;
  samples_t next(int n = 1) {
    samples_t m{};
    m.bench = "bench-1";
    m.seq = seq;
    m.clock_epoch = epoch;
    m.quantity = samples_t::QUANTITY_BACK_EMF_V;
    m.source_session = static_cast<std::int64_t>(session);
    m.source_host = host;
    for (int i = 0; i < n; ++i) {
      m.device_time_us.push_back(device_us);
      m.host_time_us.push_back(0);
      m.value.push_back(1.0);
      m.raw_adc.push_back(-1);
      device_us += 20 * ms;
    }
    m.n = n;
    seq += n;
    return m;
  }
};

bool take(SampleStream& s, const samples_t& m, std::int64_t recv, Counting& sink) {
  return s.take(m, static_cast<std::size_t>(m.n), recv, sink);
}

// Samples 0..n-1 taken once each, in order; none called lost or repeated.
void expect_every_sample_once_in_order(const Counting& sink, std::size_t n) {
  EXPECT_EQ(sink.total(SampleProblem::samples_lost), 0);
  EXPECT_EQ(sink.count(SampleProblem::repeated), 0);
  ASSERT_EQ(sink.seqs.size(), n);
  for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(sink.seqs[i], std::int64_t(i));
}

// The board replugged / the bridge restarted: a new session starting at sequence 0 and device
// time 0. Before, every message was "repeated" until the new clock passed the old one.
TEST(SampleStream, ARestartedBridgeIsANewStreamNeverRepeated) {
  SampleStream s;
  Counting sink;
  Bridge a{0xa, "pc-a"};
  std::int64_t recv = t0;
  for (int i = 0; i < 500; ++i, recv += 20 * ms) take(s, a.next(), recv, sink);
  Bridge b{0xb, "pc-a"};
  recv += 1500 * ms;  // the new process starts 1.5 s later
  for (int i = 0; i < 300; ++i, recv += 20 * ms) take(s, b.next(), recv, sink);
  EXPECT_EQ(sink.count(SampleProblem::repeated), 0);
  EXPECT_EQ(sink.count(SampleProblem::new_source), 1);
  EXPECT_EQ(sink.count(SampleProblem::two_sources), 0);
  EXPECT_EQ(sink.seqs.size(), 800u);  // every sample of both
  EXPECT_NE(sink.text(SampleProblem::new_source).find("a new source: host pc-a (session 000000000000000b) after host "
                                                      "pc-a (session 000000000000000a) went quiet"),
            std::string::npos)
      << sink.text(SampleProblem::new_source);
  EXPECT_EQ(s.session, 0xbu);
}

// A restart faster than the takeover time: the new source's first messages are held until the old
// one has been quiet long enough, then taken in order — nothing lost, nothing named as two sources.
TEST(SampleStream, AFastRestartIsHeldThenTakenWhole) {
  SampleStream s;
  Counting sink;
  Bridge a{0xa, "pc-a"};
  std::int64_t recv = t0;
  for (int i = 0; i < 100; ++i, recv += 20 * ms) take(s, a.next(), recv, sink);
  Bridge b{0xb, "pc-a"};
  recv += 100 * ms;
  for (int i = 0; i < 100; ++i, recv += 20 * ms) take(s, b.next(), recv, sink);
  EXPECT_EQ(sink.count(SampleProblem::new_source), 1);
  EXPECT_EQ(sink.count(SampleProblem::two_sources), 0);
  EXPECT_EQ(sink.count(SampleProblem::other_source), 0);
  ASSERT_EQ(sink.seqs.size(), 200u);
  for (int i = 0; i < 100; ++i) EXPECT_EQ(sink.seqs[100 + static_cast<std::size_t>(i)], i);
}

// Two bridges with one bench id (or a forger with its own session): both alive, interleaved. The
// first keeps the stream; the second is named once and never taken.
TEST(SampleStream, TwoSourcesAtOnceAreNamedAndTheSecondRefused) {
  SampleStream s;
  Counting sink;
  Bridge a{0xa, "pc-a"}, b{0xb, "pc-b"};
  std::int64_t recv = t0;
  for (int i = 0; i < 300; ++i, recv += 10 * ms) {
    take(s, a.next(), recv, sink);
    if (i >= 50) take(s, b.next(), recv + 5 * ms, sink);
  }
  EXPECT_EQ(sink.count(SampleProblem::two_sources), 1);
  EXPECT_EQ(sink.count(SampleProblem::new_source), 0);
  EXPECT_EQ(sink.seqs.size(), 300u);
  EXPECT_EQ(sink.total(SampleProblem::other_source), 250);
  EXPECT_NE(sink.text(SampleProblem::two_sources).find("has two sources: host pc-a (session 000000000000000a) and host "
                                                       "pc-b (session 000000000000000b)"),
            std::string::npos)
      << sink.text(SampleProblem::two_sources);
  // The first stops: the second takes over, as a restart would.
  for (int i = 0; i < 100; ++i, recv += 20 * ms) take(s, b.next(), recv + 2000 * ms, sink);
  EXPECT_EQ(sink.count(SampleProblem::new_source), 1);
  EXPECT_EQ(s.session, 0xbu);
}

// One forged datagram with the stream's own source and sequence 2^40: held, then dropped when the
// stream goes on where it was. Before, every later real sample was "repeated" for the session.
TEST(SampleStream, AForgedHugeSequenceNeverBlindsTheStream) {
  SampleStream s;
  Counting sink;
  Bridge a{0xa, "pc-a"};
  std::int64_t recv = t0;
  for (int i = 0; i < 100; ++i, recv += 20 * ms) take(s, a.next(), recv, sink);
  samples_t forged = a.next();
  a.seq -= 1;
  a.device_us -= 20 * ms;
  forged.seq = std::int64_t{1} << 40;
  forged.device_time_us[0] = std::int64_t{1} << 50;
  EXPECT_FALSE(take(s, forged, recv, sink));
  for (int i = 0; i < 100; ++i, recv += 20 * ms) take(s, a.next(), recv, sink);
  EXPECT_EQ(sink.count(SampleProblem::repeated), 0);
  EXPECT_EQ(sink.count(SampleProblem::samples_lost), 0);
  EXPECT_EQ(sink.count(SampleProblem::jump), 1);
  EXPECT_EQ(sink.total(SampleProblem::jump), 1);
  EXPECT_EQ(sink.seqs.size(), 200u);
  EXPECT_EQ(sink.seqs.back(), 199);
  EXPECT_NE(sink.text(SampleProblem::jump).find("forged or damaged"), std::string::npos);
  // A forged device time alone (the sequence in place) is caught the same way.
  forged = a.next();
  a.seq -= 1;
  a.device_us -= 20 * ms;
  forged.device_time_us[0] += 3600 * 1000 * ms;
  take(s, forged, recv, sink);
  for (int i = 0; i < 10; ++i, recv += 20 * ms) take(s, a.next(), recv, sink);
  EXPECT_EQ(sink.count(SampleProblem::jump), 2);
  EXPECT_EQ(sink.count(SampleProblem::time_backwards), 0);
  EXPECT_EQ(sink.seqs.size(), 210u);
}

// A real jump (an outage: 1000 samples and 20 s missing) is taken once the stream has gone on from
// there for confirm_s with nothing continuing the old position: counted as lost, nothing dropped.
TEST(SampleStream, ARealFarGapIsTakenOnceConfirmed) {
  SampleStream s;
  Counting sink;
  Bridge a{0xa, "pc-a"};
  std::int64_t recv = t0;
  for (int i = 0; i < 100; ++i, recv += 20 * ms) take(s, a.next(), recv, sink);
  a.seq += 1000;
  a.device_us += 20'000 * ms;
  recv += 20'000 * ms;
  for (int i = 0; i < 100; ++i, recv += 20 * ms) take(s, a.next(), recv, sink);
  EXPECT_EQ(sink.count(SampleProblem::jump), 0);
  EXPECT_EQ(sink.total(SampleProblem::samples_lost), 1000);
  EXPECT_EQ(sink.seqs.size(), 200u);
  // The order is kept: the held samples came first.
  EXPECT_EQ(sink.seqs[100], 1100);
  EXPECT_EQ(sink.seqs.back(), 1199);
}

// An Arduino reset under the same bridge: a new clock epoch, taken (after confirm_s) as a restart.
TEST(SampleStream, ABoardResetUnderTheSameBridgeIsAClockRestart) {
  SampleStream s;
  Counting sink;
  Bridge a{0xa, "pc-a"};
  std::int64_t recv = t0;
  for (int i = 0; i < 100; ++i, recv += 20 * ms) take(s, a.next(), recv, sink);
  a.epoch = 1;
  a.device_us = 0;
  for (int i = 0; i < 100; ++i, recv += 20 * ms) take(s, a.next(), recv, sink);
  EXPECT_EQ(sink.count(SampleProblem::clock_restart), 1);
  EXPECT_EQ(sink.count(SampleProblem::jump), 0);
  EXPECT_EQ(sink.seqs.size(), 200u);
  // At the end of the stream a jump nothing contradicted is taken.
  a.epoch = 2;
  a.device_us = 0;
  take(s, a.next(), recv, sink);
  EXPECT_EQ(sink.seqs.size(), 200u);
  s.flush(sink);
  EXPECT_EQ(sink.seqs.size(), 201u);
  EXPECT_EQ(sink.count(SampleProblem::clock_restart), 2);
}

// After a takeover, the old session's messages sent again are repeats; its going on is two sources.
TEST(SampleStream, AnOldSessionComingBackIsNamed) {
  SampleStream s;
  Counting sink;
  Bridge a{0xa, "pc-a"};
  std::int64_t recv = t0;
  std::vector<samples_t> sent;
  for (int i = 0; i < 50; ++i, recv += 20 * ms) {
    sent.push_back(a.next());
    take(s, sent.back(), recv, sink);
  }
  Bridge b{0xb, "pc-a"};
  recv += 2000 * ms;
  for (int i = 0; i < 50; ++i, recv += 20 * ms) take(s, b.next(), recv, sink);
  take(s, sent[10], recv, sink);  // a replay of an old message
  EXPECT_EQ(sink.count(SampleProblem::repeated), 1);
  EXPECT_EQ(sink.count(SampleProblem::two_sources), 0);
  take(s, a.next(), recv, sink);  // the old bridge is alive after all
  EXPECT_EQ(sink.count(SampleProblem::two_sources), 1);
  EXPECT_EQ(sink.seqs.size(), 100u);
}

// Messages from before sources were named (session 0, no host): one source, the old rules.
TEST(SampleStream, UnnamedSourcesKeepTheOldRules) {
  SampleStream s;
  Counting sink;
  Bridge a{0, ""};
  std::int64_t recv = t0;
  std::vector<samples_t> sent;
  for (int i = 0; i < 20; ++i, recv += 20 * ms) {
    sent.push_back(a.next());
    take(s, sent.back(), recv, sink);
  }
  a.seq += 3;
  a.device_us += 60 * ms;
  take(s, a.next(), recv, sink);
  take(s, sent[5], recv, sink);
  EXPECT_EQ(sink.count(SampleProblem::repeated), 1);
  EXPECT_EQ(sink.total(SampleProblem::samples_lost), 0);  // the gap may still fill
  s.expire(recv + s.options.reorder.window_us, sink);
  EXPECT_EQ(sink.total(SampleProblem::samples_lost), 3);
  EXPECT_EQ(sink.seqs.size(), 21u);
  EXPECT_NE(s.source_text().find("an unnamed source"), std::string::npos);
}

// A network reorders (issue 42): a late datagram inside the window takes its place, in order;
// nothing is called lost or repeated, and a copy is a repeat exactly once per extra copy.
TEST(SampleStream, LateDatagramsAreTakenInOrderNeverLostOrRepeated) {
  SampleStream s;
  Counting sink;
  Bridge a{7, "bench-pc"};
  std::vector<samples_t> sent;
  for (int i = 0; i < 40; ++i) sent.push_back(a.next());
  // Arrival: 0..9, then 14..19, then 10..13 (60 ms late), a copy of 15, then the rest; 25 twice.
  std::vector<int> order;
  for (int i = 0; i < 10; ++i) order.push_back(i);
  for (int i = 14; i < 20; ++i) order.push_back(i);
  for (int i = 10; i < 14; ++i) order.push_back(i);
  order.push_back(15);
  for (int i = 20; i < 40; ++i) order.push_back(i);
  order.push_back(25);
  std::int64_t recv = t0;
  for (int i : order) take(s, sent[static_cast<std::size_t>(i)], recv += 20 * ms, sink);
  s.flush(sink);
  EXPECT_EQ(sink.total(SampleProblem::samples_lost), 0);
  EXPECT_EQ(sink.count(SampleProblem::repeated), 2);  // the copies of 15 and 25, nothing else
  EXPECT_EQ(sink.count(SampleProblem::late), 0);
  ASSERT_EQ(sink.seqs.size(), 40u);
  for (std::size_t i = 0; i < 40; ++i) EXPECT_EQ(sink.seqs[i], std::int64_t(i));
  EXPECT_EQ(sink.count(SampleProblem::time_backwards), 0);
}

// A power-saving access point hands over 1.5 s of datagrams behind newer ones: inside the window,
// every sample is taken in order.
TEST(SampleStream, ABlockDeliveredLateInsideTheWindowIsWhole) {
  SampleStream s;
  Counting sink;
  Bridge a{7, "bench-pc"};
  std::vector<samples_t> sent;
  for (int i = 0; i < 300; ++i) sent.push_back(a.next());
  std::int64_t recv = t0;
  for (int i = 0; i < 100; ++i) take(s, sent[std::size_t(i)], recv += 20 * ms, sink);
  for (int i = 175; i < 250; ++i) take(s, sent[std::size_t(i)], recv += 20 * ms, sink);  // 100..174 held up
  EXPECT_EQ(sink.seqs.size(), 100u);
  for (int i = 100; i < 175; ++i) take(s, sent[std::size_t(i)], recv, sink);  // 1.5 s late, all at once
  EXPECT_EQ(sink.seqs.size(), 250u);
  for (int i = 250; i < 300; ++i) take(s, sent[std::size_t(i)], recv += 20 * ms, sink);
  expect_every_sample_once_in_order(sink, 300);
}

// A real loss is called once its gap has waited the window, exactly; a straggler after that is
// late (named so), not a repeat, and its samples are not taken out of order.
TEST(SampleStream, ALossIsCalledAfterTheWindowAndAStragglerIsLate) {
  SampleStream s;
  Counting sink;
  Bridge a{7, "bench-pc"};
  std::vector<samples_t> sent;
  for (int i = 0; i < 400; ++i) sent.push_back(a.next());
  std::int64_t recv = t0;
  for (int i = 0; i < 400; ++i) {
    if (i >= 50 && i < 55) continue;  // lost on the way
    if (i == 60) continue;            // comes 3 s late
    take(s, sent[std::size_t(i)], recv += 20 * ms, sink);
    if (i == 100) {
      EXPECT_EQ(sink.seqs.size(), 50u) << "waits for the gap";
    }
  }
  take(s, sent[60], recv, sink);
  s.flush(sink);
  EXPECT_EQ(sink.total(SampleProblem::samples_lost), 6);
  EXPECT_EQ(sink.count(SampleProblem::samples_lost), 2);
  EXPECT_EQ(sink.total(SampleProblem::late), 1);
  EXPECT_NE(sink.text(SampleProblem::late).find("after they were counted lost"), std::string::npos)
      << sink.text(SampleProblem::late);
  EXPECT_EQ(sink.count(SampleProblem::repeated), 0);
  EXPECT_EQ(sink.seqs.size(), 394u);
  EXPECT_EQ(sink.count(SampleProblem::time_backwards), 0);
  for (std::size_t i = 1; i < sink.seqs.size(); ++i) ASSERT_GT(sink.seqs[i], sink.seqs[i - 1]);
}

// Time passing with no message calls a waiting gap lost (the fitter's poll), and what waited
// behind it is taken.
TEST(SampleStream, ExpireTakesWhatWaitedBehindAGap) {
  SampleStream s;
  Counting sink;
  Bridge a{7, "bench-pc"};
  std::int64_t recv = t0;
  for (int i = 0; i < 10; ++i) take(s, a.next(), recv += 20 * ms, sink);
  a.next(3);  // lost
  for (int i = 0; i < 5; ++i) take(s, a.next(), recv += 20 * ms, sink);
  EXPECT_EQ(sink.seqs.size(), 10u);
  s.expire(recv + 100 * ms, sink);
  EXPECT_EQ(sink.seqs.size(), 10u);
  s.expire(recv + s.options.reorder.window_us, sink);
  EXPECT_EQ(sink.seqs.size(), 15u);
  EXPECT_EQ(sink.total(SampleProblem::samples_lost), 3);
  EXPECT_FALSE(s.waiting());
}

// The stream's first datagrams overtaken (200 ± 200 ms of jitter between the PCs): sequence 1
// arrives first, then 5, then 0. What came first waits for what it overtook: every sample is taken
// in order from 0, none "repeated" (before, seq 0 and its neighbours were skipped as repeats).
TEST(SampleStream, AStreamWhoseFirstDatagramsWereOvertakenStartsAtZero) {
  SampleStream s;
  Counting sink;
  Bridge a{7, "bench-pc"};
  std::vector<samples_t> sent;
  for (int i = 0; i < 12; ++i) sent.push_back(a.next());
  std::int64_t recv = t0;
  for (int i : {1, 5, 0, 4, 2, 3, 6, 7, 9, 8, 10, 11}) take(s, sent[static_cast<std::size_t>(i)], recv += 20 * ms, sink);
  s.flush(sink);
  expect_every_sample_once_in_order(sink, 12);
}

// A follower that joins a running stream (a fitter started mid-session) waits the window once for
// anything older, then begins at the first sample it heard: nothing before it is "lost".
TEST(SampleStream, AJoinedStreamBeginsAfterTheWindowWithNothingLost) {
  SampleStream s;
  Counting sink;
  Bridge a{7, "bench-pc"};
  a.seq = 5000;
  std::int64_t recv = t0;
  for (int i = 0; i < 10; ++i) take(s, a.next(), recv += 20 * ms, sink);
  EXPECT_TRUE(sink.seqs.empty());  // waiting for what it may have overtaken
  s.expire(t0 + 20 * ms + s.options.reorder.window_us, sink);
  ASSERT_EQ(sink.seqs.size(), 10u);
  EXPECT_EQ(sink.seqs.front(), 5000);
  EXPECT_EQ(sink.total(SampleProblem::samples_lost), 0);
  EXPECT_FALSE(s.waiting());
  take(s, a.next(), recv += 20 * ms, sink);  // and then in step, at once
  EXPECT_EQ(sink.seqs.size(), 11u);
}

}  // namespace
}  // namespace spindown
