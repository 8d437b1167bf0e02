// The shared Levenberg–Marquardt loop (spindown/levenberg_marquardt.hpp) on a problem of its own:
// y = a·e^(−b·t) with the bounds a > 0, b ≥ 0, its 2×2 normal equations solved by hand (the loop
// needs no matrix type). It must find a known optimum, end exactly on a bound that binds and stay
// there, and keep to its problem's caps and rules.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "spindown/levenberg_marquardt.hpp"

using namespace spindown;

namespace {

struct Decay {
  using Point = std::array<double, 2>;  // a, b
  struct State {
    double jtj[2][2] = {};
    double jtr[2] = {};
  };

  std::vector<double> t, y;
  LmPolicy lm_policy{};
  int evaluations = 0;
  int at_minimum_calls = 0;

  LmPolicy policy() const { return lm_policy; }
  double evaluate(const Point& x, State& s) {
    ++evaluations;
    s = State{};
    double sse = 0;
    for (std::size_t i = 0; i < t.size(); ++i) {
      const double e = std::exp(-x[1] * t[i]), r = y[i] - x[0] * e;
      const double g[2] = {e, -x[0] * t[i] * e};
      for (int a = 0; a < 2; ++a) {
        s.jtr[a] += g[a] * r;
        for (int b = 0; b < 2; ++b) s.jtj[a][b] += g[a] * g[b];
      }
      sse += r * r;
    }
    return sse;
  }
  bool at_minimum(const Point&, const State&, double) {
    ++at_minimum_calls;
    return false;
  }
  // (JᵀJ + λ·diag JᵀJ)·δ = Jᵀr by Cramer's rule, then a > 0 and b ≥ 0 by projection. With b on
  // its bound and the descent pushing it outward, b is held there (an active set) and a alone
  // moves: projection alone would let LM stall short of the bounded minimum.
  bool step(const Point& x, const State& s, double lambda, Point& out) const {
    const double a00 = s.jtj[0][0] * (1 + lambda), a11 = s.jtj[1][1] * (1 + lambda), a01 = s.jtj[0][1];
    if (x[1] <= 0 && s.jtr[1] <= 0) {
      if (!(a00 > 0)) return false;
      out = {std::max(x[0] + s.jtr[0] / a00, 1e-12), 0.0};
      return true;
    }
    const double det = a00 * a11 - a01 * a01;
    if (!(det > 0)) return false;
    const double d0 = (a11 * s.jtr[0] - a01 * s.jtr[1]) / det, d1 = (a00 * s.jtr[1] - a01 * s.jtr[0]) / det;
    out = {std::max(x[0] + d0, 1e-12), std::max(x[1] + d1, 0.0)};
    return true;
  }
  bool negligible(const Point& from, const Point& to) const {
    return std::abs(to[0] - from[0]) <= 1e-12 * std::abs(from[0]) && std::abs(to[1] - from[1]) <= 1e-12 * std::abs(from[1]);
  }
};

static_assert(LeastSquaresProblem<Decay>);

Decay decay_data(double a, double b, double ripple = 0.0) {
  Decay d;
  for (int i = 0; i < 200; ++i) {
    const double t = 0.05 * i;
    d.t.push_back(t);
    d.y.push_back(a * std::exp(-b * t) + ripple * std::sin(7.0 * t));
  }
  return d;
}

}  // namespace

TEST(LevenbergMarquardt, FindsAKnownOptimum) {
  Decay d = decay_data(3.0, 0.7);
  const auto r = levenberg_marquardt(d, Decay::Point{1.0, 0.1});
  EXPECT_TRUE(r.converged);
  EXPECT_NEAR(r.theta[0], 3.0, 1e-8);
  EXPECT_NEAR(r.theta[1], 0.7, 1e-8);
  EXPECT_LT(r.sse, 1e-15);
  // The count is the problem's own: every evaluation, the start's included.
  EXPECT_EQ(r.evals, d.evaluations);
  EXPECT_LE(r.evals, d.policy().max_evaluations);
  // The state returned is the optimum's: Jᵀr there is ~0.
  EXPECT_NEAR(r.state.jtr[0], 0.0, 1e-7);
  EXPECT_NEAR(r.state.jtr[1], 0.0, 1e-7);
}

