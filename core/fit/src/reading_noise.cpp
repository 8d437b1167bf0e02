#include "spindown/reading_noise.hpp"

#include "vector_clones.hpp"

#include <algorithm>
#include <cmath>

namespace spindown {
namespace {

// Half-width of the local mean: wide enough that a sample's own error hardly moves ū (1/17
// of it), narrow next to the coast's curvature at 50 Hz.
constexpr std::size_t half_window = 8;

// ū_i: mean of y over [i − h, i + h] clipped to the run, as a sliding window sum. Each step
// adds y_(i+h) while there is one, then takes out y_(i−h−1) once there is one; the loops below
// are those steps with the two tests decided per range of i (same sums, same order). Into mean
// (n values, written not read: the caller's buffer need not be zeroed first).
void local_means(std::span<const double> y, double* mean) {
  const std::size_t n = y.size(), h = half_window;  // n ≥ 2h + 2 here
  double sum = 0;
  for (std::size_t j = 0; j < h; ++j) sum += y[j];
  std::size_t i = 0;
  for (; i <= h; ++i) {  // the window grows: [0, i + h]
    sum += y[i + h];
    mean[i] = sum / static_cast<double>(i + h + 1);
  }
  constexpr double full = 2 * half_window + 1;
#pragma GCC unroll 4  // a sequential sum of a few instructions per sample: fewer loop tests
  for (; i + h < n; ++i) {  // full width
    sum += y[i + h];
    sum -= y[i - h - 1];
    mean[i] = sum / full;
  }
  for (; i < n; ++i) {  // the window shrinks: [i − h, n)
    sum -= y[i - h - 1];
    mean[i] = sum / static_cast<double>(n - i + h);
  }
}

// Least squares of v_i = d_i²/6 on x_i = ū_i², d the second difference.
SPINDOWN_VECTOR_CLONES ReadingNoise estimate(std::span<const double> y, std::span<const double> mean,
                                             double max_ratio) {
  ReadingNoise out;
  const std::size_t n = y.size();
  enum { x_sum, v_sum, xx_sum, xv_sum, quantities };
  Lanes<quantities> acc;
  double lane_max[Lanes<quantities>::count] = {};  // the largest x, per lane (a max is exact in any order)
  for_each_in_lanes(1, n - 1, [&](std::size_t i, std::size_t l) SPINDOWN_LANE_BODY {  // n ≥ 32 here
    const double d = y[i + 1] - 2 * y[i] + y[i - 1];
    const double v = d * d / 6, x = mean[i] * mean[i];
    auto& a = acc.sum;
    a[x_sum][l] += x, a[v_sum][l] += v, a[xx_sum][l] += x * x, a[xv_sum][l] += x * v;
    lane_max[l] = std::max(lane_max[l], x);
  });
  const double sx = acc.total(x_sum), sv = acc.total(v_sum), sxx = acc.total(xx_sum), sxv = acc.total(xv_sum);
  // Every sample gets a weight: the two ends, outside the sums' range, count too.
  double x_max = std::max({lane_max[0], lane_max[1], lane_max[2], lane_max[3], mean[0] * mean[0],
                           mean[n - 1] * mean[n - 1]});
  const double m = static_cast<double>(n - 2);
  const double det = m * sxx - sx * sx;
  double a = sv / m, b = 0;  // constant variance unless the reading explains it
  if (det > 1e-12 * m * sxx) {
    b = (m * sxv - sx * sv) / det;
    a = (sv - b * sx) / m;
    if (b < 0) b = 0, a = sv / m;
  }
  if (!(a + b * x_max > 0) || !std::isfinite(a) || !std::isfinite(b)) return out;
  // (a + b·x_max)/a ≤ max_ratio, also when the regression's a came out ≤ 0.
  out.a = std::max(a, b * x_max / std::max(max_ratio - 1.0, 1e-9));
  if (!(out.a > 0)) return out;
  out.b = b;
  out.known = true;
  return out;
}

// The local means ū_i become the weights 1/σ²(ū_i) in place, scaled to average 1.
SPINDOWN_VECTOR_CLONES void means_to_weights(std::span<double> w, const ReadingNoise& noise_in) {
  const ReadingNoise noise = noise_in;  // a copy: the stores to w cannot change it, so no reloads
  Lanes<1> total;
  double* x = w.data();
  const std::size_t n = w.size();
  for_each_in_lanes(0, n, [&](std::size_t i, std::size_t l) SPINDOWN_LANE_BODY { total.sum[0][l] += x[i] = 1.0 / noise.variance(x[i]); });
  const double scale = static_cast<double>(n) / total.total(0);
#pragma omp simd
  for (std::size_t i = 0; i < n; ++i) x[i] *= scale;
}

}  // namespace

ReadingNoise weigh_by_noise_into(std::span<const double> y, std::span<double> weight, double max_ratio) {
  ReadingNoise noise;
  if (y.size() >= 32) {
    local_means(y, weight.data());
    noise = estimate(y, weight, max_ratio);
    if (noise.known) {
      means_to_weights(weight, noise);  // one buffer, no second allocation
      return noise;
    }
  }
  std::fill(weight.begin(), weight.end(), 1.0);
  return noise;
}

NoiseWeights weigh_by_noise(std::span<const double> y, double max_ratio) {
  NoiseWeights out;
  out.weight.resize(y.size());
  out.noise = weigh_by_noise_into(y, out.weight, max_ratio);
  return out;
}

double reading_noise_sigma(std::span<const double> y) {
  if (y.size() < 3) return 0;
  double s = 0;
  for (std::size_t i = 1; i + 1 < y.size(); ++i) {
    const double d2 = y[i + 1] - 2 * y[i] + y[i - 1];
    s += d2 * d2;
  }
  return std::sqrt(s / (6.0 * static_cast<double>(y.size() - 2)));
}

}  // namespace spindown
