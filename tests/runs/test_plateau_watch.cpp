// PlateauWatch: the decision that an open "coast" holds a plateau (a drive stepping down under
// power), on its own, looked at as the live detector does: every half second, the last second.
#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <optional>

#include "spindown/plateau_watch.hpp"
#include "recorded_readings.hpp"

using namespace spindown;
using spindown::test::at;
using spindown::test::record;

namespace {

// Looks every half second from 2 s after the cut (at 0 s) over the last second of samples, until
// a plateau or the recording's end.
std::optional<Plateau> watch(const SampleStore& s, double noise_floor, double* when = nullptr) {
  PlateauWatch w;
  w.start(0, 2.0);
  const PlateauCoast coast{0, 0.0, s.v(0), 0.0, noise_floor, false};
  for (std::size_t i = 0; i < s.end(); ++i) {
    if (s.t(i) < w.next_look_s()) continue;
    std::size_t first = i;
    while (first > 0 && s.t(i) - s.t(first - 1) <= 1.0) --first;
    const WindowFit hold = window_over(s, 1.0, first, i + 1);
    if (auto p = w.look(s, hold, s.t(i), 0.5, coast)) {
      if (when) *when = s.t(i);
      return p;
    }
  }
  return std::nullopt;
}

}  // namespace

TEST(PlateauWatch, ADriveSteppingDownToALowerSpeedHoldsAPlateau) {
  // From 3.0 down to 2.5 in a second (a setpoint step), then held there under power.
  const SampleStore s = record([](double t) { return t < 1 ? 3.0 - 0.5 * t : 2.5; }, 8.0, 0.005);
  double when = 0;
  const auto p = watch(s, 0.0, &when);
  ASSERT_TRUE(p.has_value());
  EXPECT_NEAR(p->level, 2.5, 0.01);
  EXPECT_LT(std::abs(p->rate), 0.5 * p->least);  // resolved far below what friction takes off
  EXPECT_GE(s.t(p->from), 0.9);                   // the plateau, not the fall before it
  EXPECT_NEAR(when, 3.0, 0.05);                   // the third look in a row: 2, 2.5 and 3 s
}

TEST(PlateauWatch, AFreeCoastNeverHoldsOne) {
  // Coulomb and viscous friction: the coast falls at every level.
  const SampleStore s = record([](double t) { return std::max(3.0 * std::exp(-0.05 * t) - 0.06 * t, 0.0); }, 25.0, 0.005);
  EXPECT_FALSE(watch(s, 0.0).has_value());
}

TEST(PlateauWatch, AFrozenReadingIsLeftToTheStandstillChecks) {
  PlateauWatch w;
  const SampleStore s = record([](double t) { return t < 1 ? 3.0 - 0.5 * t : 2.5; }, 8.0, 0.005);
  w.start(0, 2.0);
  const PlateauCoast frozen{0, 0.0, s.v(0), 0.0, 0.0, true};
  for (double now = 2.0; now < 8.0; now += 0.5) {
    const std::size_t i = static_cast<std::size_t>(std::lround(now / spindown::test::lab_period_s)) - 1;
    EXPECT_FALSE(w.look(s, window_over(s, 1.0, i - 49, i + 1), s.t(i), 0.5, frozen).has_value());
  }
}
