#pragma once
// One bounded refinement for every least-squares fit (fit and explain): NLopt's L-BFGS (LD_LBFGS)
// under box bounds, the fallback when Levenberg–Marquardt does not converge. The caller scales its
// parameters (x_j = θ_j/scale_j) and its objective; this owns NLopt: the optimizer, its
// tolerances, the C callback that no exception crosses (design §7: the objective's exception is
// kept and NLopt is stopped), and what each way of ending means. NLopt stays private to the
// library: nothing of it in this header.
#include <functional>
#include <span>
#include <string>
#include <vector>

namespace spindown {

struct RefinementOptions {
  std::vector<double> lower, upper;  // bounds on x, one per parameter
  double ftol_rel = 1e-12;           // relative change of the objective
  double xtol_rel = 1e-10;           // relative change of x
  int max_evaluations = 400;
};

// The objective at x; when grad is not empty (NLopt wants the gradient) it receives ∂f/∂x. It may
// throw: the refinement then stops and says why.
using RefinementObjective = std::function<double(std::span<const double> x, std::span<double> grad)>;

// Minimises the objective from x (inside the bounds) with bounded L-BFGS; x becomes the best point
// NLopt found, and evaluations grows by the objective's calls. Returns "" on success (stopping on
// round-off counts: at the optimum to machine precision), or why not: "no convergence within N
// evaluations", "the objective failed[: what]", "NLopt: what".
std::string refine_bounded(std::vector<double>& x, const RefinementOptions& options,
                           const RefinementObjective& objective, int& evaluations);

}  // namespace spindown