TEST(LevenbergMarquardt, EndsOnABoundThatBindsAndStaysThere) {
  // Growing data: the best decay rate is below the bound b ≥ 0, so the fit ends at b = 0 exactly,
  // with a the plain mean of y, and calls that a (bounded) minimum.
  Decay d = decay_data(2.0, -0.2);
  const auto r = levenberg_marquardt(d, Decay::Point{1.0, 0.5});
  EXPECT_TRUE(r.converged);
  EXPECT_EQ(r.theta[1], 0.0);
  double mean = 0;
  for (double v : d.y) mean += v;
  mean /= static_cast<double>(d.y.size());
  EXPECT_NEAR(r.theta[0], mean, 1e-9 * mean);
  // The gradient still pushes b outward (Jᵀr for b = −Σ a·t·r < 0 would lower b): the bound is active.
  EXPECT_LT(r.state.jtr[1], 0.0);
}

TEST(LevenbergMarquardt, NeverRaisesTheSse) {
  Decay d = decay_data(3.0, 0.7, 0.05);
  Decay::State s;
  const Decay::Point start{10.0, 3.0};
  const double sse_start = d.evaluate(start, s);
  const auto r = levenberg_marquardt(d, start);
  EXPECT_TRUE(r.converged);
  EXPECT_LT(r.sse, sse_start);
  Decay::State at;
  EXPECT_EQ(d.evaluate(r.theta, at), r.sse);
}

TEST(LevenbergMarquardt, KeepsToThePolicysCaps) {
  Decay d = decay_data(3.0, 0.7, 0.05);
  d.lm_policy.max_evaluations = 3;
  const auto r = levenberg_marquardt(d, Decay::Point{10.0, 3.0});
  EXPECT_FALSE(r.converged);
  EXPECT_EQ(r.evals, 3);

  Decay e = decay_data(3.0, 0.7, 0.05);
  e.lm_policy.max_iterations = 2;
  const auto q = levenberg_marquardt(e, Decay::Point{10.0, 3.0});
  EXPECT_FALSE(q.converged);
  EXPECT_EQ(e.at_minimum_calls, 2);  // the problem's test runs once before each step
}

TEST(LevenbergMarquardt, TheProblemsTestBeforeAStepEndsIt) {
  struct AtOnce : Decay {
    bool at_minimum(const Point&, const State&, double) { return true; }
  };
  AtOnce d;
  static_cast<Decay&>(d) = decay_data(3.0, 0.7);
  const auto r = levenberg_marquardt(d, Decay::Point{1.0, 0.1});
  EXPECT_TRUE(r.converged);
  EXPECT_EQ(r.evals, 1);
  EXPECT_EQ(r.theta[0], 1.0);
}

TEST(LevenbergMarquardt, StopsUnconvergedWhenTheSystemCannotBeSolved) {
  struct Singular : Decay {
    bool step(const Point&, const State&, double, Point&) const { return false; }
  };
  Singular d;
  static_cast<Decay&>(d) = decay_data(3.0, 0.7);
  const auto r = levenberg_marquardt(d, Decay::Point{1.0, 0.1});
  EXPECT_FALSE(r.converged);
  EXPECT_EQ(r.evals, 1);
}

TEST(LevenbergMarquardt, AnEqualSseIsTakenOnlyWhenThePolicySaysSo) {
  // A flat problem: every point has the same SSE. Taken, the first step gains nothing and so
  // converges; refused, λ grows until no step is deemed to improve.
  struct Flat : Decay {
    double evaluate(const Point&, State& s) {
      ++evaluations;
      s = State{};
      s.jtj[0][0] = s.jtj[1][1] = 1;
      s.jtr[0] = 1;
      return 1.0;
    }
  };
  Flat taken;
  taken.lm_policy.take_equal = true;
  const auto a = levenberg_marquardt(taken, Decay::Point{1.0, 0.0});
  EXPECT_TRUE(a.converged);
  EXPECT_EQ(a.evals, 2);
  EXPECT_GT(a.theta[0], 1.0);

  Flat refused;
  refused.lm_policy.take_equal = false;
  const auto b = levenberg_marquardt(refused, Decay::Point{1.0, 0.0});
  EXPECT_TRUE(b.converged);  // λ from 1e-3 past 1e10: 14 refused steps
  EXPECT_EQ(b.evals, 15);
  EXPECT_EQ(b.theta[0], 1.0);
}
