#include <gtest/gtest.h>

#include "spindown/device_clock.hpp"

using spindown::DeviceClock;

TEST(DeviceClock, MillisAreMicrosecondsAndMonotonic) {
  DeviceClock c(1000);
  auto r = c.update(5234);
  EXPECT_EQ(r.time_us, 5'234'000);
  EXPECT_EQ(r.epoch, 0);
  EXPECT_FALSE(r.reset);
  r = c.update(5254);
  EXPECT_EQ(r.time_us, 5'254'000);
}

TEST(DeviceClock, MillisWrapAfter49DaysIsUnwrapped) {
  DeviceClock c(1000);
  const std::uint64_t near_end = 0xFFFFFFFFull - 15;  // 16 ms before the wrap
  auto r = c.update(near_end);
  EXPECT_EQ(r.time_us, std::int64_t(near_end) * 1000);
  r = c.update(4);  // 20 ms later, after the wrap
  EXPECT_TRUE(r.wrapped);
  EXPECT_FALSE(r.reset);
  EXPECT_EQ(r.epoch, 0);
  EXPECT_EQ(r.time_us, (std::int64_t(1) << 32) * 1000 + 4000);
  EXPECT_EQ(r.time_us - std::int64_t(near_end) * 1000, 20'000);
}

TEST(DeviceClock, MicrosWrapsEvery71Minutes) {
  DeviceClock c(1);
  std::int64_t prev = -1;
  std::uint64_t t = 0xFFFFFFFFull - 50'000;
  for (int i = 0; i < 10; ++i, t += 20'000) {  // crosses 2^32 µs
    const auto r = c.update(t & 0xFFFFFFFFull);
    EXPECT_FALSE(r.reset);
    if (prev >= 0) {
      EXPECT_EQ(r.time_us - prev, 20'000);
    }
    prev = r.time_us;
  }
}

TEST(DeviceClock, ArduinoResetStartsANewEpoch) {
  DeviceClock c(1000);
  c.update(60'000);
  c.update(60'020);
  auto r = c.update(3);  // rebooted: millis() restarts
  EXPECT_TRUE(r.reset);
  EXPECT_FALSE(r.wrapped);
  EXPECT_EQ(r.epoch, 1);
  EXPECT_EQ(r.time_us, 3000);
  r = c.update(23);
  EXPECT_FALSE(r.reset);
  EXPECT_EQ(r.epoch, 1);
  EXPECT_EQ(c.epoch(), 1);
}

TEST(DeviceClock, SmallStepBackIsAResetNotAWrap) {
  DeviceClock c(1000);
  c.update(600);
  const auto r = c.update(100);
  EXPECT_TRUE(r.reset);
  EXPECT_EQ(r.epoch, 1);
}

TEST(DeviceClock, MarkResetAndUnitChangeCountOnlyAfterAReading) {
  DeviceClock c(1000);
  c.mark_reset();  // nothing read yet: the first epoch is still 0
  EXPECT_EQ(c.update(10).epoch, 0);
  c.set_tick_us(1);  // protocol switch: new unit, new epoch
  const auto r = c.update(5'000'000);
  EXPECT_TRUE(r.reset);
  EXPECT_EQ(r.epoch, 1);
  EXPECT_EQ(r.time_us, 5'000'000);
}
