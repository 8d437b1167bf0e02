// The shared bounded refinement (spindown/bounded_refinement.hpp): NLopt's L-BFGS under bounds,
// what each way of ending says, and that no exception of the objective crosses NLopt.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

#include "spindown/bounded_refinement.hpp"

using namespace spindown;

namespace {

// (x0 − 2)² + (x1 + 1)²: its minimum (2, −1) lies outside x1 ≥ 0, so the bounded one is (2, 0).
double bowl(std::span<const double> x, std::span<double> grad) {
  if (!grad.empty()) grad[0] = 2 * (x[0] - 2), grad[1] = 2 * (x[1] + 1);
  return (x[0] - 2) * (x[0] - 2) + (x[1] + 1) * (x[1] + 1);
}

RefinementOptions box() { return {.lower = {-10, 0}, .upper = {10, 10}}; }

}  // namespace

TEST(BoundedRefinement, FindsTheMinimumOnItsBound) {
  std::vector<double> x{5, 5};
  int evaluations = 7;  // grows by the refinement's own
  const std::string why = refine_bounded(x, box(), bowl, evaluations);
  EXPECT_EQ(why, "");
  EXPECT_NEAR(x[0], 2, 1e-6);
  EXPECT_EQ(x[1], 0);
  EXPECT_GT(evaluations, 7);
  EXPECT_LT(evaluations, 7 + 400);
}

TEST(BoundedRefinement, SaysWhenItRanOutOfEvaluations) {
  // A long narrow valley, two evaluations allowed.
  const auto valley = [](std::span<const double> x, std::span<double> grad) {
    const double a = 1 - x[0], b = x[1] - x[0] * x[0];
    if (!grad.empty()) grad[0] = -2 * a - 400 * x[0] * b, grad[1] = 200 * b;
    return a * a + 100 * b * b;
  };
  std::vector<double> x{-1.5, 2};
  RefinementOptions options = box();
  options.lower = {-10, -10};
  options.max_evaluations = 2;
  int evaluations = 0;
  EXPECT_EQ(refine_bounded(x, options, valley, evaluations), "no convergence within 2 evaluations");
  EXPECT_GE(evaluations, 2);  // NLopt's L-BFGS counts its evaluations its own way: every call is counted here
}

TEST(BoundedRefinement, AnObjectiveThatThrowsStopsItWithTheReason) {
  int calls = 0;
  const auto failing = [&](std::span<const double> x, std::span<double> grad) {
    if (++calls == 3) throw std::runtime_error("simulator diverged");
    return bowl(x, grad);
  };
  std::vector<double> x{5, 5};
  int evaluations = 0;
  EXPECT_EQ(refine_bounded(x, box(), failing, evaluations), "the objective failed: simulator diverged");
  EXPECT_GE(evaluations, 3);
  // x is the best point NLopt had: inside the bounds, no worse than the start.
  EXPECT_GE(x[1], 0);
  std::vector<double> none;
  EXPECT_LE(bowl(x, none), bowl(std::vector<double>{5, 5}, none));
}

TEST(BoundedRefinement, NloptsOwnComplaintsAreReported) {
  std::vector<double> x{5, 5};
  RefinementOptions options = box();
  options.lower = {-10};  // one bound for two parameters
  int evaluations = 0;
  const std::string why = refine_bounded(x, options, bowl, evaluations);
  EXPECT_EQ(why.rfind("NLopt: ", 0), 0u) << why;
  EXPECT_EQ(evaluations, 0);
}
