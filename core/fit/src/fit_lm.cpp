#include "fit_lm.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "spindown/levenberg_marquardt.hpp"

namespace spindown::friction {
namespace {

bool at_minimum(const Family& f, const Theta& th, const Eigen::Matrix3d& jtj, const Eigen::Vector3d& jtr, double sse,
                double dof) {
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(jtj);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) return false;
  const Eigen::Matrix3d inv = ldlt.solve(Eigen::Matrix3d::Identity());
  const Eigen::Vector3d step = inv * jtr;
  if (!step.allFinite()) return false;
  const double s2 = sse / dof;
  double x[3];
  int j = 0;
  x[j++] = th.u0;
  if (f.alpha_free) x[j++] = th.alpha;
  if (f.beta_free) x[j++] = th.beta;
  for (j = 0; j < f.size(); ++j) {
    const bool blocked = j > 0 && x[j] <= 0 && step[j] < 0;
    if (!blocked && std::abs(step[j]) > negligible_step_in_se * std::sqrt(std::max(s2 * inv(j, j), 0.0)) &&
        std::abs(step[j]) > 1e-12 * std::abs(x[j]))
      return false;
  }
  return true;
}

// One family's least squares for the shared Levenberg–Marquardt (levenberg_marquardt.hpp), with
// the bounds α, β ≥ 0, u0 > 0 enforced by projection. The closed-form Jacobian makes each
// iteration one pass over the data; from the integral start it converges in a handful of
// iterations. Its policy: a step that leaves the SSE equal is taken, converged when the step is
// negligible beside the standard errors (at_minimum) or gains under 10⁻¹⁴ of the SSE, at most 100
// iterations and 200 evaluations; 3×3 systems for every family (a smaller one padded with the
// identity).
class FamilyLeastSquares {
 public:
  using Point = Theta;
  struct State {
    Eigen::Matrix3d jtj;
    Eigen::Vector3d jtr;
  };
  FamilyLeastSquares(const Family& f, Evaluator& eval)
      : f_(f), eval_(eval), dof_(static_cast<double>(std::max<std::size_t>(eval.size() - f.size(), 1))) {}

  LmPolicy policy() const {
    return {.max_iterations = 100, .max_evaluations = 200, .take_equal = true, .relative_gain = 1e-14};
  }
  double evaluate(const Theta& th, State& s) { return eval_(f_, th, &s.jtj, &s.jtr); }
  bool at_minimum(const Theta& th, const State& s, double sse) const {
    return friction::at_minimum(f_, th, s.jtj, s.jtr, sse, dof_);
  }
  bool step(const Theta& th, const State& s, double lambda, Theta& out) const {
    const int p = f_.size();
    Eigen::Matrix3d a = s.jtj;
    a.diagonal().head(p) *= 1.0 + lambda;
    const Eigen::LDLT<Eigen::Matrix3d> ldlt(a);
    if (ldlt.info() != Eigen::Success) return false;
    const Eigen::Vector3d step = ldlt.solve(s.jtr);
    if (!step.allFinite()) return false;
    double x[3];
    int j = 0;
    x[j++] = th.u0;
    if (f_.alpha_free) x[j++] = th.alpha;
    if (f_.beta_free) x[j++] = th.beta;
    for (j = 0; j < p; ++j) x[j] = std::max(x[j] + step[j], j == 0 ? 1e-12 : 0.0);
    out = unpack(f_, x);
    return true;
  }
  bool negligible(const Theta&, const Theta&) const { return false; }

 private:
  Family f_;
  Evaluator& eval_;
  double dof_;
};

}  // namespace

LmOutcome levenberg_marquardt(const Family& f, const Theta& th, Evaluator& eval) {
  FamilyLeastSquares problem(f, eval);
  const auto lm = spindown::levenberg_marquardt(problem, th);
  return {lm.theta, lm.evals, lm.converged};
}

}  // namespace spindown::friction
