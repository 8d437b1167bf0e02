// LcmLoop over memq:// (LCM in this process, no network): typed messages decoded and delivered
// in order, a malformed one counted and named instead, a handler's exception out of run() (never
// through LCM's C callback), the stop signal, stop(), deadlines and timers.
#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <spindown/samples_t.hpp>

#include "spindown/lcm_loop.hpp"
#include "spindown/stop_signal.hpp"

namespace spindown {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

samples_t samples(std::int64_t seq, const std::string& bench = "b1") {
  samples_t m{};
  m.utime = 1;
  m.bench = bench;
  m.seq = seq;
  m.quantity = samples_t::QUANTITY_BACK_EMF_V;
  m.n = 1;
  m.device_time_us = {seq * 20000};
  m.host_time_us = {1};
  m.value = {2.5};
  m.raw_adc = {512};
  return m;
}

TEST(LcmLoop, DeliversDecodedMessagesInOrder) {
  LcmLoop loop("memq://");
  ASSERT_TRUE(loop.good());
  std::vector<std::int64_t> seqs;
  std::vector<std::string> channels;
  ASSERT_TRUE(loop.subscribe<samples_t>("SPINDOWN\\..*\\.SAMPLE", [&](const samples_t& m, const LcmMessage& r) {
    seqs.push_back(m.seq);
    channels.emplace_back(r.channel);
    EXPECT_GT(r.recv_utime, 0);
  }));
  for (int i = 0; i < 5; ++i) ASSERT_EQ(loop.publish("SPINDOWN.b1.SAMPLE", samples(i)), 0);
  loop.publish("SPINDOWN.b1.CONFIG", samples(99));  // no subscription: never seen
  EXPECT_EQ(loop.run({.timeout_s = 0.2}), LcmLoopEnd::deadline);
  EXPECT_EQ(seqs, (std::vector<std::int64_t>{0, 1, 2, 3, 4}));
  EXPECT_EQ(channels.front(), "SPINDOWN.b1.SAMPLE");
  EXPECT_EQ(loop.decode_errors(), 0);
}

TEST(LcmLoop, AHandlerOfTheMessageAloneIsFine) {
  LcmLoop loop("memq://");
  int got = 0;
  loop.subscribe<samples_t>("S", [&](const samples_t&) { ++got; });
  loop.publish("S", samples(1));
  loop.run({.timeout_s = 0.1});
  EXPECT_EQ(got, 1);
}

TEST(LcmLoop, AMalformedMessageIsCountedAndNamedNotHandled) {
  LcmLoop loop("memq://");
  int handled = 0;
  std::vector<std::string> reported;
  loop.subscribe<samples_t>("SPINDOWN\\..*\\.SAMPLE", [&](const samples_t&) { ++handled; });
  loop.on_decode_error([&](const LcmDecodeError& e) { reported.push_back(e.text()); });
  const std::string junk = "this is not a samples_t message";
  loop.lcm().publish("SPINDOWN.b1.SAMPLE", junk.data(), static_cast<unsigned>(junk.size()));
  // A samples_t cut in half: the count says more samples than there are bytes.
  const samples_t whole = samples(3);
  std::vector<unsigned char> buf(static_cast<std::size_t>(whole.getEncodedSize()));
  whole.encode(buf.data(), 0, static_cast<int>(buf.size()));
  loop.lcm().publish("SPINDOWN.b2.SAMPLE", buf.data(), static_cast<unsigned>(buf.size() - 10));
  loop.publish("SPINDOWN.b1.SAMPLE", samples(4));
  loop.run({.timeout_s = 0.2});
  EXPECT_EQ(handled, 1);
  EXPECT_EQ(loop.decode_errors(), 2);
  ASSERT_EQ(reported.size(), 2u);
  EXPECT_EQ(reported[0].rfind("SPINDOWN.b1.SAMPLE: 31 bytes that do not decode as samples_t: not a samples_t", 0), 0u)
      << reported[0];
  EXPECT_NE(reported[1].find("SPINDOWN.b2.SAMPLE"), std::string::npos) << reported[1];
  EXPECT_NE(reported[1].find("truncated"), std::string::npos) << reported[1];
  EXPECT_EQ(loop.last_decode_error().channel, "SPINDOWN.b2.SAMPLE");
  EXPECT_EQ(loop.last_decode_error().type, "samples_t");
}

TEST(LcmLoop, AnAcceptFilterSkipsBeforeDecoding) {
  LcmLoop loop("memq://");
  int handled = 0;
  loop.subscribe<samples_t>("SPINDOWN\\..*\\.SAMPLE", [&](const samples_t&) { ++handled; },
                            {.accept = [](std::string_view ch) { return ch != "SPINDOWN.other.SAMPLE"; }});
  const std::string junk = "junk";
  loop.lcm().publish("SPINDOWN.other.SAMPLE", junk.data(), 4);
  loop.publish("SPINDOWN.other.SAMPLE", samples(1));
  loop.publish("SPINDOWN.b1.SAMPLE", samples(2));
  loop.run({.timeout_s = 0.1});
  EXPECT_EQ(handled, 1);
  EXPECT_EQ(loop.decode_errors(), 0);
}

TEST(LcmLoop, AHandlersExceptionComesOutOfRunNotThroughC) {
  LcmLoop loop("memq://");
  int after = 0;
  loop.subscribe<samples_t>("S", [&](const samples_t& m) {
    if (m.seq == 1) throw std::runtime_error("handler failed on seq 1");
    ++after;
  });
  int second_subscriber = 0;
  loop.subscribe_raw("S", [&](const LcmMessage&) { ++second_subscriber; });
  loop.publish("S", samples(0));
  loop.publish("S", samples(1));
  loop.publish("S", samples(2));
  try {
    loop.run({.timeout_s = 2});
    FAIL() << "run() returned instead of rethrowing";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "handler failed on seq 1");
  }
  EXPECT_EQ(after, 1);              // seq 0
  EXPECT_EQ(second_subscriber, 1);  // seq 0 only: seq 1's dispatch stopped at the exception
  // The loop goes on afterwards with what is still queued.
  loop.run({.timeout_s = 0.1});
  EXPECT_EQ(after, 2);
  EXPECT_EQ(second_subscriber, 2);
}

