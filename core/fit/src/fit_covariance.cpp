#include "fit_covariance.hpp"

#include <cmath>
#include <optional>

#include "spindown/parameter_covariance.hpp"

namespace spindown::friction {

Covariance covariance(const Family& f, const Theta& th, Evaluator& eval) {
  const int p = f.size();
  Eigen::Matrix3d jtj, omega;
  Eigen::Vector3d jtr;
  const double sse = eval(f, th, &jtj, &jtr, &omega);
  Covariance out;
  const auto long_run = [&](const Eigen::Matrix3d& inv, int j) {
    const auto v = inv.col(j).head(p);
    return v.dot(omega.topLeftCorner(p, p) * v) / (eval.lags() + 1.0);
  };
  const std::optional<Eigen::Matrix3d> cov = hac_covariance(jtj, sse, eval.size(), p, long_run);
  if (!cov) return out;
  out.cov = *cov;
  out.ok = out.cov.allFinite();
  return out;
}

double delta_se(const Family& f, const Eigen::Matrix3d& cov, double d_u0, double d_alpha, double d_beta) {
  Eigen::Vector3d g;
  int j = 0;
  g[j++] = d_u0;
  if (f.alpha_free) g[j++] = d_alpha;
  if (f.beta_free) g[j++] = d_beta;
  const int p = f.size();
  const double var = g.head(p).dot(cov.topLeftCorner(p, p) * g.head(p));
  return var > 0 ? std::sqrt(var) : 0.0;
}

}  // namespace spindown::friction
