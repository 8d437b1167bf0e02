// coast_jump: the decision that the reading jumped inside a coast (what came before was no part
// of it), on its own.
#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <vector>

#include "spindown/coast_jump.hpp"
#include "spindown/reading_scale.hpp"
#include "recorded_readings.hpp"

using namespace spindown;
using spindown::test::at;
using spindown::test::record;

namespace {

std::optional<CoastJump> judge(const SampleStore& s, double end_s, double amp, double step = 0.0, bool floating = false,
                               int* asked = nullptr) {
  std::vector<double> m5;
  LagNoise noise;
  const std::size_t end = at(end_s);
  return coast_jump(s, {0, end, amp, step, floating},
                    [&]() -> const LagNoise& {
                      if (asked) ++*asked;
                      noise = noise_over(s, 0, end);
                      return noise;
                    },
                    m5);
}

}  // namespace

TEST(CoastJump, ARiseInsideACoastIsWhereTheCoastBegins) {
  // An open pin's level (1.0, wandering) for 2 s, then A0 connected to the coasting motor at 2.5 V.
  const SampleStore s = record([](double t) { return t < 2 ? 1.0 + 0.05 * std::sin(3 * t) : 2.5 - 0.1 * (t - 2); }, 20.0, 0.005);
  const auto j = judge(s, 20.0, 1.0);
  ASSERT_TRUE(j.has_value());
  EXPECT_NEAR(double(j->at), double(at(2.0)), 3.0);
  EXPECT_NEAR(j->rose, 1.5, 0.1);
  EXPECT_GT(j->rose, 8 * j->white);  // evidence in the coast's own noise
}

TEST(CoastJump, AStepDownFarSteeperThanTheCoastIsAJumpToo) {
  // An open pin reading above the back-EMF (3.0) until connected at 1.5 s to a motor at 2.0.
  const SampleStore s = record([](double t) { return t < 1.5 ? 3.0 - 0.02 * t : 2.0 - 0.08 * (t - 1.5); }, 20.0, 0.004);
  const auto j = judge(s, 20.0, 3.0);
  ASSERT_TRUE(j.has_value());
  EXPECT_LT(j->rose, -0.8);
  EXPECT_NEAR(double(j->at), double(at(1.5)), 4.0);
}

TEST(CoastJump, ACoastWithinItsNoiseAndStepHasNoJumpAndNeverAsksItsNoiseAtEveryLag) {
  int asked = 0;
  const SampleStore s = record([](double t) { return std::max(2.8 - 0.12 * t, 0.0); }, 25.0, 0.006, 0.01);
  EXPECT_FALSE(judge(s, 24.0, 2.8, 0.01, false, &asked).has_value());
  EXPECT_EQ(asked, 0);
}

TEST(CoastJump, AWheelsRippleIsNoJumpWhereItsLevelOverWholeRipplesFalls) {
  // Once per revolution ±0.25 at 2 Hz on a coast at 0.05 a second, white noise 0.002: neighbouring
  // crests and troughs differ by far more than eight times the white noise, but the level over a
  // whole ripple only falls.
  const SampleStore s = record([](double t) { return 2.0 - 0.05 * t + 0.25 * std::sin(2 * M_PI * 2 * t); }, 30.0, 0.002);
  int asked = 0;
  EXPECT_FALSE(judge(s, 30.0, 2.0, 0.0, false, &asked).has_value());
  EXPECT_EQ(asked, 1);  // the ripple was looked at
}