TEST(LcmLoop, AnErrorReporterKeepsTheLoopGoing) {
  LcmLoop loop("memq://");
  std::vector<std::string> errors;
  loop.on_handler_error([&](const LcmMessage& m, const std::exception& e) {
    errors.push_back(std::string(m.channel) + ": " + e.what());
  });
  int handled = 0;
  loop.subscribe<samples_t>("S", [&](const samples_t& m) {
    if (m.seq == 1) throw std::runtime_error("bad");
    ++handled;
  });
  for (int i = 0; i < 3; ++i) loop.publish("S", samples(i));
  EXPECT_EQ(loop.run({.timeout_s = 0.2}), LcmLoopEnd::deadline);
  EXPECT_EQ(handled, 2);
  EXPECT_EQ(errors, (std::vector<std::string>{"S: bad"}));
}

TEST(LcmLoop, StopFromAHandlerEndsTheRunAfterThatMessage) {
  LcmLoop loop("memq://");
  int handled = 0;
  loop.subscribe<samples_t>("S", [&](const samples_t&) {
    if (++handled == 2) loop.stop();
  });
  for (int i = 0; i < 5; ++i) loop.publish("S", samples(i));
  EXPECT_EQ(loop.run({.timeout_s = 10}), LcmLoopEnd::stopped);
  EXPECT_EQ(handled, 2);
}

