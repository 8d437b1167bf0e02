#include "spindown/two_segment_split.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace spindown {

TwoSegmentSplit::TwoSegmentSplit(const SampleStore& s, std::size_t a_, std::size_t b, std::vector<double>& scratch)
    : d(s), a(a_), n(b - a_ + 1), tr(s.t(b)) {
  if (scratch.size() < 6 * (n + 1)) scratch.resize(6 * (n + 1));
  pv = scratch.data();
  pvv = pv + (n + 1);
  ss = pvv + (n + 1);
  stt_ = ss + (n + 1);
  sv_ = stt_ + (n + 1);
  stv_ = sv_ + (n + 1);
  pv[0] = pvv[0] = 0.0;
  ss[n] = stt_[n] = sv_[n] = stv_[n] = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    const double x = d.v(a + k);
    pv[k + 1] = pv[k] + x;
    pvv[k + 1] = pvv[k] + x * x;
  }
  for (std::size_t k = n; k-- > 0;) {
    const double tt = d.t(a + k) - tr, x = d.v(a + k);
    ss[k] = ss[k + 1] + tt;
    stt_[k] = stt_[k + 1] + tt * tt;
    sv_[k] = sv_[k + 1] + x;
    stv_[k] = stv_[k + 1] + tt * x;
  }
  svv_all = pvv[n];
}

TwoSegmentSplit::Line TwoSegmentSplit::post_line(std::size_t k) const {
  const double np = double(n - k);
  const double sxx = stt_[k] - ss[k] * ss[k] / np;
  const double sxy = stv_[k] - ss[k] * sv_[k] / np;
  const double syy = (svv_all - pvv[k]) - sv_[k] * sv_[k] / np;
  Line l;
  l.slope = sxx > 0 ? sxy / sxx : 0.0;
  l.v0 = sv_[k] / np + l.slope * ((d.t(a + k) - tr) - ss[k] / np);
  l.sd = np > 2 ? std::sqrt(std::max(syy - l.slope * sxy, 0.0) / (np - 2)) : 0.0;
  return l;
}

std::size_t TwoSegmentSplit::best_split(std::size_t kb) const {
  double best = std::numeric_limits<double>::infinity();
  std::size_t best_k = kb;
  for (std::size_t k = kb; k + 3 <= n; ++k) {
    const double m = double(k - kb);
    const double sp_ = pv[k] - pv[kb];
    const double sse_pre = k > kb ? (pvv[k] - pvv[kb]) - sp_ * sp_ / m : 0.0;
    const double np = double(n - k);
    const double sxx = stt_[k] - ss[k] * ss[k] / np;
    const double sxy = stv_[k] - ss[k] * sv_[k] / np;
    const double syy = (svv_all - pvv[k]) - sv_[k] * sv_[k] / np;
    const double sse_post = sxx > 0 ? syy - sxy * sxy / sxx : syy;
    const double sse = std::max(sse_pre, 0.0) + std::max(sse_post, 0.0);
    if (sse < best) {
      best = sse;
      best_k = k;
    }
  }
  return best_k;
}

std::size_t TwoSegmentSplit::later_step(std::size_t& kb, std::size_t k) const {
  for (int again = 0; again < 3; ++again) {
    const std::size_t k2 = best_split(k);
    if (k2 < k + 3) break;
    const double m = double(k2 - k);
    const double mean = (pv[k2] - pv[k]) / m;
    const double sd = std::sqrt(std::max((pvv[k2] - pvv[k]) / m - mean * mean, 0.0));
    const Line l = post_line(k2);
    const double scale = std::abs(l.v0);
    if (std::abs(l.v0 - mean) <= std::max(5.0 * l.sd, 0.03 * scale) || sd > std::max(3.0 * l.sd, 0.02 * scale))
      break;
    kb = k;
    k = k2;
  }
  return k;
}

}  // namespace spindown
