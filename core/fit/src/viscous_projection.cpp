#include "viscous_projection.hpp"

#include <algorithm>
#include <cmath>

#include "fit_lm.hpp"

namespace spindown::friction {

std::optional<Theta> viscous_by_projection(Evaluator& eval, double alpha, int& passes) {
  const double sum_wyy = eval.weighted_sum_sq();
  const double dof = static_cast<double>(std::max<std::size_t>(eval.size(), 3) - 2);
  for (int it = 0; it < 30; ++it) {
    const Evaluator::DecaySums s = eval.decay_sums(alpha);
    ++passes;
    // F = Syy − N²/D with N = Σw·y·e, D = Σw·e²; dN/dα = −Σw·τ·y·e, dD/dα = −2·Σw·τ·e², …
    const double N = s.ye, D = s.ee, N1 = -s.t_ye, N2 = s.tt_ye, D1 = -2 * s.t_ee, D2 = 4 * s.tt_ee;
    if (!(D > 0) || !(N > 0)) return std::nullopt;
    const double u = 2 * N * N1 * D - N * N * D1;
    const double grad = -u / (D * D);
    const double hess = -(2 * N1 * N1 * D + 2 * N * N2 * D - N * N * D2) / (D * D) + 2 * D1 * u / (D * D * D);
    if (!(hess > 0) || !std::isfinite(grad)) return std::nullopt;
    const double step = -grad / hess;
    const double var_alpha = 2 * std::max(sum_wyy - N * N / D, 0.0) / dof / hess;
    if (std::abs(step) <= negligible_step_in_se * std::sqrt(var_alpha) || std::abs(step) <= 1e-12 * alpha)
      return Theta{N / D, alpha, 0.0};
    if (alpha + step <= 0) return std::nullopt;  // at the bound α = 0: LM's projection handles it
    alpha += step;
  }
  return std::nullopt;
}

}  // namespace spindown::friction
