// TwoSegmentSplit: where, in a window holding a cut, the coast begins (a constant lead-in, then
// the coast's line), on its own.
#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <vector>

#include "spindown/two_segment_split.hpp"
#include "recorded_readings.hpp"

using namespace spindown;
using spindown::test::at;
using spindown::test::record;

namespace {

}  // namespace

TEST(TwoSegmentSplit, ThePowerCutIsWhereTheSupplysLevelMeetsTheCoastsLine) {
  // The supply's 3.0 for a second, then the back-EMF at 2.8 falling 0.2 a second.
  const SampleStore s = record([](double t) { return t < 1.0 ? 3.0 : 2.8 - 0.2 * (t - 1.0); }, 3.0, 0.003);
  std::vector<double> scratch;
  const TwoSegmentSplit split(s, 0, s.end() - 1, scratch);
  const std::size_t k = split.best_split(0);
  EXPECT_NEAR(double(k), 50.0, 1.0);
  const TwoSegmentSplit::Line l = split.post_line(k);
  EXPECT_NEAR(l.v0, 2.8, 0.01);
  EXPECT_NEAR(l.slope, -0.2, 0.01);
  EXPECT_NEAR(l.sd, 0.003, 0.001);
}

TEST(TwoSegmentSplit, WithZerosThenTheSupplyThenTheCoastTheCoastFollowsTheLaterStep) {
  // A0 read zeros until the motor was powered (0.5 s), the supply's 3.0 for 0.6 s, then the cut:
  // back-EMF 2.6 falling. The best single split may take the first step; the later step is the cut.
  const SampleStore s = record([](double t) { return t < 0.5 ? 0.0 : t < 1.1 ? 3.0 : 2.6 - 0.2 * (t - 1.1); }, 3.0, 0.003);
  std::vector<double> scratch;
  const TwoSegmentSplit split(s, 0, s.end() - 1, scratch);
  std::size_t kb = 0;
  const std::size_t k = split.later_step(kb, split.best_split(0));
  EXPECT_NEAR(double(k), 55.0, 1.0);   // 1.1 s
  EXPECT_NEAR(double(kb), 25.0, 1.0);  // the lead-in is the supply's plateau, from 0.5 s
  EXPECT_NEAR(split.post_line(k).v0, 2.6, 0.01);
}

TEST(TwoSegmentSplit, ScratchTooSmallIsGrownAndAWindowAnywhereInTheStoreIsSplit) {
  const SampleStore s = record([](double t) { return t < 2.0 ? 0.0 : t < 3.0 ? 2.0 : 1.9 - 0.1 * (t - 3.0); }, 5.0, 0.002);
  std::vector<double> scratch(3);
  const TwoSegmentSplit split(s, 100, 220, scratch);  // [2 s, 4.4 s]
  EXPECT_GE(scratch.size(), 6u * 122u);
  EXPECT_NEAR(double(split.best_split(0)), 50.0, 1.0);  // 3 s, 50 samples into the window
}
