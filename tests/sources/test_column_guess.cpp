// column_guess.hpp: which columns of a table without names are the time and the speed, from the
// numbers alone, judged against how the table was made.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "spindown/column_guess.hpp"

using namespace spindown;

namespace {

// A dyno logger at 50 Hz: sample number, time (s), speed (rpm: spin-up from 1 s, cut at 6 s, a
// combined-friction coast to rest), supply current (A: a start-up surge, 0 after the cut), winding
// temperature (°C, creeping up).
std::vector<std::vector<double>> dyno_table(double time_scale) {
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0, 1);
  std::vector<std::vector<double>> cols(5);
  const double a = 150.0, b = 0.05;  // coast: dω/dt = -a - b ω (rpm/s)
  double w = 0;
  for (int i = 0; i < 1200; ++i) {
    const double t = 0.02 * i;
    if (t >= 1 && t < 6) w = 2800 * (1 - std::exp(-(t - 1) / 0.5));
    else if (t >= 6) w = std::max(0.0, w - 0.02 * (a + b * w));
    const double current = t >= 1 && t < 6 ? 0.35 + 2.5 * std::exp(-(t - 1) / 0.3) : 0.0;
    cols[0].push_back(i + 1);
    cols[1].push_back(std::round(t * time_scale * 1000) / 1000);
    cols[2].push_back(w > 0 ? w + 2 * noise(rng) : 0.0);
    cols[3].push_back(current + 0.01 * noise(rng));
    cols[4].push_back(std::round((24 + 0.01 * t) * 100) / 100);
  }
  return cols;
}

}  // namespace

TEST(ColumnGuess, TimeInSecondsAndTheSpeedOfADynoLog) {
  const ColumnGuess g = guess_columns(dyno_table(1));
  EXPECT_EQ(g.time, 1);  // not the sample number beside it
  EXPECT_EQ(g.time_unit, TimeUnit::s);
  EXPECT_EQ(g.value, 2);  // not the current, which drops at the cut in one sample
  const auto p = column_proposal(g);
  ASSERT_TRUE(p);
  EXPECT_NE(p->find("--time-column 2 --time-unit s --value-column 3"), std::string::npos) << *p;
  EXPECT_NE(p->find("--value-unit rpm"), std::string::npos) << *p;  // 2800 is no back-EMF in volts
  EXPECT_NE(p->find("--value-unit mV if they are millivolts"), std::string::npos) << *p;  // or whole millivolts
}

TEST(ColumnGuess, MillisAndMicrosFromTheirSteps) {
  EXPECT_EQ(guess_columns(dyno_table(1000)).time_unit, TimeUnit::ms);
  EXPECT_EQ(guess_columns(dyno_table(1e6)).time_unit, TimeUnit::us);
  bool integral = false;
  double step = 0;
  const std::vector<double> t{1000, 1020, 1040, 1061, 1080};
  EXPECT_EQ(time_unit_from_values(t, &integral, &step), TimeUnit::ms);
  EXPECT_TRUE(integral);
  EXPECT_DOUBLE_EQ(step, 20);
}

TEST(ColumnGuess, NothingToProposeWhenNoColumnRisesOrCoasts) {
  std::vector<std::vector<double>> flat(3, std::vector<double>(50, 1.0));
  const ColumnGuess g = guess_columns(flat);
  EXPECT_EQ(g.time, -1);
  EXPECT_EQ(g.value, -1);
  EXPECT_FALSE(column_proposal(g));
}
