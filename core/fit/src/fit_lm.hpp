#pragma once
// The friction models' least squares for the shared Levenberg–Marquardt
// (spindown/levenberg_marquardt.hpp), and the convergence rule the direct solutions share.
#include "fit_evaluator.hpp"
#include "fit_family.hpp"

namespace spindown::friction {

// Converged once the Gauss–Newton step from the current point is a tiny fraction of each
// parameter's own statistical uncertainty s²·(JᵀJ)⁻¹ (both from the same JᵀJ, so the test
// costs no evaluation): iterating further only moves digits nobody can use. A step that a
// bound blocks (α or β held at 0) counts as zero.
inline constexpr double negligible_step_in_se = 1e-3;

struct LmOutcome {
  Theta theta;
  int evals = 0;
  bool converged = false;
};

// Levenberg–Marquardt for family f from th on the evaluator's run.
LmOutcome levenberg_marquardt(const Family& f, const Theta& th, Evaluator& eval);

}  // namespace spindown::friction
