// The shared parameter covariance (spindown/parameter_covariance.hpp): the classic s²·(JᵀJ)⁻¹,
// widened per parameter to the Newey–West variance only where that is larger, in fixed (padded)
// and dynamic matrices alike; and the Newey–West pieces themselves.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <vector>

#include "spindown/parameter_covariance.hpp"

using namespace spindown;

namespace {

// A straight line y = c0 + c1·t: JᵀJ of the columns (1, t).
Eigen::Matrix2d line_information(int n) {
  Eigen::Matrix2d m = Eigen::Matrix2d::Zero();
  for (int i = 0; i < n; ++i) {
    const double t = 0.1 * i;
    m(0, 0) += 1, m(0, 1) += t, m(1, 1) += t * t;
  }
  m(1, 0) = m(0, 1);
  return m;
}

}  // namespace

TEST(ParameterCovariance, NeweyWestLags) {
  EXPECT_EQ(newey_west_lags(100), 4);
  EXPECT_EQ(newey_west_lags(1000), 7);  // ⌈4·10^(2/9)⌉ = ⌈6.68⌉
  EXPECT_EQ(newey_west_lags(1), 2);
}

TEST(ParameterCovariance, NeweyWestSumIsBartlettWeighted) {
  const std::vector<double> z{1, 2, 3};
  // Σz² = 14; lag 1 (weight 1 − 1/3): 1·2 + 2·3 = 8; lag 2 (weight 1 − 2/3): 1·3 = 3.
  EXPECT_DOUBLE_EQ(newey_west_sum(z, 2), 14 + 2 * (2.0 / 3) * 8 + 2 * (1.0 / 3) * 3);
  EXPECT_DOUBLE_EQ(newey_west_sum(z, 0), 14);
  EXPECT_DOUBLE_EQ(newey_west_sum(z, 5), 14 + 2 * (5.0 / 6) * 8 + 2 * (4.0 / 6) * 3);  // lags past n stop at n − 1
}

TEST(ParameterCovariance, ClassicWhenTheResidualsAreWhite) {
  const int n = 50;
  const Eigen::Matrix2d jtj = line_information(n);
  const double sse = 4.8;
  int calls = 0;
  const auto white = [&](const Eigen::Matrix2d&, int) { return ++calls, 0.0; };
  const auto cov = hac_covariance(jtj, sse, n, 2, white);
  ASSERT_TRUE(cov.has_value());
  EXPECT_EQ(calls, 2);
  const Eigen::Matrix2d classic = sse / (n - 2) * jtj.inverse();
  EXPECT_TRUE(cov->isApprox(classic, 1e-12));
}

TEST(ParameterCovariance, WidenedWhereTheLongRunVarianceIsLarger) {
  const int n = 50;
  const Eigen::Matrix2d jtj = line_information(n);
  const double sse = 4.8, s2 = sse / (n - 2);
  const Eigen::Matrix2d classic = s2 * jtj.inverse();
  // Parameter 0's long-run variance is four times its classic one (after the n/(n − p)
  // correction), parameter 1's half of it: only parameter 0 widens, by 2 in standard error.
  const double dof = double(n) / (n - 2);
  const auto long_run = [&](const Eigen::Matrix2d&, int j) { return (j == 0 ? 4.0 : 0.5) * classic(j, j) / dof; };
  const auto cov = hac_covariance(jtj, sse, n, 2, long_run);
  ASSERT_TRUE(cov.has_value());
  EXPECT_NEAR((*cov)(0, 0), 4 * classic(0, 0), 1e-12 * classic(0, 0));
  EXPECT_NEAR((*cov)(1, 1), classic(1, 1), 1e-12 * classic(1, 1));
  // The correlation is the classic one.
  EXPECT_NEAR((*cov)(0, 1), 2 * classic(0, 1), 1e-12 * std::abs(classic(0, 1)));
  EXPECT_EQ((*cov)(0, 1), (*cov)(1, 0));
}

TEST(ParameterCovariance, PaddedFixedMatricesGiveTheSameNumbers) {
  const int n = 50;
  const Eigen::Matrix2d small = line_information(n);
  Eigen::Matrix3d padded = Eigen::Matrix3d::Identity();
  padded.topLeftCorner(2, 2) = small;
  const auto white2 = [](const Eigen::Matrix2d&, int) { return 0.0; };
  const auto white3 = [](const Eigen::Matrix3d&, int) { return 0.0; };
  const auto a = hac_covariance(small, 4.8, n, 2, white2);
  const auto b = hac_covariance(padded, 4.8, n, 2, white3);
  ASSERT_TRUE(a && b);
  EXPECT_TRUE(b->topLeftCorner(2, 2).isApprox(*a, 1e-12));
  EXPECT_EQ(b->row(2).norm(), 0.0);  // the padding is zero, not the identity's 1
  EXPECT_EQ(b->col(2).norm(), 0.0);

  const Eigen::MatrixXd dynamic = small;
  const auto c = hac_covariance(dynamic, 4.8, n, 2, [](const Eigen::MatrixXd&, int) { return 0.0; });
  ASSERT_TRUE(c.has_value());
  EXPECT_TRUE(c->isApprox(*a, 1e-12));
}

TEST(ParameterCovariance, NothingWhenTheInformationIsIndefiniteOrAnInverseTooLarge) {
  Eigen::Matrix2d indefinite;
  indefinite << 1, 2, 2, 1;
  const auto none = [](const Eigen::Matrix2d&, int) { return 0.0; };
  EXPECT_FALSE(hac_covariance(indefinite, 1.0, 10, 2, none).has_value());
  Eigen::Matrix2d weak;
  weak << 1, 0, 0, 1e-13;  // (JᵀJ)⁻¹ has 1e13 on its diagonal
  EXPECT_TRUE(hac_covariance(weak, 1.0, 10, 2, none).has_value());
  EXPECT_FALSE(hac_covariance(weak, 1.0, 10, 2, none, 1e12).has_value());
}
