// The run's window, computed once for fit, explain and the live fitter (run_window.hpp): the cut to
// the end less the outliers and any sample that is not a number, τ from the cut, readings less the
// zero level, the part before the stop, weights and noise from the kept samples.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "spindown/fit.hpp"
#include "spindown/run_window.hpp"
#include "synthetic_case.hpp"

using namespace spindown;
using spindown::testing::Case;
using spindown::testing::make_case;

namespace {

Case lab_case() {
  SyntheticRunSpec spec;
  spec.seed = 7;
  return make_case(spec);
}

}  // namespace

TEST(RunWindow, LeavesOutTheOutliersAndCountsWhatMovesBeforeTheStop) {
  Case c = lab_case();
  spindown::Run run = c.seg;
  ASSERT_TRUE(run.stopped);
  run.zero_level = 0.01;
  // Two dropouts in the coast and one in the standstill tail.
  run.outliers = {run.cut_index + 10, run.cut_index + 50, run.stop_index + 2};
  const RunWindow w(c.t, c.run.volts, run, true);
  const std::size_t all = run.end_index - run.cut_index;
  EXPECT_EQ(w.size(), all - 3);
  EXPECT_EQ(w.moving(), run.stop_index - run.cut_index - 2);
  EXPECT_EQ(w.readings().size(), all);  // the caller's readings, outliers included
  // The sample after the first dropout is the window's tenth: τ from the cut, the zero level off.
  EXPECT_DOUBLE_EQ(w.tau()[10], c.t[run.cut_index + 11] - run.t_cut_s);
  EXPECT_DOUBLE_EQ(w.y()[10], c.run.volts[run.cut_index + 11] - 0.01);
  EXPECT_DOUBLE_EQ(w.zero_level(), 0.01);
  double mean_weight = 0;
  for (double x : w.weight()) mean_weight += x / static_cast<double>(w.size());
  EXPECT_NEAR(mean_weight, 1.0, 1e-9);
  EXPECT_TRUE(w.noise().known);
  EXPECT_GT(w.reading_noise(), 0.0);
}

TEST(RunWindow, AReadingThatIsNotANumberIsLeftOutLikeAnOutlier) {
  Case c = lab_case();
  const spindown::Run run = c.seg;  // no outliers: the vectorised copy, then the check
  std::vector<double> v = c.run.volts;
  v[run.cut_index + 20] = std::numeric_limits<double>::quiet_NaN();
  const RunWindow bad(c.t, v, run, true);
  spindown::Run marked = run;
  marked.outliers = {run.cut_index + 20};
  const RunWindow as_outlier(c.t, c.run.volts, marked, true);
  ASSERT_EQ(bad.size(), as_outlier.size());
  EXPECT_EQ(bad.moving(), as_outlier.moving());
  for (std::size_t i = 0; i < bad.size(); ++i) {
    ASSERT_EQ(bad.tau()[i], as_outlier.tau()[i]) << i;
    ASSERT_EQ(bad.y()[i], as_outlier.y()[i]) << i;
    ASSERT_EQ(bad.weight()[i], as_outlier.weight()[i]) << i;
  }
  // and the fit on it is the fit with that sample marked an outlier, not a NaN fit.
  const RunFit f = fit_run(c.t, v, Quantity::back_emf_volts, run, FitOptions{});
  ASSERT_FALSE(f.best.empty());
  EXPECT_TRUE(std::isfinite(f.model(ModelKind::combined)->rmse));
  EXPECT_EQ(f.model(ModelKind::combined)->n, bad.size());
}

TEST(RunWindow, UnweightedGivesWeightsOfOne) {
  Case c = lab_case();
  const RunWindow w(c.t, c.run.volts, c.seg, false);
  EXPECT_FALSE(w.weighted());
  for (double x : w.weight()) ASSERT_EQ(x, 1.0);
}

TEST(RunWindow, AWindowOutsideTheRecordingIsEmptyNotAnOverrun) {
  Case c = lab_case();
  spindown::Run run = c.seg;
  run.cut_index = c.t.size() + 5;
  run.end_index = c.t.size() + 50;
  run.outliers = {c.t.size() + 7};
  const RunWindow w(c.t, c.run.volts, run, true);
  EXPECT_EQ(w.size(), 0u);
  EXPECT_EQ(w.moving(), 0u);
}
