#pragma once
// One Levenberg–Marquardt loop for every least-squares fit in the library: the friction models'
// (fit) and the hidden effects' (explain). The loop owns only what all of them share: the damping
// schedule (λ from 10⁻³, ÷10 after a step that is taken, down to 10⁻¹²; ×10 after one that is
// not, and past 10¹⁰ no step improves: a minimum, perhaps on a bound), taking or refusing a
// step by its SSE, and counting evaluations. The problem owns the rest, as its policy:
//
//   Point, State       the parameters, and what one evaluation leaves (JᵀJ, Jᵀr, anything the
//                      caller wants back at the optimum, such as the model and its Jacobian)
//   policy()           the caps on iterations and evaluations, whether a step that leaves the
//                      SSE unchanged is taken, and the relative gain below which it has converged
//   evaluate(x, s)     the SSE at x, with s filled for x
//   at_minimum(x, s, sse)
//                      a test before each step (a fit may know from s alone that it is done)
//   step(x, s, λ, out) solves the damped system at x (the damping, its floor and any active set
//                      at the bounds are the problem's), projects x + step onto the bounds into
//                      out; false when the system cannot be solved (the loop stops unconverged)
//   negligible(x, out) a test on a step that is taken (the step is small beside x)
//
// Header-only and free of any linear-algebra type: the problem brings its own matrices, fixed or
// dynamic, so the loop adds no arithmetic of its own to the fit's and changes no bit of it.
#include <algorithm>
#include <concepts>
#include <utility>

namespace spindown {

struct LmPolicy {
  int max_iterations = 100;
  int max_evaluations = 200;
  bool take_equal = false;       // take a step whose SSE equals the current one
  double relative_gain = 1e-14;  // converged once a step gains no more than this fraction of the SSE
};

template <class P>
concept LeastSquaresProblem =
    requires(P& p, const typename P::Point& x, typename P::Point& out, typename P::State& s, double v) {
      { p.policy() } -> std::convertible_to<LmPolicy>;
      { p.evaluate(x, s) } -> std::convertible_to<double>;
      { p.at_minimum(x, std::as_const(s), v) } -> std::convertible_to<bool>;
      { p.step(x, std::as_const(s), v, out) } -> std::convertible_to<bool>;
      { p.negligible(x, std::as_const(out)) } -> std::convertible_to<bool>;
    };

template <class Point, class State>
struct LmResult {
  Point theta;      // the best point found
  State state;      // its evaluation
  double sse = 0;
  int evals = 0;
  bool converged = false;
};

// Levenberg–Marquardt from theta. Every point it evaluates is feasible (the problem's step
// projects), and it keeps only steps that do not raise the SSE, so the result is at least as good
// as the start.
template <LeastSquaresProblem Problem>
LmResult<typename Problem::Point, typename Problem::State> levenberg_marquardt(Problem& problem,
                                                                                typename Problem::Point theta) {
  using Point = typename Problem::Point;
  using State = typename Problem::State;
  const LmPolicy policy = problem.policy();
  LmResult<Point, State> out;
  State trial_state{};
  Point trial{};
  double sse = problem.evaluate(theta, out.state);
  out.evals = 1;
  double lambda = 1e-3;
  for (int it = 0; it < policy.max_iterations && out.evals < policy.max_evaluations; ++it) {
    if (problem.at_minimum(theta, std::as_const(out.state), sse)) {
      out.converged = true;
      break;
    }
    if (!problem.step(theta, std::as_const(out.state), lambda, trial)) break;
    const double sse_try = problem.evaluate(std::as_const(trial), trial_state);
    ++out.evals;
    if (policy.take_equal ? sse_try <= sse : sse_try < sse) {
      const double gain = sse - sse_try;
      const bool small = problem.negligible(std::as_const(theta), std::as_const(trial));
      std::swap(theta, trial);
      std::swap(out.state, trial_state);
      sse = sse_try;
      lambda = std::max(lambda / 10, 1e-12);
      if (small || gain <= policy.relative_gain * sse) {
        out.converged = true;
        break;
      }
    } else {
      lambda *= 10;
      if (lambda > 1e10) {
        out.converged = true;  // no step improves: at a (bounded) minimum
        break;
      }
    }
  }
  out.theta = std::move(theta);
  out.sse = sse;
  return out;
}

}  // namespace spindown
