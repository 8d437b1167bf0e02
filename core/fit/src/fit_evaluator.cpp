#include "fit_evaluator.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>

#include "spindown/parameter_covariance.hpp"

namespace spindown::friction {
namespace {

// The model's value and partial derivatives at one sample, in the family's parameter order
// (u0, then α and β where free; g2 is 0 for two parameters). Two forms of the same closed form,
// chosen once per pass: DecayingRow and SeriesRow.
struct ModelRow {
  double model, g0, g1, g2;
};

// DecayingRow, where α·τ reaches 10⁻³: with c = β/α the model is (u0 + c)·e − c, no division
// per sample. Its α-derivative, −(u0 + c)·τ·e + (c/α)·(1 − e), loses only ~ε·βτ/α to
// cancellation where ατ is small.
struct DecayingRow {
  double a, c, c_over_alpha, inv_alpha;
  template <int P>
  ModelRow operator()(double t, double e) const {
    return {a * e - c, e, c_over_alpha * (1.0 - e) - a * t * e, P == 3 ? (e - 1.0) * inv_alpha : 0.0};
  }
};

// SeriesRow, where α·τ stays below 10⁻³ (α free): φ(x) = (1 − e^(−x))/x by its series, exact to
// rounding there (α = 0 gives x = 0, φ = 1 and φ' = −1/2 exactly). The two-parameter family is
// the viscous one: its second column is α's.
struct SeriesRow {
  Theta th;
  template <int P>
  ModelRow operator()(double t, double e) const {
    const double x = th.alpha * t;
    const double p = 1.0 - x / 2 + x * x / 6 - x * x * x / 24, dp = -0.5 + x / 3 - x * x / 8;
    const double d_alpha = -th.u0 * t * e - th.beta * t * t * dp, d_beta = -t * p;
    const double model = th.u0 * e - th.beta * t * p;
    if constexpr (P == 2) return {model, e, d_alpha, 0.0};
    return {model, e, d_alpha, d_beta};
  }
};

// LineRow, the Coulomb family (α held at 0): the straight line u0 − β·τ. Exactly what SeriesRow
// gives at x = 0 (φ = 1, e = 1), without the series.
struct LineRow {
  double u0, beta;
  template <int P>
  ModelRow operator()(double t, double) const {
    static_assert(P == 2);
    return {u0 - beta * t, 1.0, -t, 0.0};
  }
};

}  // namespace

Evaluator::Evaluator(std::span<const double> tau, std::span<const double> y, std::span<const double> weight)
    : tau_(tau),
      y_(y),
      w_(weight),
      wy_(std::make_unique_for_overwrite<double[]>(tau.size())),
      tail_sq_(std::make_unique_for_overwrite<double[]>(tau.size() + 1)),
      e_(std::make_unique_for_overwrite<double[]>(tau.size())),
      scores_(std::make_unique_for_overwrite<double[]>(3 * tau.size())),
      lags_(newey_west_lags(tau.size())),
      sorted_(std::is_sorted(tau.begin(), tau.end())) {
  const std::size_t n = tau.size();
  double sum_y = 0, tail = 0;
  // The suffix sum runs in a register and the inputs are restrict: read back from the array it
  // had just stored (the store to wy_ might have changed it), each sample waited on a store.
  const double *__restrict w_in = weight.data(), *__restrict y_in = y.data();
  double *__restrict tail_out = tail_sq_.get(), *__restrict wy_out = wy_.get();
  tail_out[n] = 0;
#pragma GCC unroll 4  // a short sequential body: the loop's own count and test were much of it
  for (std::size_t i = n; i-- > 0;) {
    const double yy = y_in[i] * y_in[i];
    tail_out[i] = tail = tail + w_in[i] * yy;
    wy_out[i] = w_in[i] * y_in[i];
    sum_y += y_in[i];
  }
  if (n > 0) {
    const double mean = sum_y / static_cast<double>(n);
    double sst = 0;
#pragma omp simd reduction(+ : sst)
    for (std::size_t i = 0; i < n; ++i) sst += (y[i] - mean) * (y[i] - mean);
    total_sum_sq_ = sst;
  }
  index_time_steps();
}

SPINDOWN_VECTOR_CLONES Evaluator::DecaySums Evaluator::decay_sums(double alpha) {
  const std::size_t n = tau_.size();
  decay(alpha, n);
  enum { ee, ye, t_ee, t_ye, tt_ee, tt_ye, quantities };
  Lanes<quantities> acc;
  const double *tau = tau_.data(), *ex = e_.get(), *w = w_.data(), *wy = wy_.get();
  for_each_in_lanes(0, n, [&](std::size_t i, std::size_t l) SPINDOWN_LANE_BODY {
    const double e = ex[i], t = tau[i], wee = w[i] * e * e, wye = wy[i] * e;
    acc.sum[ee][l] += wee, acc.sum[t_ee][l] += t * wee, acc.sum[tt_ee][l] += t * t * wee;
    acc.sum[ye][l] += wye, acc.sum[t_ye][l] += t * wye, acc.sum[tt_ye][l] += t * t * wye;
  });
  return {acc.total(ee), acc.total(ye), acc.total(t_ee), acc.total(t_ye), acc.total(tt_ee), acc.total(tt_ye)};
}

double Evaluator::plain_sse(const Family& f, const Theta& th) {
  (*this)(f, th);
  // The stopped tail's Σy², summed from the end as the suffix sums are: asked for once per model,
  // so not kept for every m.
  double tail = 0;
  for (std::size_t i = tau_.size(); i-- > m_;) tail += y_[i] * y_[i];
  return last_plain_moving_ + tail;
}

void Evaluator::evaluate(const Family& f, const Theta& th) {
  const std::size_t n = tau_.size();
  std::size_t m = n;
  const double ts = stop_time(th);
  if (sorted_ && std::isfinite(ts)) m = static_cast<std::size_t>(std::upper_bound(tau_.begin(), tau_.end(), ts) - tau_.begin());
  m_ = m;
  if (!f.alpha_free) {
    accumulate<2>(LineRow{th.u0, th.beta});
  } else {
    const double tau_max = m == 0 ? 0.0 : sorted_ ? tau_[m - 1] : *std::max_element(tau_.begin(), tau_.begin() + m);
    if (th.alpha != 0) {
      decay(th.alpha, m);
    } else {
      std::fill(e_.get(), e_.get() + m, 1.0);
      decay_m_ = 0;
    }
    if (th.alpha * tau_max >= 1e-3) {
      const double c = th.beta / th.alpha;
      const DecayingRow row{th.u0 + c, c, c / th.alpha, 1.0 / th.alpha};
      f.beta_free ? accumulate<3>(row) : accumulate<2>(row);
    } else {
      const SeriesRow row{th};
      f.beta_free ? accumulate<3>(row) : accumulate<2>(row);
    }
  }
  last_f_ = f, last_th_ = th, last_valid_ = true, last_has_omega_ = false;
}

template <int P, class Row>
SPINDOWN_VECTOR_CLONES void Evaluator::accumulate(const Row& row) {
  static_assert(P == 2 || P == 3);
  enum { sse, plain, r0, r1, r2, j00, j10, j11, j20, j21, j22, quantities };
  Lanes<quantities> acc;
  // The scores are the only stores: restrict and a local copy of the row tell the compiler they
  // change no input, which it would otherwise reload every iteration.
  const Row local_row = row;
  const double *__restrict tau = tau_.data(), *__restrict e = e_.get(), *__restrict w = w_.data(),
                           *__restrict y = y_.data();
  double *__restrict score0 = score(0), *__restrict score1 = score(1), *__restrict score2 = score(2);
  const std::size_t m = m_;
  for_each_in_lanes(0, m, [&](std::size_t i, std::size_t l) SPINDOWN_LANE_BODY {
    const auto [model, g0, g1, g2] = local_row.template operator()<P>(tau[i], e[i]);
    const double moving = model > 0 ? 1.0 : 0.0;
    const double d = y[i] - std::max(model, 0.0), wd = w[i] * d;
    const double gw = moving * w[i], gwd = moving * wd;  // the gradient's weights
    auto& a = acc.sum;
    a[sse][l] += wd * d, a[plain][l] += d * d;
    a[r0][l] += g0 * gwd, a[r1][l] += g1 * gwd;
    a[j00][l] += gw * g0 * g0, a[j10][l] += gw * g1 * g0, a[j11][l] += gw * g1 * g1;
    if constexpr (P == 3)
      a[r2][l] += g2 * gwd, a[j20][l] += gw * g2 * g0, a[j21][l] += gw * g2 * g1, a[j22][l] += gw * g2 * g2;
    score0[i] = g0 * gwd, score1[i] = g1 * gwd;
    if constexpr (P == 3) score2[i] = g2 * gwd;
  });
  last_sse_ = acc.total(sse) + tail_sq_[m];
  last_plain_moving_ = acc.total(plain);
  last_jtj_ << acc.total(j00), acc.total(j10), acc.total(j20), acc.total(j10), acc.total(j11), acc.total(j21),
      acc.total(j20), acc.total(j21), acc.total(j22);
  last_jtr_ << acc.total(r0), acc.total(r1), acc.total(r2);
  if constexpr (P == 2) last_jtj_(2, 2) = 1;
}

template <int P>
void Evaluator::moving_sums() {
  const std::size_t m = m_, span = static_cast<std::size_t>(lags_) + 1;
  double omega[6] = {};  // the lower triangle, row by row: 00, 10, 11, 20, 21, 22
  if (m > 0) {
    double *c0 = score(0), *c1 = score(1), *c2 = score(2);
    double total0 = 0, total1 = 0, total2 = 0;  // in registers: the columns are one array
#pragma GCC unroll 4  // sequential, a few instructions per sample: unrolled, the loop's own are fewer
    for (std::size_t i = 0; i < m; ++i) {
      c0[i] = total0 += c0[i], c1[i] = total1 += c1[i];
      if constexpr (P == 3) c2[i] = total2 += c2[i];
    }
    const std::size_t end = m + span - 1;
    add_window_products<P, false, false>(0, std::min(m, span), m, span, omega);
    add_window_products<P, false, true>(span, m, m, span, omega);
    add_window_products<P, true, false>(m, std::min(span, end), m, span, omega);
    add_window_products<P, true, true>(std::max(m, span), end, m, span, omega);
  }
  last_omega_.setZero();
  for (int a = 0, k = 0; a < P; ++a)
    for (int b = 0; b <= a; ++b, ++k) last_omega_(a, b) = last_omega_(b, a) = omega[k];
  last_has_omega_ = true;
}

template <int P, bool Stopped, bool Leaves>
SPINDOWN_VECTOR_CLONES void Evaluator::add_window_products(std::size_t lo, std::size_t hi, std::size_t m,
                                                           std::size_t span, double* omega) const {
  const double *c0 = score(0), *c1 = score(1), *c2 = score(2);
  Lanes<6> acc;  // the lower triangle, as omega
  for_each_in_lanes(lo, hi, [&](std::size_t t, std::size_t l) SPINDOWN_LANE_BODY {
    const std::size_t in = Stopped ? m - 1 : t;
    double s0 = c0[in], s1 = c1[in], s2 = P == 3 ? c2[in] : 0.0;
    if constexpr (Leaves) {
      s0 -= c0[t - span], s1 -= c1[t - span];
      if constexpr (P == 3) s2 -= c2[t - span];
    }
    auto& a = acc.sum;
    a[0][l] += s0 * s0, a[1][l] += s1 * s0, a[2][l] += s1 * s1;
    if constexpr (P == 3) a[3][l] += s2 * s0, a[4][l] += s2 * s1, a[5][l] += s2 * s2;
  });
  for (std::size_t k = 0; k < 6; ++k) omega[k] += acc.total(k);
}

void Evaluator::decay(double alpha, std::size_t m) {
  if (alpha == decay_alpha_ && m <= decay_m_) return;
  decay_alpha_ = alpha, decay_m_ = m;
  if (!step_code_ || tau_.size() < 2 * anchor_every) {
    // Over the whole run, whatever m: Eigen's vector and scalar exp may differ in the last bit,
    // and which one a sample gets must not depend on the m asked for first.
    const auto k = static_cast<Eigen::Index>(tau_.size());
    Eigen::Map<Eigen::ArrayXd>(e_.get(), k) = (-alpha * Eigen::Map<const Eigen::ArrayXd>(tau_.data(), k)).exp();
    decay_m_ = tau_.size();
    return;
  }
  for (std::size_t d = 0; d < steps_.size(); ++d) step_factor_[d] = std::exp(-alpha * steps_[d]);
  const double* factor = step_factor_.data();
  const std::uint8_t* code = step_code_.get();
  double* out = e_.get();
  constexpr std::size_t group = 4 * anchor_every;
  std::size_t anchor = 0;
  for (; anchor + group <= m; anchor += group) {
    double *o0 = out + anchor, *o1 = o0 + anchor_every, *o2 = o1 + anchor_every, *o3 = o2 + anchor_every;
    const std::uint8_t *c0 = code + anchor, *c1 = c0 + anchor_every, *c2 = c1 + anchor_every, *c3 = c2 + anchor_every;
    const double* t = tau_.data() + anchor;
    double e0 = o0[0] = std::exp(-alpha * t[0]), e1 = o1[0] = std::exp(-alpha * t[anchor_every]);
    double e2 = o2[0] = std::exp(-alpha * t[2 * anchor_every]), e3 = o3[0] = std::exp(-alpha * t[3 * anchor_every]);
#pragma GCC unroll 3  // 63 steps of four chains: the loop's own count and test were a fifth of it
    for (std::size_t j = 1; j < anchor_every; ++j) {
      o0[j] = e0 *= factor[c0[j]];
      o1[j] = e1 *= factor[c1[j]];
      o2[j] = e2 *= factor[c2[j]];
      o3[j] = e3 *= factor[c3[j]];
    }
  }
  for (; anchor < m; anchor += anchor_every) {
    double e = out[anchor] = std::exp(-alpha * tau_[anchor]);
    for (std::size_t i = anchor + 1; i < std::min(m, anchor + anchor_every); ++i) out[i] = e *= factor[code[i]];
  }
}

void Evaluator::index_time_steps() {
  // At most an eighth full: a step seldom finds its home slot taken by another.
  constexpr std::size_t max_steps = 32, slots = 256;
  const std::size_t n = tau_.size();
  if (!sorted_ || n < 2) return;
  std::array<std::uint64_t, slots> key{};
  std::array<std::uint8_t, slots> code_plus_one{};  // 0: the slot is free
  auto code = std::make_unique_for_overwrite<std::uint8_t[]>(n);  // code[0] is never read
  const double* tau = tau_.data();  // a local: the byte stores below could alias a member
  double before = tau[0];
  for (std::size_t i = 1; i < n; ++i) {
    const double now = tau[i];
    const auto bits = std::bit_cast<std::uint64_t>(now - before);
    before = now;
    std::size_t slot = static_cast<std::size_t>((bits * 0x9E3779B97F4A7C15ull) >> 56);
    if (key[slot] != bits || code_plus_one[slot] == 0) [[unlikely]] {  // only finite steps are entered
      const double step = std::bit_cast<double>(bits);  // from the bits: nothing kept for this rare path
      if (!std::isfinite(step)) {  // no product chain through a step that is not a number
        steps_.clear();
        return;
      }
      while (code_plus_one[slot] != 0 && key[slot] != bits) slot = (slot + 1) % slots;
      if (code_plus_one[slot] == 0) {
        if (steps_.size() == max_steps) {  // jittered clock: one exponential per sample
          steps_.clear();
          return;
        }
        steps_.push_back(step);
        key[slot] = bits;
        code_plus_one[slot] = static_cast<std::uint8_t>(steps_.size());
      }
    }
    code[i] = static_cast<std::uint8_t>(code_plus_one[slot] - 1);
  }
  step_code_ = std::move(code);
  step_factor_.resize(steps_.size());
}

template void Evaluator::moving_sums<2>();
template void Evaluator::moving_sums<3>();

}  // namespace spindown::friction
