// level_return: the decision that a coast came back to the level it began at (no coast had
// begun), on its own.
#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <vector>

#include "spindown/level_return.hpp"
#include "spindown/reading_scale.hpp"
#include "recorded_readings.hpp"

using namespace spindown;
using spindown::test::at;
using spindown::test::record;

namespace {

struct Judged {
  std::optional<LevelReturn> ret;
  int noise_asked = 0;
};

Judged judge(const SampleStore& s, double coast_end_s) {
  Judged j;
  std::vector<double> scratch;
  LagNoise noise;
  const std::size_t end = at(coast_end_s);
  j.ret = level_return(s, {0, 0, end, 0.0, s.v(0), 0.0},
                       [&]() -> const LagNoise& {
                         ++j.noise_asked;
                         noise = noise_over(s, 0, end);
                         return noise;
                       },
                       scratch);
  return j;
}

}  // namespace

TEST(LevelReturn, ADriveHuntingAboutItsSetpointBeforeTheCutIsNoCoast) {
  // A drive hunting ±0.3 about 2.0 (2 s period) for 6 s, then the supply cut: a coast at 0.1 a
  // second from 2.3 to standstill at 29 s. Taken as one coast from 0 s, it stood back at its
  // level at 2, 4 and 6 s, where it must have fallen: the coast begins after the last return.
  const SampleStore s = record([](double t) { return t < 6 ? 2.0 + 0.3 * std::cos(M_PI * t) : std::max(2.3 - 0.1 * (t - 6), 0.0); },
                               31.0, 0.002);
  const Judged j = judge(s, 29.0);
  ASSERT_TRUE(j.ret.has_value());
  EXPECT_GE(j.ret->back, at(5.5));
  EXPECT_LE(j.ret->back, at(6.6));
  EXPECT_NEAR(j.ret->level, 2.3, 0.01);
  EXPECT_GT(j.ret->lost, 10 * j.ret->se);  // evidence in the recording's own noise
  EXPECT_EQ(j.noise_asked, 1);
}

TEST(LevelReturn, ACoastThatOnlyFallsIsNotJudgedAndItsNoiseNotAsked) {
  const SampleStore s = record([](double t) { return std::max(2.3 - 0.1 * t, 0.0); }, 25.0, 0.004);
  const Judged j = judge(s, 23.0);
  EXPECT_FALSE(j.ret.has_value());
  EXPECT_EQ(j.noise_asked, 0);  // every window fell far below the level: no noise measured
}

TEST(LevelReturn, AWheelsRippleOnACoastIsNoReturn) {
  // Once per revolution ±0.06 (a wheel's run-out) on a coast at 0.08 a second: the crests of the
  // first seconds stand near the level, but means over whole ripples fall with the coast.
  const SampleStore s = record([](double t) { return std::max(2.4 - 0.08 * t, 0.0) + 0.06 * std::sin(2 * M_PI * 4 * t); },
                               32.0, 0.003);
  EXPECT_FALSE(judge(s, 30.0).ret.has_value());
}