TEST(LcmLoop, TheStopSignalEndsAWaitAtOnce) {
  StopSignals stop;
  LcmLoop loop("memq://");
  loop.subscribe<samples_t>("S", [](const samples_t&) {});
  std::thread killer([] {
    std::this_thread::sleep_for(50ms);
    ::kill(::getpid(), SIGTERM);
  });
  const auto start = Clock::now();
  // One wait could last the whole 10 s: only the signal's pipe ends it early.
  EXPECT_EQ(loop.run({.stop = &stop, .timeout_s = 30, .max_wait_ms = 10'000}), LcmLoopEnd::stopped);
  killer.join();
  EXPECT_LT(Clock::now() - start, 2s);
}

TEST(LcmLoop, AStopBeforeTheRunEndsItBeforeAnyMessage) {
  StopSignals stop;
  LcmLoop loop("memq://");
  int handled = 0;
  loop.subscribe<samples_t>("S", [&](const samples_t&) { ++handled; });
  loop.publish("S", samples(0));
  stop.request();
  EXPECT_EQ(loop.run({.stop = &stop, .timeout_s = 5}), LcmLoopEnd::stopped);
  EXPECT_EQ(handled, 0);
  loop.drain(10, 1.0);  // drain ignores the stop: what arrived is handled
  EXPECT_EQ(handled, 1);
}

TEST(LcmLoop, TheDeadlineEndsAQuietRun) {
  LcmLoop loop("memq://");
  const auto start = Clock::now();
  EXPECT_EQ(loop.run({.timeout_s = 0.15}), LcmLoopEnd::deadline);
  const auto took = Clock::now() - start;
  EXPECT_GE(took, 150ms);
  EXPECT_LT(took, 2s);
}

TEST(LcmLoop, TimersRunOnTimeWithoutMessages) {
  LcmLoop loop("memq://");
  int fast = 0, every_wake = 0;
  std::vector<std::int64_t> times;
  loop.every(0.02, [&](std::int64_t now_us) {
    ++fast;
    times.push_back(now_us);
  });
  loop.every(0, [&](std::int64_t) { ++every_wake; });
  // Waits of up to 10 s: the 20 ms timer shortens them.
  loop.run({.timeout_s = 0.5, .max_wait_ms = 10'000});
  EXPECT_GE(fast, 15);
  EXPECT_LE(fast, 26);
  EXPECT_GE(every_wake, fast);
  for (std::size_t i = 1; i < times.size(); ++i) EXPECT_GE(times[i], times[i - 1]);
}

TEST(LcmLoop, ATimerCanStopTheLoop) {
  LcmLoop loop("memq://");
  int ticks = 0;
  loop.every(0.01, [&](std::int64_t) {
    if (++ticks == 3) loop.stop();
  }, 0);
  EXPECT_EQ(loop.run({.timeout_s = 10}), LcmLoopEnd::stopped);
  EXPECT_EQ(ticks, 3);
}

TEST(LcmLoop, RawSubscriptionsSeeTheBytes) {
  LcmLoop loop("memq://");
  std::string got;
  loop.subscribe_raw("RAW", [&](const LcmMessage& m) { got.assign(static_cast<const char*>(m.data), m.size); });
  loop.lcm().publish("RAW", "hello", 5);
  loop.run({.timeout_s = 0.1});
  EXPECT_EQ(got, "hello");
}

TEST(LcmLoop, ABadRegexIsRefused) {
  LcmLoop loop("memq://");
  EXPECT_FALSE(loop.subscribe_raw("SPINDOWN\\.(unclosed", [](const LcmMessage&) {}));
}

TEST(LcmLoop, UnsubscribedMessagesAreNotHandled) {
  LcmLoop loop("memq://");
  int handled = 0;
  loop.subscribe<samples_t>("S", [&](const samples_t&) { ++handled; });
  loop.unsubscribe_all();
  loop.publish("S", samples(0));
  loop.run({.timeout_s = 0.1});
  EXPECT_EQ(handled, 0);
}

}  // namespace
}  // namespace spindown
