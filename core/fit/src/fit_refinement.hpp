#pragma once
// The friction models' fallback when Levenberg–Marquardt does not converge: bounded L-BFGS
// (spindown/bounded_refinement.hpp).
#include <span>
#include <string>

#include "fit_evaluator.hpp"
#include "fit_family.hpp"

namespace spindown::friction {

// Bounded quasi-Newton refinement from th, on the parameters scaled by their size and the SSE by
// its value at th. Returns "" on success or why it failed; th is updated to the best point found.
std::string refine_with_nlopt(const Family& fam, std::span<const double> tau, Evaluator& eval, Theta& th,
                              int& evals);

}  // namespace spindown::friction
