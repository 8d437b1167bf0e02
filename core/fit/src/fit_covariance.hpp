#pragma once
// The friction models' parameter covariance and the standard errors derived from it.
#include <Eigen/Dense>

#include "fit_evaluator.hpp"
#include "fit_family.hpp"

namespace spindown::friction {

struct Covariance {
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  bool ok = false;
};

// Parameter covariance from the Jacobian at the optimum (parameter_covariance.hpp): classic,
// widened per parameter to the Newey–West variance, whose Ω comes from the evaluation's moving
// sums of the scores (Evaluator::operator()).
Covariance covariance(const Family& f, const Theta& th, Evaluator& eval);

// Standard error of g(θ) by the delta method, grad in (u0, α, β) order restricted to free params.
double delta_se(const Family& f, const Eigen::Matrix3d& cov, double d_u0, double d_alpha, double d_beta);

}  // namespace spindown::friction
