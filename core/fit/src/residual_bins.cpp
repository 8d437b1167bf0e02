#include "spindown/residual_bins.hpp"

#include <algorithm>
#include <cmath>

namespace spindown {

ResidualBins bin_residuals(std::span<const double> r, std::size_t m, double white_sigma) {
  ResidualBins b;
  b.m = std::max<std::size_t>(m, 1);
  b.white = white_sigma;
  const std::size_t n = r.size();
  for (std::size_t i = 0; i < n; i += b.m) {
    if (i > 0 && n - i < b.m / 2) break;  // a short last bin joins the one before it
    b.first.push_back(i);
  }
  for (std::size_t k = 0; k < b.first.size(); ++k) {
    const std::size_t i0 = b.first[k];
    const std::size_t i1 = k + 1 < b.first.size() ? b.first[k + 1] : n;
    double s = 0;
    for (std::size_t i = i0; i < i1; ++i) s += r[i];
    b.mean.push_back(s / static_cast<double>(i1 - i0));
  }
  std::vector<double> jumps;
  for (std::size_t k = 1; k < b.mean.size(); ++k) jumps.push_back(std::abs(b.mean[k] - b.mean[k - 1]));
  if (jumps.size() >= 4) {
    const auto mid = jumps.begin() + static_cast<std::ptrdiff_t>(jumps.size() / 2);
    std::nth_element(jumps.begin(), mid, jumps.end());
    b.from_jumps = 1.4826 * *mid / std::sqrt(2.0);
  }
  b.bin_se = std::max({white_sigma / std::sqrt(static_cast<double>(b.m)), b.from_jumps, 1e-15});
  return b;
}

}  // namespace spindown
