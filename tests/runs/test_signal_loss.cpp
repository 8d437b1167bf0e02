// signal_loss: the decision that a sensor gave up before the motor stopped, on its own.
#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>

#include "spindown/signal_loss.hpp"

using namespace spindown;

namespace {

// A coast at 50 Hz falling `rate` a second from 2.8, printed to `step`, reading `hold_at` (once it
// gets there) for hold_s seconds, then `tail` for one second (the standstill). Returns the store;
// *cut is 0, *first_in the tail's first sample.
SampleStore coast(double rate, double step, double hold_at, double hold_s, double tail, std::size_t* first_in) {
  SampleStore s;
  const double dt = 0.02;
  double t = 0, v = 2.8;
  while (v > hold_at) {
    s.push({t, std::round(v / step) * step});
    t += dt, v -= rate * dt;
  }
  for (double h = 0; h < hold_s; h += dt, t += dt) s.push({t, std::round(hold_at / step) * step});
  *first_in = s.end();
  for (int k = 0; k < 50; ++k, t += dt) s.push({t, tail});
  return s;
}

}  // namespace

TEST(SignalLoss, AReadingHeldLongerThanTheCoastAllowsThenZeroIsASensorThatGaveUp) {
  // A display that stops updating at 0.5: held 1 s where the coast falls 0.1 a second (five of
  // the print's 0.01 steps), then 0.
  std::size_t first_in = 0;
  const SampleStore s = coast(0.1, 0.01, 0.5, 1.0, 0.0, &first_in);
  const auto loss = signal_loss(s, {0, first_in, 0.0, 2.8, 0.0, 0.01});
  ASSERT_TRUE(loss.has_value());
  EXPECT_NEAR(loss->level, 0.5, 1e-9);
  EXPECT_NEAR(loss->last, 0.5, 1e-9);
  EXPECT_NEAR(loss->fall, 0.1 * 0.02, 2e-4);  // the coast's own fall per sample
  EXPECT_GT(first_in - loss->held, 40u);      // the hold is about a second of samples
}

TEST(SignalLoss, ALabStopsLastPrintedValuesAreNoLoss) {
  // The lab's coast ending in 0.02, 0.01, 0.00 on its 2-decimal print: it reaches zero falling.
  std::size_t first_in = 0;
  const SampleStore s = coast(0.1, 0.01, 0.0, 0.0, 0.0, &first_in);
  EXPECT_FALSE(signal_loss(s, {0, first_in, 0.0, 2.8, 0.0, 0.01}).has_value());
}

TEST(SignalLoss, ASlowCoastsLastPrintedStepIsNoLoss) {
  // A slow coast (0.005 a second) on a 2-decimal print holds 0.02 for 0.3 s, then reads 0: a drop
  // of two of the print's steps, under the three a collapse must exceed.
  std::size_t first_in = 0;
  const SampleStore s = coast(0.005, 0.01, 0.02, 0.3, 0.0, &first_in);
  EXPECT_FALSE(signal_loss(s, {0, first_in, 0.0, 2.8, 0.0, 0.01}).has_value());
}

TEST(SignalLoss, AStandstillAwayFromTheMotorsZeroIsNoSensorGivingUp) {
  // The reading settles at 0.4 (a floating pin's level), not at the motor's zero.
  std::size_t first_in = 0;
  const SampleStore s = coast(0.1, 0.01, 0.5, 1.0, 0.4, &first_in);
  EXPECT_FALSE(signal_loss(s, {0, first_in, 0.4, 2.4, 0.0, 0.01}).has_value());
}
