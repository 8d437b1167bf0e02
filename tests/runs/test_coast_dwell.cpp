// coast_dwell: the decision that a "coast" held a level far longer than a coast can (a drive
// under power), on its own.
#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <vector>

#include "spindown/coast_dwell.hpp"
#include "recorded_readings.hpp"

using namespace spindown;
using spindown::test::at;
using spindown::test::record;

namespace {

std::optional<CoastDwell> judge(const SampleStore& s, double end_s, double noise, double step = 0.0) {
  std::vector<double> scratch;
  return coast_dwell(s, {0, at(end_s), noise, step}, scratch);
}

// A drive that overshoots to 3.0 at its start, settles on 2.5 until cut_s, then coasts at 0.25 a
// second to standstill (2 mV of noise), recorded until 2 s after it stops.
SampleStore settled_drive(double cut_s) {
  return record([cut_s](double t) {
    if (t < 1) return 3.0 - 0.5 * t;
    if (t < cut_s) return 2.5;
    return std::max(2.5 - 0.25 * (t - cut_s), 0.0);
  }, cut_s + 12.0, 0.002);
}

}  // namespace

TEST(CoastDwell, AStartUpOvershootSettlingOnItsSetpointIsNoCoast) {
  // A drive overshoots to 3.0 at its start, settles on 2.5 for 8 s, then the supply is cut: a coast
  // at 0.25 a second. Taken as a coast from the overshoot, it held 2.5 ± its noise for 8 s, where
  // it then fell four more of those bands in about 0.3 s (a dwell counts beyond 20 times that).
  const SampleStore s = settled_drive(9.0);
  const auto d = judge(s, 19.0, 0.002);
  ASSERT_TRUE(d.has_value());
  EXPECT_NEAR(double(d->at), double(at(9.0)), 25.0);  // within half a second of the cut
  EXPECT_GT(d->at - d->from, at(6.0));  // held for most of the 8 s
  EXPECT_NEAR(d->band, 4 * 0.002, 0.002);  // four times the coast's own noise
}

TEST(CoastDwell, AHoldShorterThanTwentyTimesTheFallIsNoDwell) {
  // The same drive settled for only 2 s: where the coast then falls four bands in 0.3 s, a 2-s hold
  // is within what the decision allows (a slow start, Stribeck friction): no dwell.
  const SampleStore s = settled_drive(3.0);
  EXPECT_FALSE(judge(s, 13.0, 0.002).has_value());
}

TEST(CoastDwell, AFreeCoastNeverDwellsEvenWithStribeckFrictionNearStandstill) {
  // Coulomb + viscous, plus friction rising near standstill: its last third falls fastest, so the
  // search runs, and finds no level held longer than the coast's own fall allows.
  const SampleStore s = record([](double t) {
    const double w = 2.6 * std::exp(-0.04 * t) - 0.06 * t - 0.02 * t * t / 10;
    return std::max(w, 0.0);
  }, 26.0, 0.004, 0.01);
  EXPECT_FALSE(judge(s, 24.0, 0.004, 0.01).has_value());
}

TEST(CoastDwell, AReadingFrozenOnOneValueIsASensorNotADrive) {
  // A sensor stuck at 2.50 (one printed value, no noise) for 6 s, then a coast: one value held over
  // half the dwell is a frozen reading, which the stop and signal checks judge, not this one.
  const SampleStore s = record([](double t) { return t < 6 ? 2.5 : std::max(2.5 - 0.12 * (t - 6), 0.0); }, 28.0, 0.0, 0.01);
  EXPECT_FALSE(judge(s, 26.0, 0.004, 0.01).has_value());
}
