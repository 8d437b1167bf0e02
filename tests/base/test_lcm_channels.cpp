#include <gtest/gtest.h>

#include "spindown/lcm_channels.hpp"

using namespace spindown;

TEST(LcmChannels, NamesFollowTheContract) {
  EXPECT_EQ(channel_name("bench-3", ChannelKind::sample), "SPINDOWN.bench-3.SAMPLE");
  EXPECT_EQ(channel_name("B_1", ChannelKind::config), "SPINDOWN.B_1.CONFIG");
  EXPECT_EQ(channel_name("x", ChannelKind::run), "SPINDOWN.x.RUN");
  EXPECT_EQ(channel_name("x", ChannelKind::fit), "SPINDOWN.x.FIT");
  EXPECT_EQ(channel_name("x", ChannelKind::explain), "SPINDOWN.x.EXPLAIN");
  EXPECT_EQ(channel_name("x", ChannelKind::status), "SPINDOWN.x.STATUS");
}

TEST(LcmChannels, BenchIdRule) {
  std::string why;
  EXPECT_TRUE(is_valid_bench_id(std::string(32, 'a')));
  EXPECT_FALSE(is_valid_bench_id(std::string(33, 'a'), &why));
  EXPECT_NE(why.find("33 characters"), std::string::npos);
  EXPECT_FALSE(is_valid_bench_id("", &why));
  EXPECT_FALSE(is_valid_bench_id("a.b", &why));
  EXPECT_NE(why.find("0x2e at position 2"), std::string::npos) << why;
  EXPECT_FALSE(is_valid_bench_id("bänk"));
  EXPECT_THROW(channel_name("a b", ChannelKind::sample), std::invalid_argument);
}

TEST(LcmChannels, ParsesItsOwnNames) {
  const auto p = parse_channel("SPINDOWN.bench-3.FIT");
  ASSERT_TRUE(p);
  EXPECT_EQ(p->bench, "bench-3");
  EXPECT_EQ(p->kind, ChannelKind::fit);
  EXPECT_FALSE(parse_channel("SPINDOWN.bench-3.OTHER"));
  EXPECT_FALSE(parse_channel("OTHER.bench-3.FIT"));
  EXPECT_FALSE(parse_channel("SPINDOWN.a.b.FIT"));
  EXPECT_FALSE(parse_channel("SPINDOWN..FIT"));
}

// The split that readers counting a bad bench id apart use: views into the channel, the bench not
// checked; every suffix of the contract names its kind and nothing else does.
TEST(LcmChannels, SplitsWithoutCheckingTheBenchAndNamesEachKind) {
  const auto p = split_channel("SPINDOWN.bad bench!.SAMPLE");
  ASSERT_TRUE(p);
  EXPECT_EQ(p->bench, "bad bench!");
  EXPECT_EQ(p->suffix, "SAMPLE");
  EXPECT_FALSE(split_channel("SPINDOWN"));
  EXPECT_FALSE(split_channel("OTHER.a.FIT"));
  for (auto kind : {ChannelKind::sample, ChannelKind::config, ChannelKind::run, ChannelKind::fit,
                    ChannelKind::explain, ChannelKind::status})
    EXPECT_EQ(channel_kind(channel_suffix(kind)), kind);
  EXPECT_FALSE(channel_kind("sample"));
  EXPECT_FALSE(channel_kind("OTHER"));
}
