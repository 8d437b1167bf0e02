// stop_shape: the decision that a coast stops (Coulomb friction to the end) or creeps into its
// floor (pure viscous: an exponential), and the measurements it is made of, on their own.
#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <limits>

#include "spindown/stop_shape.hpp"
#include "recorded_readings.hpp"

using namespace spindown;
using spindown::test::at;
using spindown::test::record;

namespace {

// The three measurements of a coast from 0 s that reaches its floor 0 at t_stop.
StopShape shape(const SampleStore& s, double amp, double t_stop) {
  const std::size_t stop = at(t_stop);
  const std::size_t k = last_quarter_index(s, 0, stop, 0.25 * amp);
  const double t_quarter = s.t(k);
  return {end_rate(0.0, t_quarter, t_stop), approach_t_stat(s, 0, stop, 1.0), floor_rate_t(s, k, stop, 0.0)};
}

}  // namespace

TEST(StopShape, ACoulombCoastStops) {
  // Dry friction: a straight line to the floor at 20 s.
  const SampleStore s = record([](double t) { return std::max(2.0 - 0.1 * t, 0.0); }, 24.0, 0.004);
  const StopShape sh = shape(s, 2.0, 20.0);
  EXPECT_NEAR(sh.end_rate, 1.0, 0.05);  // the last quarter in a quarter of the time
  EXPECT_GT(sh.approach_t, 10.0);
  EXPECT_GT(sh.floor_t, 1.0);  // a rate at the floor (4 mV of noise on 2 mV steps blurs it: not alone)
  EXPECT_FALSE(sh.creeps_in());
}

TEST(StopShape, APureViscousCoastCreepsIn) {
  // An exponential (τ = 5 s), "flat" in its noise by 25 s: the last quarter took most of the coast,
  // the reading no longer falls clearly before it, and its rate died with its height.
  const SampleStore s = record([](double t) { return 2.0 * std::exp(-t / 5.0); }, 30.0, 0.004);
  const StopShape sh = shape(s, 2.0, 25.0);
  EXPECT_LT(sh.end_rate, 0.5);
  EXPECT_LT(sh.floor_t, 4.0);
  EXPECT_TRUE(sh.creeps_in());
}

TEST(StopShape, AnyOneSignOfAStopIsEnough) {
  EXPECT_FALSE((StopShape{0.3, 3.0, 9.0}.creeps_in()));   // still a finite rate at the floor
  EXPECT_FALSE((StopShape{0.3, 40.0, 1.0}.creeps_in()));  // still falling clearly before it
  EXPECT_FALSE((StopShape{0.9, 3.0, 1.0}.creeps_in()));   // crossed its last quarter fast
  EXPECT_EQ(end_rate(0.0, 10.0, 10.0), std::numeric_limits<double>::infinity());
}

TEST(StopShape, AValueHeldLongerThanTheCoastAllowsIsOneReading) {
  // A per-tooth sensor holds its last reading (0.40) for 1.5 s where the coast falls 0.1 a second.
  const SampleStore held = record([](double t) { return t < 16 ? 2.0 - 0.1 * t : 0.4; }, 17.5, 0.0, 0.01);
  EXPECT_NEAR(double(held_into(held, 0, held.end(), 0.01)), double(at(16.0)), 3.0);  // the print reads 0.40 from 15.96 s
  // The lab's 2-decimal print holds a value a few samples: that is the coast's own pace.
  const SampleStore lab = record([](double t) { return std::max(2.0 - 0.1 * t, 0.0); }, 15.0, 0.0, 0.01);
  EXPECT_EQ(held_into(lab, 0, lab.end(), 0.01), lab.end());
}
