#include "fit_refinement.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <vector>

#include "spindown/bounded_refinement.hpp"

namespace spindown::friction {

std::string refine_with_nlopt(const Family& fam, std::span<const double> tau, Evaluator& eval, Theta& th,
                              int& evals) {
  const int p = fam.size();
  const double span_s = std::max(tau.back(), 1e-3);
  Eigen::Vector3d scale;  // parameters are optimised as x_j = θ_j / scale_j (conditioning)
  std::vector<double> x(p);
  {
    int j = 0;
    scale[j] = std::max(th.u0, 1e-9), x[j] = th.u0 / scale[j], ++j;
    if (fam.alpha_free) scale[j] = std::max(th.alpha, 1e-6 / span_s), x[j] = th.alpha / scale[j], ++j;
    if (fam.beta_free) scale[j] = std::max(th.beta, 1e-6 * th.u0 / span_s), x[j] = th.beta / scale[j], ++j;
  }
  const double sse0 = std::max(eval(fam, th), 1e-300);  // objective normalisation
  RefinementOptions options{.lower = std::vector<double>(p, 0.0),
                            .upper = std::vector<double>(p, 1e6),
                            .ftol_rel = 1e-13,
                            .xtol_rel = 1e-10,
                            .max_evaluations = 400};
  options.lower[0] = 1e-9;
  const auto objective = [&](std::span<const double> xs, std::span<double> grad) {
    double xt[3];
    for (int j = 0; j < p; ++j) xt[j] = xs[j] * scale[j];
    const Theta t = unpack(fam, xt);
    Eigen::Matrix3d jtj;
    Eigen::Vector3d jtr;
    const double sse = grad.empty() ? eval(fam, t) : eval(fam, t, &jtj, &jtr);
    // d(Σr²)/dθ = −2·Jᵀr
    for (std::size_t j = 0; j < grad.size(); ++j) grad[j] = -2 * jtr[j] * scale[j] / sse0;
    return sse / sse0;
  };
  const std::string why = refine_bounded(x, options, objective, evals);
  for (int j = 0; j < p; ++j) x[j] *= scale[j];
  th = unpack(fam, x.data());
  return why;
}

}  // namespace spindown::friction
