#pragma once
// The friction models' start values: the integral form of the ODE, solved linearly.
#include <Eigen/Dense>
#include <cstddef>
#include <span>

#include "fit_family.hpp"

namespace spindown::friction {

// Starting point from the integral form of the ODE, linear in the unknowns:
//   r(τ) = u0 − α·∫₀^τ r dt − β·τ     (while moving)
// one least-squares solve over the samples before the stop: no derivatives of noisy data,
// no initial guess needed. The normal equations of the full form (columns 1, −∫r, −τ) are
// built once per run; each family solves its own sub-block.
struct IntegralForm {
  Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
  Eigen::Vector3d atb = Eigen::Vector3d::Zero();
};

// The full form's normal equations over the first `moving` samples.
IntegralForm integral_form(std::span<const double> tau, std::span<const double> y, std::size_t moving);

// The start for family f from the form: its own sub-block solved; all zero when that fails.
Theta integral_start(const Family& f, const IntegralForm& form);

}  // namespace spindown::friction
