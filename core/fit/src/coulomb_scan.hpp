#pragma once
// The Coulomb model's direct solution: a scan over the stop.
#include <cstddef>
#include <optional>

#include "fit_evaluator.hpp"
#include "fit_family.hpp"

namespace spindown::friction {

// The Coulomb model in closed form. While moving it is the straight line u0 − β·τ, and the
// samples that move are those before its stop ts = u0/β; so for each count m of moving samples
// the weighted SSE is a quadratic in (u0, β) whose minimum is either the plain line fit over the
// first m samples (when its own stop falls between τ[m−1] and τ[m]) or on that range's edge
// ts = τ[m], the line through (τ[m], 0). Running sums give every candidate's SSE in O(1), so
// one pass over m finds the global minimum of the clamped SSE — where LM from a start could
// stop at a nearby kink. nullopt when the clock is not sorted or no falling line fits: LM then.
//
// A candidate's gain (Σw·y² minus its SSE) is at most P(m) = Σ_(i<m) w·y², as its SSE over the
// moving samples is not negative, and P grows with m. So once the candidates at the detector's
// stop (`hint` moving samples) give a gain G, no count with P(m) < G can win: the scan gathers
// those samples' sums in one vectorised pass and weighs candidates only after them.
std::optional<Theta> coulomb_by_line_scan(const Evaluator& eval, std::size_t hint, int& passes);

}  // namespace spindown::friction
