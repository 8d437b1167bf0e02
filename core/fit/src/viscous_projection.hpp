#pragma once
// The viscous model's direct solution, by variable projection.
#include <optional>

#include "fit_evaluator.hpp"
#include "fit_family.hpp"

namespace spindown::friction {

// The viscous model by variable projection: Newton's method on the one-dimensional projected
// SSE F(α) = Σw·y² − (Σw·y·e)²/Σw·e², u0 following in closed form. The same minimum as LM over
// (u0, α), reached with one cheap pass per iteration (no Jacobian matrix). Stops by the same
// rule as LM: the step is a tiny fraction of α's standard error, whose variance is s²·2/F''.
// nullopt when Newton is not safe (F'' ≤ 0, α driven to its bound, no convergence): LM then.
std::optional<Theta> viscous_by_projection(Evaluator& eval, double alpha, int& passes);

}  // namespace spindown::friction
