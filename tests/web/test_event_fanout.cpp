// EventFanout: each page gets the events meant for it, in order; a page that does not read is
// resynced (its backlog dropped) instead of holding the publisher or growing; the cap on pages.
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "spindown/event_fanout.hpp"

namespace spindown {
namespace {

using namespace std::chrono_literals;

WebUpdate update(WebUpdate::To to, std::string bench, std::string text) {
  return {to, std::move(bench), std::make_shared<const std::string>(std::move(text))};
}

TEST(EventFanout, EachPageGetsWhatIsMeantForIt) {
  EventFanout f;
  const auto room = f.connect("", "snap-room;");
  const auto b1 = f.connect("b1", "snap-b1;");
  const auto b2 = f.connect("b2", "snap-b2;");
  ASSERT_TRUE(room && b1 && b2);
  f.publish(update(WebUpdate::To::room, "", "room;"));
  f.publish(update(WebUpdate::To::bench, "b1", "b1-only;"));
  f.publish(update(WebUpdate::To::room_and_bench, "b2", "tile-b2;"));
  f.publish(update(WebUpdate::To::everyone, "", "all;"));
  std::string out;
  ASSERT_EQ(f.next(*room, out, 0ms), EventFanout::Next::events);
  EXPECT_EQ(out, "snap-room;room;tile-b2;all;");
  ASSERT_EQ(f.next(*b1, out, 0ms), EventFanout::Next::events);
  EXPECT_EQ(out, "snap-b1;b1-only;all;");
  ASSERT_EQ(f.next(*b2, out, 0ms), EventFanout::Next::events);
  EXPECT_EQ(out, "snap-b2;tile-b2;all;");
  EXPECT_EQ(f.next(*b2, out, 10ms), EventFanout::Next::idle);
}

TEST(EventFanout, APageThatDoesNotReadIsResyncedNotWaitedFor) {
  EventFanoutOptions o;
  o.max_queued_events = 10;
  EventFanout f(o);
  const auto slow = f.connect("", "snap;");
  const auto fast = f.connect("", "snap;");
  std::string out;
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < 10000; ++i) {
    f.publish(update(WebUpdate::To::room, "", "e;"));
    if (i % 5 == 0) f.next(*fast, out, 0ms);
  }
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 2s);  // generous: publishing never waits for a page
  ASSERT_EQ(f.next(*slow, out, 0ms), EventFanout::Next::resync);
  const auto c = f.counters();
  EXPECT_EQ(c.resyncs, 1);
  EXPECT_GE(c.dropped_events, 9990);
  f.resync(*slow, "fresh;");
  f.publish(update(WebUpdate::To::room, "", "after;"));
  ASSERT_EQ(f.next(*slow, out, 0ms), EventFanout::Next::events);
  EXPECT_EQ(out, "fresh;after;");
}

TEST(EventFanout, AQueueIsBoundedInBytesToo) {
  EventFanoutOptions o;
  o.max_queued_bytes = 1000;
  EventFanout f(o);
  const auto c = f.connect("", "");
  f.publish(update(WebUpdate::To::room, "", std::string(600, 'x')));
  f.publish(update(WebUpdate::To::room, "", std::string(600, 'y')));
  std::string out;
  EXPECT_EQ(f.next(*c, out, 0ms), EventFanout::Next::resync);
}

TEST(EventFanout, PagesPastTheCapAreRefusedAndAClosedFanoutEndsEveryWriter) {
  EventFanoutOptions o;
  o.max_clients = 2;
  EventFanout f(o);
  const auto a = f.connect("", "");
  const auto b = f.connect("", "");
  EXPECT_FALSE(f.connect("", ""));
  EXPECT_EQ(f.counters().refused, 1);
  f.disconnect(*a);
  const auto c = f.connect("b1", "");
  ASSERT_TRUE(c);
  EXPECT_EQ(f.counters().clients, 2u);
  std::string out;
  EXPECT_EQ(f.next(*a, out, 0ms), EventFanout::Next::closed);  // gone
  // A writer waiting for events ends when the fanout closes.
  std::thread waiter([&] { EXPECT_EQ(f.next(*b, out, 10s), EventFanout::Next::events); });  // "" was queued
  waiter.join();
  std::thread waiter2([&] { EXPECT_EQ(f.next(*b, out, 10s), EventFanout::Next::closed); });
  std::this_thread::sleep_for(20ms);
  f.close_all();
  waiter2.join();
  EXPECT_FALSE(f.connect("", ""));
}

}  // namespace
}  // namespace spindown
