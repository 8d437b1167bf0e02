#pragma once
// One parameter covariance for every least-squares fit (fit and explain): the classic s²·(JᵀJ)⁻¹
// from the Jacobian at the optimum, each parameter's variance widened to its Newey–West (HAC)
// long-run variance when that is larger. The classic estimate assumes white residuals; commutator
// ripple and quantization make them correlated. Only the sandwich's diagonal is needed:
// var_j = v_jᵀ·Ω·v_j with v_j = column j of (JᵀJ)⁻¹, the long-run variance of the scalar series
// z_i = (g_i·v_j)·r_i, and the caller computes it the cheapest way it has (moving sums of the
// scores it kept, or the series itself); the correlation structure of the classic estimate is
// kept, scaled per parameter.
//
// A template over the matrix type (fixed 3×3 padded with the identity for the friction models,
// dynamic for the effects), so each caller keeps its own decomposition's arithmetic bit for bit.
// Needs Eigen: spindown_fit links it PUBLIC for this header.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <optional>
#include <span>

namespace spindown {

// Newey–West's bandwidth for n samples: L = ⌈4·(n/100)^(2/9)⌉.
inline int newey_west_lags(std::size_t n) {
  return static_cast<int>(std::ceil(4.0 * std::pow(static_cast<double>(n) / 100.0, 2.0 / 9.0)));
}

// Σ z_i² + 2·Σ_(l=1…L) (1 − l/(L+1))·Σ_i z_i·z_(i+l): the Bartlett-weighted long-run variance of
// the series z times its length.
inline double newey_west_sum(std::span<const double> z, int lags) {
  const std::size_t n = z.size();
  double hac = 0;
  for (std::size_t i = 0; i < n; ++i) hac += z[i] * z[i];
  for (int l = 1; l <= lags && static_cast<std::size_t>(l) < n; ++l) {
    const double wgt = 1.0 - l / (lags + 1.0);
    double g = 0;
    for (std::size_t i = 0; i + static_cast<std::size_t>(l) < n; ++i) g += z[i] * z[i + static_cast<std::size_t>(l)];
    hac += 2.0 * wgt * g;
  }
  return hac;
}

// The covariance of the first p parameters from JᵀJ (rows and columns from p on are padding, set
// to 0 in the result) and the SSE over n samples: s² = SSE/(n − p), classic = s²·(JᵀJ)⁻¹, and
// parameter j's variance widened to n/(n − p)·long_run(inv, j) where that is larger, long_run the
// Newey–West sum of parameter j's series (newey_west_sum) given inv = (JᵀJ)⁻¹. nullopt when JᵀJ
// is not positive definite, its inverse not finite, or an entry of the inverse's diagonal larger
// than max_inverse_diagonal (an unidentifiable direction); the result may still hold non-finite
// numbers (the caller decides what that means).
template <class Matrix, class LongRun>
std::optional<Matrix> hac_covariance(const Matrix& jtj, double sse, std::size_t n, int p, LongRun&& long_run,
                                     double max_inverse_diagonal = std::numeric_limits<double>::infinity()) {
  const Eigen::LDLT<Matrix> ldlt(jtj);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) return std::nullopt;
  const Matrix inv = ldlt.solve(Matrix::Identity(jtj.rows(), jtj.cols()));
  if (!inv.allFinite() || inv.diagonal().maxCoeff() > max_inverse_diagonal) return std::nullopt;
  const auto count = static_cast<Eigen::Index>(n);
  const double s2 = sse / static_cast<double>(std::max<Eigen::Index>(1, count - p));
  const Matrix classic = s2 * inv;
  const double dof = static_cast<double>(count) / static_cast<double>(std::max<Eigen::Index>(1, count - p));
  Eigen::Matrix<double, Matrix::RowsAtCompileTime, 1> widen =
      Eigen::Matrix<double, Matrix::RowsAtCompileTime, 1>::Ones(jtj.rows());
  for (int j = 0; j < p; ++j) {
    const double lr = long_run(inv, j);
    widen[j] = std::sqrt(std::max(1.0, dof * lr / classic(j, j)));
  }
  Matrix cov = widen.asDiagonal() * classic * widen.asDiagonal();
  for (Eigen::Index j = p; j < cov.rows(); ++j) cov.row(j).setZero(), cov.col(j).setZero();
  return cov;
}

}  // namespace spindown
