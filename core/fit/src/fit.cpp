#include "spindown/fit.hpp"

#include "spindown/bounded_refinement.hpp"
#include "spindown/levenberg_marquardt.hpp"
#include "spindown/parameter_covariance.hpp"
#include "spindown/reading_noise.hpp"
#include "vector_clones.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fmt/format.h>
#include <limits>
#include <memory>

namespace spindown {
namespace {

constexpr double inf = std::numeric_limits<double>::infinity();
constexpr double nan = std::numeric_limits<double>::quiet_NaN();

// The three lab models are one family in reading units (r = k·ω above the zero level):
//   r(τ) = max(0, u0·e^(−ατ) − β·τ·φ(ατ)),  φ(x) = (1 − e^(−x))/x,
// with α = c_viscous/J (1/s) and β = k·c_coulomb/J (reading/s). viscous: β = 0; coulomb:
// α = 0; combined: both free. Once r reaches 0 it stays 0: for α, β ≥ 0 the closed form is
// decreasing, so clamping at zero is exactly the stop.
struct Family {
  bool alpha_free, beta_free;
  int size() const { return 1 + alpha_free + beta_free; }
};

Family family_of(ModelKind k) {
  switch (k) {
    case ModelKind::viscous: return {true, false};
    case ModelKind::coulomb: return {false, true};
    case ModelKind::combined: return {true, true};
  }
  return {true, true};
}

struct Theta {
  double u0 = 0, alpha = 0, beta = 0;
};

Theta unpack(const Family& f, const double* x) {
  Theta th;
  int i = 0;
  th.u0 = x[i++];
  if (f.alpha_free) th.alpha = x[i++];
  if (f.beta_free) th.beta = x[i++];
  return th;
}

// φ(x) = (1 − e^(−x))/x and dφ/dx from the one exponential already computed; a series where
// 1 − e would cancel.
inline void phi(double x, double e, double& p, double& dp) {
  if (x < 1e-3) {
    p = 1.0 - x / 2 + x * x / 6 - x * x * x / 24;
    dp = -0.5 + x / 3 - x * x / 8;
  } else {
    p = (1.0 - e) / x;
    dp = (e * (1.0 + x) - 1.0) / (x * x);
  }
}

// Model reading at τ and, when grad is given, its partial derivatives (zero once stopped).
inline double reading(const Family& f, const Theta& th, double tau, double* grad) {
  const double x = th.alpha * tau;
  const double e = std::exp(-x);
  double p, dp;
  phi(x, e, p, dp);
  const double m = th.u0 * e - th.beta * tau * p;
  const bool moving = m > 0;
  if (grad) {
    int i = 0;
    grad[i++] = moving ? e : 0.0;
    if (f.alpha_free) grad[i++] = moving ? (-th.u0 * tau * e - th.beta * tau * tau * dp) : 0.0;
    if (f.beta_free) grad[i++] = moving ? -tau * p : 0.0;
  }
  return moving ? m : 0.0;
}

double stop_time(const Theta& th) {
  if (th.beta <= 0) return inf;
  if (th.alpha <= 1e-12) return th.u0 / th.beta;
  return std::log1p(th.alpha * th.u0 / th.beta) / th.alpha;
}

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

// One pass of the model over the run: the closed form is decreasing, so every sample after
// the predicted stop reads exactly 0 and only the moving samples need the model; the stopped
// tail contributes Σw·y² from a precomputed suffix sum. Each pass is one branch-free, vectorised
// loop that gathers the weighted SSE, the plain SSE, JᵀJ and Jᵀr together (w the samples'
// weights, reading_noise.hpp) and keeps each sample's score for the Newey–West matrix, which the
// covariance asks for.
class Evaluator {
 public:
  Evaluator(std::span<const double> tau, std::span<const double> y, std::span<const double> weight)
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

  std::size_t size() const { return tau_.size(); }
  double weighted_sum_sq() const { return tail_sq_[0]; }  // Σw·y²
  double weighted_sum_sq_from(std::size_t i) const { return tail_sq_[i]; }  // Σ_(j≥i) w·y²
  double total_sum_sq() const { return total_sum_sq_; }   // Σ(y − ȳ)², for R²

  // Weighted sums for the viscous model by variable projection: at a given α the best u0 is
  // Σw·y·e / Σw·e² (e = e^(−ατ)), so the fit is a search over α alone. The τ and τ² moments
  // give the first and second derivatives of the projected SSE for Newton's method.
  struct DecaySums {
    double ee = 0, ye = 0, t_ee = 0, t_ye = 0, tt_ee = 0, tt_ye = 0;
  };
  SPINDOWN_VECTOR_CLONES DecaySums decay_sums(double alpha) {
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

  // The run as the direct solutions see it: times (sorted or not), weights, weighted readings.
  std::span<const double> tau() const { return tau_; }
  bool sorted() const { return sorted_; }
  std::span<const double> weights() const { return w_; }
  std::span<const double> weighted_readings() const { return {wy_.get(), tau_.size()}; }

  // Weighted SSE at θ; with jtj, also JᵀJ and Jᵀr (unused rows/columns of a smaller family
  // are left as identity/zero so 3×3 solvers serve every family); with omega, also
  // Σ_t S_t·S_tᵀ, S_t = s_t + … + s_(t−L) the moving sums of the scores s_t = g_t·w_t·r_t over
  // L + 1 samples (L = lags()): the Bartlett-weighted Newey–West sum γ0 + 2·Σ_l (1 −
  // l/(L+1))·γ_l is exactly this divided by L + 1, since each product s_i·s_(i−l)ᵀ lies in
  // L + 1 − l windows. So the long-run covariance costs one pass over the scores the
  // evaluation kept, not L passes, and no second evaluation at LM's last point.
  double operator()(const Family& f, const Theta& th, Eigen::Matrix3d* jtj = nullptr, Eigen::Vector3d* jtr = nullptr,
                    Eigen::Matrix3d* omega = nullptr) {
    if (!(last_valid_ && same(f, th))) evaluate(f, th);
    if (jtj) *jtj = last_jtj_, *jtr = last_jtr_;
    if (omega) {
      if (!last_has_omega_) f.size() == 3 ? moving_sums<3>() : moving_sums<2>();
      *omega = last_omega_;
    }
    return last_sse_;
  }
  int lags() const { return lags_; }

  // Σ(y − model)² without the weights at θ (for RMSE and R², in the reading's unit).
  double plain_sse(const Family& f, const Theta& th) {
    (*this)(f, th);
    // The stopped tail's Σy², summed from the end as the suffix sums are: asked for once per model,
    // so not kept for every m.
    double tail = 0;
    for (std::size_t i = tau_.size(); i-- > m_;) tail += y_[i] * y_[i];
    return last_plain_moving_ + tail;
  }

 private:
  void evaluate(const Family& f, const Theta& th) {
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

  // The pass itself for a family of P parameters, branch-free so that it vectorises (the
  // sums' order then differs from a plain loop's only in rounding). Samples before the stop
  // where the model already reads 0 (rounding at the stop) count as stopped: residual y, no
  // gradient. Each sample's score g·w·r is kept for the moving sums, should the covariance ask.
  template <int P, class Row>
  SPINDOWN_VECTOR_CLONES void accumulate(const Row& row) {
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

  // Σ_t S_t·S_tᵀ over the scores of the last pass, S_t = s_t + … + s_(t−L) for t from 0 to
  // m + L − 1 (while a window still holds a score). With the running totals C_t = s_0 + … + s_t
  // (C_t = C_(m−1) past the stop, 0 before the start) each window is S_t = C_t − C_(t−L−1): one
  // sequential pass turns the scores into their totals in place, then branch-free passes over
  // four ranges of t (which of C_t and C_(t−L−1) are real decided per range) add the products.
  template <int P>
  void moving_sums() {
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

  // Adds S_t·S_tᵀ for t in [lo, hi) to omega: S_t = C_t, or C_(m−1) once Stopped, minus
  // C_(t−span) where Leaves.
  template <int P, bool Stopped, bool Leaves>
  SPINDOWN_VECTOR_CLONES void add_window_products(std::size_t lo, std::size_t hi, std::size_t m, std::size_t span,
                                                  double* omega) const {
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

  // e_i = exp(−α·τ_i) for the first m samples. A device clock ticks in whole units, so the
  // steps τ_i − τ_(i−1) take a handful of values: then e_i = e_(i−1)·exp(−α·Δ) needs one
  // exponential per distinct step instead of one per sample. Exact anchors every
  // anchor_every samples keep the product's rounding drift below 10⁻¹³; four blocks are worked
  // side by side so that their chains of products overlap instead of waiting on each other.
  // Which way e_i is computed depends on the run, not on m, so e_ is kept for the next call
  // with the same α (the viscous solution's covariance asks for the α it was found at).
  void decay(double alpha, std::size_t m) {
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

  // Codes each sample's step τ_i − τ_(i−1) by its distinct value, bit for bit. The steps of a
  // run are a few clock periods, each in a few rounding variants (~15 in a PuTTY log, in no
  // order a branch could learn), so they are found through a small open-addressed table. Every
  // sample looks in its step's home slot first, where nearly all of them are: one test that
  // nearly always holds, not one on whether the step changed, which a PuTTY log's rounding
  // makes a coin toss.
  // Out of line: inlined into fit_run, its loop kept its pointers and the step on the stack.
  [[gnu::noinline]] void index_time_steps() {
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
  static constexpr std::size_t anchor_every = 64;
  std::vector<double> steps_, step_factor_;
  std::unique_ptr<std::uint8_t[]> step_code_;  // null: no product chains (see decay)
  double decay_alpha_ = nan;  // e_ holds e^(−α·τ) for this α over the first decay_m_ samples
  std::size_t decay_m_ = 0;

  std::span<const double> tau_, y_, w_;
  // Weighted readings, and the suffix sums Σ_(j≥i) w·y² (n + 1).
  std::unique_ptr<double[]> wy_, tail_sq_;
  // Scratch the passes overwrite before reading: e^(−ατ), and each column's scores g_j·w·r.
  std::unique_ptr<double[]> e_, scores_;
  double* score(int j) const { return scores_.get() + static_cast<std::size_t>(j) * tau_.size(); }
  int lags_;
  double total_sum_sq_ = 0;
  bool sorted_;
  std::size_t m_ = 0;
  // The last evaluation, so asking again for the same point costs nothing.
  bool same(const Family& f, const Theta& th) const {
    return f.alpha_free == last_f_.alpha_free && f.beta_free == last_f_.beta_free && th.u0 == last_th_.u0 &&
           th.alpha == last_th_.alpha && th.beta == last_th_.beta;
  }
  bool last_valid_ = false, last_has_omega_ = false;
  Family last_f_{false, false};
  Theta last_th_;
  double last_sse_ = 0, last_plain_moving_ = 0;  // plain: Σ(y − model)² before the stop
  Eigen::Matrix3d last_jtj_, last_omega_;
  Eigen::Vector3d last_jtr_;
};

// Starting point from the integral form of the ODE, linear in the unknowns:
//   r(τ) = u0 − α·∫₀^τ r dt − β·τ     (while moving)
// one least-squares solve over the samples before the stop: no derivatives of noisy data,
// no initial guess needed. The normal equations of the full form (columns 1, −∫r, −τ) are
// built once per run; each family solves its own sub-block.
struct IntegralForm {
  Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
  Eigen::Vector3d atb = Eigen::Vector3d::Zero();
};

// The eight sums are eight independent chains in sample order, kept side by side in vectors of
// four (the GCC/Clang vector extension: each lane is the scalar operation, so every build, of
// any vector width, gives the scalar loop's bits): Σ(∫, τ, y), Σ∫·(∫, τ, y) and Στ·(·, τ, y).
// Four samples at a time: their trapezoids in one vector operation, the running integral through
// them in order, then a 4×4 transpose turns the columns (∫, τ, y) into each sample's row.
SPINDOWN_VECTOR_CLONES IntegralForm integral_form(std::span<const double> tau, std::span<const double> y,
                                                  std::size_t moving) {
  using Four = double __attribute__((vector_size(4 * sizeof(double))));
  const auto load = [](Four& v, const double* p) { std::memcpy(&v, p, sizeof v); };  // no vector return: ABI
  Four plain = {}, by_integral = {}, by_time = {};
  const auto add = [&](double integral, double t, const Four& row) {  // row: (∫, τ, y, 0)
    plain += row, by_integral += integral * row, by_time += t * row;
  };
  double integral = 0;
  if (moving > 0) add(integral, tau[0], Four{integral, tau[0], y[0], 0.0});
  std::size_t i = 1;
  for (; i + 4 <= moving; i += 4) {
    Four t, v, t_before, y_before;
    load(t, &tau[i]), load(v, &y[i]), load(t_before, &tau[i - 1]), load(y_before, &y[i - 1]);
    const Four step = 0.5 * (v + y_before) * (t - t_before);
    const double i0 = integral + step[0], i1 = i0 + step[1], i2 = i1 + step[2], i3 = i2 + step[3];
    integral = i3;
    const Four in = {i0, i1, i2, i3}, zero = {};
    const Four even = __builtin_shufflevector(in, t, 0, 4, 2, 6), odd = __builtin_shufflevector(in, t, 1, 5, 3, 7);
    const Four even_y = __builtin_shufflevector(v, zero, 0, 4, 2, 6), odd_y = __builtin_shufflevector(v, zero, 1, 5, 3, 7);
    add(i0, t[0], __builtin_shufflevector(even, even_y, 0, 1, 4, 5));
    add(i1, t[1], __builtin_shufflevector(odd, odd_y, 0, 1, 4, 5));
    add(i2, t[2], __builtin_shufflevector(even, even_y, 2, 3, 6, 7));
    add(i3, t[3], __builtin_shufflevector(odd, odd_y, 2, 3, 6, 7));
  }
  for (; i < moving; ++i) {
    integral += 0.5 * (y[i] + y[i - 1]) * (tau[i] - tau[i - 1]);
    add(integral, tau[i], Four{integral, tau[i], y[i], 0.0});
  }
  const double s_i = plain[0], s_t = plain[1], s_y = plain[2], s_ii = by_integral[0], s_it = by_integral[1],
               s_iy = by_integral[2], s_tt = by_time[1], s_ty = by_time[2];
  IntegralForm out;  // columns (1, −∫r, −τ)
  out.ata << static_cast<double>(moving), -s_i, -s_t, -s_i, s_ii, s_it, -s_t, s_it, s_tt;
  out.atb << s_y, -s_iy, -s_ty;
  return out;
}

Theta integral_start(const Family& f, const IntegralForm& form) {
  const int p = f.size();
  int idx[3], j = 0;
  idx[j++] = 0;
  if (f.alpha_free) idx[j++] = 1;
  if (f.beta_free) idx[j++] = 2;
  Eigen::Matrix3d ata = Eigen::Matrix3d::Identity();
  Eigen::Vector3d atb = Eigen::Vector3d::Zero();
  for (int a = 0; a < p; ++a) {
    atb[a] = form.atb[idx[a]];
    for (int c = 0; c < p; ++c) ata(a, c) = form.ata(idx[a], idx[c]);
  }
  Theta th;
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(ata);
  if (ldlt.info() != Eigen::Success) return th;
  const Eigen::Vector3d sol = ldlt.solve(atb);
  if (!sol.allFinite()) return th;
  return unpack(f, sol.data());
}

// Converged once the Gauss–Newton step from the current point is a tiny fraction of each
// parameter's own statistical uncertainty s²·(JᵀJ)⁻¹ (both from the same JᵀJ, so the test
// costs no evaluation): iterating further only moves digits nobody can use. A step that a
// bound blocks (α or β held at 0) counts as zero.
constexpr double negligible_step_in_se = 1e-3;

bool at_minimum(const Family& f, const Theta& th, const Eigen::Matrix3d& jtj, const Eigen::Vector3d& jtr, double sse,
                double dof) {
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(jtj);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) return false;
  const Eigen::Matrix3d inv = ldlt.solve(Eigen::Matrix3d::Identity());
  const Eigen::Vector3d step = inv * jtr;
  if (!step.allFinite()) return false;
  const double s2 = sse / dof;
  double x[3];
  int j = 0;
  x[j++] = th.u0;
  if (f.alpha_free) x[j++] = th.alpha;
  if (f.beta_free) x[j++] = th.beta;
  for (j = 0; j < f.size(); ++j) {
    const bool blocked = j > 0 && x[j] <= 0 && step[j] < 0;
    if (!blocked && std::abs(step[j]) > negligible_step_in_se * std::sqrt(std::max(s2 * inv(j, j), 0.0)) &&
        std::abs(step[j]) > 1e-12 * std::abs(x[j]))
      return false;
  }
  return true;
}

// One family's least squares for the shared Levenberg–Marquardt (levenberg_marquardt.hpp), with
// the bounds α, β ≥ 0, u0 > 0 enforced by projection. The closed-form Jacobian makes each
// iteration one pass over the data; from the integral start it converges in a handful of
// iterations. Its policy: a step that leaves the SSE equal is taken, converged when the step is
// negligible beside the standard errors (at_minimum) or gains under 10⁻¹⁴ of the SSE, at most 100
// iterations and 200 evaluations; 3×3 systems for every family (a smaller one padded with the
// identity).
class FamilyLeastSquares {
 public:
  using Point = Theta;
  struct State {
    Eigen::Matrix3d jtj;
    Eigen::Vector3d jtr;
  };
  FamilyLeastSquares(const Family& f, Evaluator& eval)
      : f_(f), eval_(eval), dof_(static_cast<double>(std::max<std::size_t>(eval.size() - f.size(), 1))) {}

  LmPolicy policy() const { return {.max_iterations = 100, .max_evaluations = 200, .take_equal = true, .relative_gain = 1e-14}; }
  double evaluate(const Theta& th, State& s) { return eval_(f_, th, &s.jtj, &s.jtr); }
  bool at_minimum(const Theta& th, const State& s, double sse) const {
    return spindown::at_minimum(f_, th, s.jtj, s.jtr, sse, dof_);
  }
  bool step(const Theta& th, const State& s, double lambda, Theta& out) const {
    const int p = f_.size();
    Eigen::Matrix3d a = s.jtj;
    a.diagonal().head(p) *= 1.0 + lambda;
    const Eigen::LDLT<Eigen::Matrix3d> ldlt(a);
    if (ldlt.info() != Eigen::Success) return false;
    const Eigen::Vector3d step = ldlt.solve(s.jtr);
    if (!step.allFinite()) return false;
    double x[3];
    int j = 0;
    x[j++] = th.u0;
    if (f_.alpha_free) x[j++] = th.alpha;
    if (f_.beta_free) x[j++] = th.beta;
    for (j = 0; j < p; ++j) x[j] = std::max(x[j] + step[j], j == 0 ? 1e-12 : 0.0);
    out = unpack(f_, x);
    return true;
  }
  bool negligible(const Theta&, const Theta&) const { return false; }

 private:
  Family f_;
  Evaluator& eval_;
  double dof_;
};

// The viscous model by variable projection: Newton's method on the one-dimensional projected
// SSE F(α) = Σw·y² − (Σw·y·e)²/Σw·e², u0 following in closed form. The same minimum as LM over
// (u0, α), reached with one cheap pass per iteration (no Jacobian matrix). Stops by the same
// rule as LM: the step is a tiny fraction of α's standard error, whose variance is s²·2/F''.
// nullopt when Newton is not safe (F'' ≤ 0, α driven to its bound, no convergence): LM then.
std::optional<Theta> viscous_by_projection(Evaluator& eval, double alpha, int& passes) {
  const double sum_wyy = eval.weighted_sum_sq();
  const double dof = static_cast<double>(std::max<std::size_t>(eval.size(), 3) - 2);
  for (int it = 0; it < 30; ++it) {
    const Evaluator::DecaySums s = eval.decay_sums(alpha);
    ++passes;
    // F = Syy − N²/D with N = Σw·y·e, D = Σw·e²; dN/dα = −Σw·τ·y·e, dD/dα = −2·Σw·τ·e², …
    const double N = s.ye, D = s.ee, N1 = -s.t_ye, N2 = s.tt_ye, D1 = -2 * s.t_ee, D2 = 4 * s.tt_ee;
    if (!(D > 0) || !(N > 0)) return std::nullopt;
    const double u = 2 * N * N1 * D - N * N * D1;
    const double grad = -u / (D * D);
    const double hess = -(2 * N1 * N1 * D + 2 * N * N2 * D - N * N * D2) / (D * D) + 2 * D1 * u / (D * D * D);
    if (!(hess > 0) || !std::isfinite(grad)) return std::nullopt;
    const double step = -grad / hess;
    const double var_alpha = 2 * std::max(sum_wyy - N * N / D, 0.0) / dof / hess;
    if (std::abs(step) <= negligible_step_in_se * std::sqrt(var_alpha) || std::abs(step) <= 1e-12 * alpha)
      return Theta{N / D, alpha, 0.0};
    if (alpha + step <= 0) return std::nullopt;  // at the bound α = 0: LM's projection handles it
    alpha += step;
  }
  return std::nullopt;
}

// Weighted sums of the straight line y ≈ u0 − β·τ over the samples added so far, and the two
// least-squares lines they give. Each is an optimum, so its SSE is Σw·y² minus a gain q/d.
struct LineSums {
  double w = 0, t = 0, tt = 0, y = 0, ty = 0;  // Σw, Σw·τ, Σw·τ², Σw·y, Σw·τ·y

  void add(double wi, double wyi, double ti) { w += wi, t += wi * ti, tt += wi * ti * ti, y += wyi, ty += wyi * ti; }
  // Both parameters free: [Σw −Σwτ; −Σwτ Σwτ²]·(u0, β) = (Σwy, −Σwτy), u0 = U/det, β = B/det.
  double det() const { return w * tt - t * t; }
  double u() const { return tt * y - t * ty; }
  double b() const { return t * y - w * ty; }
  double plain_gain_times_det() const { return tt * y * y - 2 * t * y * ty + w * ty * ty; }
  Theta plain() const { return {u() / det(), 0.0, b() / det()}; }
  // Stopped exactly at te (u0 = β·te): β = Σw·y·(te−τ) / Σw·(te−τ)², gain num²/den.
  double edge_num(double te) const { return te * y - ty; }
  double edge_den(double te) const { return te * te * w - 2 * te * t + tt; }
  Theta edge(double te) const {
    const double beta = edge_num(te) / edge_den(te);
    return {beta * te, 0.0, beta};
  }
};

// LineSums over samples [lo, hi) in one vectorised pass (four lanes: the order of the additions
// differs from adding them one by one only in rounding).
using LineLanes = Lanes<5>;  // Σw, Σw·τ, Σw·τ², Σw·y, Σw·τ·y
SPINDOWN_LANE_BODY inline void add_line_lanes(LineLanes& acc, const double* t, const double* ws, const double* wys,
                                              std::size_t lo, std::size_t hi) {
  for_each_in_lanes(lo, hi, [&](std::size_t i, std::size_t l) SPINDOWN_LANE_BODY {
    const double wt = ws[i] * t[i];
    auto& a = acc.sum;
    a[0][l] += ws[i], a[1][l] += wt, a[2][l] += wt * t[i], a[3][l] += wys[i], a[4][l] += wys[i] * t[i];
  });
}
LineSums line_total(const LineLanes& acc) { return {acc.total(0), acc.total(1), acc.total(2), acc.total(3), acc.total(4)}; }

SPINDOWN_VECTOR_CLONES LineSums line_sums(std::span<const double> tau, std::span<const double> w,
                                          std::span<const double> wy, std::size_t lo, std::size_t hi) {
  LineLanes acc;
  add_line_lanes(acc, tau.data(), w.data(), wy.data(), lo, hi);
  return line_total(acc);
}

// Counted from sample 0, sample i adds to lane i mod 4 in order, so the lanes over [0, m) are
// those over [0, c), c any multiple of 4 up to m, plus the samples [c, m). The Coulomb scan needs
// the sums up to the hint and then up to an earlier count: line_sums(0, hi) keeps its lanes
// every checkpoint_every samples (checkpoint k holds [0, k·checkpoint_every)), and the shorter
// prefix continues from one, bit for bit what line_sums(0, m) gives, instead of starting again.
constexpr std::size_t checkpoint_every = 64;  // a multiple of the four lanes
constexpr std::size_t checkpoint_size = sizeof(LineLanes::sum) / sizeof(double);  // doubles per checkpoint
SPINDOWN_VECTOR_CLONES LineSums line_sums_with_checkpoints(std::span<const double> tau, std::span<const double> w,
                                                           std::span<const double> wy, std::size_t hi,
                                                           double* checkpoints) {
  LineLanes acc;
  for (std::size_t lo = 0, k = 0; lo < hi; lo += checkpoint_every, ++k) {
    std::memcpy(checkpoints + k * checkpoint_size, acc.sum, sizeof acc.sum);
    add_line_lanes(acc, tau.data(), w.data(), wy.data(), lo, std::min(lo + checkpoint_every, hi));
  }
  return line_total(acc);
}
SPINDOWN_VECTOR_CLONES LineSums line_sums_from_checkpoint(std::span<const double> tau, std::span<const double> w,
                                                          std::span<const double> wy, std::size_t m,
                                                          const double* checkpoints) {
  const std::size_t k = m / checkpoint_every;
  LineLanes acc;
  std::memcpy(acc.sum, checkpoints + k * checkpoint_size, sizeof acc.sum);
  add_line_lanes(acc, tau.data(), w.data(), wy.data(), k * checkpoint_every, m);
  return line_total(acc);
}

// The Coulomb model in closed form. While moving it is the straight line u0 − β·τ, and the
// samples that move are those before its stop ts = u0/β; so for each count m of moving samples
// the weighted SSE is a quadratic in (u0, β) whose minimum is either the plain line fit over the
// first m samples (when its own stop falls between τ[m−1] and τ[m]) or on that range's edge
// ts = τ[m], the line through (τ[m], 0). Running sums give every candidate's SSE in O(1), so
// one pass over m finds the global minimum of the clamped SSE — where LM from a start could
// stop at a nearby kink. nullopt when the clock is not sorted or no falling line fits: LM then.
//
// A candidate's gain (Σw·y² minus its SSE) is at most P(m) = Σ_(i<m) w·y², as its SSE over the
// moving samples is not negative, and P grows with m. So once the candidates at the detector's
// stop (`hint` moving samples) give a gain G, no count with P(m) < G can win: the scan gathers
// those samples' sums in one vectorised pass and weighs candidates only after them.
std::optional<Theta> coulomb_by_line_scan(const Evaluator& eval, std::size_t hint, int& passes) {
  const std::span<const double> tau = eval.tau(), w = eval.weights(), wy = eval.weighted_readings();
  const std::size_t n = tau.size();
  if (!eval.sorted() || n < 3) return std::nullopt;
  ++passes;
  // The best candidate has the largest gain q/d, compared as q·d_best > q_best·d (d > 0): no
  // division per m. The winner's sums are kept; its parameters come from them at the end.
  LineSums sums, best;
  double best_q = 0, best_d = 1, best_edge = nan;  // best_edge: the stop te if the winner is an edge
  bool found = false;
  const auto take = [&](double q, double d, double edge) SPINDOWN_LANE_BODY {
    if (q * best_d > best_q * d) best_q = q, best_d = d, best = sums, best_edge = edge, found = true;
  };
  // The candidates with m moving samples, given their sums. Inlined (as take) into the scan, so
  // that the running sums stay in registers.
  const auto weigh = [&](std::size_t m) SPINDOWN_LANE_BODY {
    const double t = tau[m - 1];
    // The plain line over the first m counts if it falls (U, B > 0) and stops in (τ[m−1], τ[m]].
    const double det = sums.det(), U = sums.u(), B = sums.b();
    if (det > 0 && U > 0 && B > 0 && U > B * t && (m == n || U <= B * tau[m])) take(sums.plain_gain_times_det(), det, nan);
    // The edge: stopped exactly at the next sample.
    if (m < n) {
      const double num = sums.edge_num(tau[m]), den = sums.edge_den(tau[m]);
      if (den > 0 && num > 0) take(num * num, den, tau[m]);
    }
  };
  // The bound from the candidates at the hint; they are weighed again in the scan.
  std::size_t first = 3;
  double bound = 0;
  // The hint's lanes, for the scan's start (never past the hint); written before read, not zeroed.
  std::unique_ptr<double[]> checkpoints;
  if (hint >= 3 && hint <= n) {
    checkpoints = std::make_unique_for_overwrite<double[]>((hint + checkpoint_every - 1) / checkpoint_every * checkpoint_size);
    sums = line_sums_with_checkpoints(tau, w, wy, hint, checkpoints.get());
    weigh(hint);
    if (found) {
      // The first count with P(m) ≥ G (P is monotone: a suffix sum of non-negative terms).
      bound = best_q / best_d * (1 - 1e-9);
      const double total = eval.weighted_sum_sq();
      for (std::size_t hi = hint; first < hi;) {
        const std::size_t mid = first + (hi - first) / 2;
        if (total - eval.weighted_sum_sq_from(mid) < bound) first = mid + 1;
        else hi = mid;
      }
    }
    sums = LineSums{}, best = LineSums{}, best_q = 0, best_d = 1, best_edge = nan, found = false;
  }
  const auto scan_from = [&](std::size_t from) {
    sums = checkpoints ? line_sums_from_checkpoint(tau, w, wy, from - 1, checkpoints.get())
                       : line_sums(tau, w, wy, 0, from - 1);
    for (std::size_t m = from; m <= n; ++m) {
      sums.add(w[m - 1], wy[m - 1], tau[m - 1]);
      weigh(m);
    }
  };
  scan_from(first);
  // The bound holds if the scan's own best reaches G; a boundary test that the hint's sums and
  // the scan's round differently could deny it that candidate: then every count is weighed.
  if (first > 3 && !(found && best_q / best_d >= bound)) {
    sums = LineSums{}, best = LineSums{}, best_q = 0, best_d = 1, best_edge = nan, found = false;
    scan_from(3);
  }
  if (!found) return std::nullopt;
  return std::isnan(best_edge) ? best.plain() : best.edge(best_edge);
}

struct Covariance {
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  bool ok = false;
};

// Parameter covariance from the Jacobian at the optimum (parameter_covariance.hpp): classic,
// widened per parameter to the Newey–West variance, whose Ω comes from the evaluation's moving
// sums of the scores (Evaluator::operator()).
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

Parameter make_param(std::string name, double value, double se, std::string unit) {
  return {std::move(name), value, se, std::move(unit)};
}

// Standard error of g(θ) by the delta method, grad in (u0, α, β) order restricted to free params.
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

// Bounded quasi-Newton refinement (bounded_refinement.hpp, the fallback when LM does not
// converge) on the parameters scaled by their size, the SSE by its value at the start.
// Returns "" on success or why it failed; th is updated to the best point found.
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

ModelFit fit_model(ModelKind kind, std::span<const double> tau, std::span<const double> y, std::size_t moving,
                   double k, const BenchParams& bench, std::string_view runit, Evaluator* evaluator,
                   const IntegralForm& form, const Theta* start = nullptr) {
  ModelFit out;
  out.kind = kind;
  out.n = tau.size();
  const Family fam = family_of(kind);
  const int p = fam.size();
  if (moving < static_cast<std::size_t>(p) + 2 || tau.size() < static_cast<std::size_t>(p) + 2) {
    out.message = fmt::format("{} samples while moving: too few to fit {} parameters", moving, p);
    return out;
  }

  // Start: the integral form; guard it into the feasible region (α, β ≥ 0, u0 > 0).
  Theta th = start ? *start : integral_start(fam, form);
  const double y_first = *std::max_element(y.begin(), y.begin() + std::min<std::size_t>(moving, 5));
  if (!(th.u0 > 0) || !std::isfinite(th.u0)) th.u0 = std::max(y_first, 1e-6);
  const double span_s = std::max(tau[moving - 1], 1e-3);
  if (!start && fam.alpha_free && !(th.alpha > 0)) th.alpha = fam.beta_free ? 1e-3 / span_s : 1.0 / span_s;
  if (!start && fam.beta_free && !(th.beta > 0)) th.beta = fam.alpha_free ? 1e-3 * th.u0 / span_s : th.u0 / span_s;

  Evaluator& eval = *evaluator;
  // Viscous and Coulomb have direct solutions (one parameter by Newton, or none); LM for the
  // combined model and whenever a direct solution declines.
  std::optional<Theta> direct;
  if (kind == ModelKind::viscous) direct = viscous_by_projection(eval, th.alpha, out.evaluations);
  if (kind == ModelKind::coulomb) direct = coulomb_by_line_scan(eval, moving, out.evaluations);
  bool solved = direct.has_value();
  if (direct) {
    th = *direct;
  } else {
    FamilyLeastSquares problem(fam, eval);
    const auto lm = levenberg_marquardt(problem, th);
    out.evaluations += lm.evals;
    th = lm.theta;
    solved = lm.converged;
  }
  std::string why;
  if (!solved) {
    // Fallback: NLopt's L-BFGS under bounds on scaled parameters, from LM's best point.
    why = refine_with_nlopt(fam, tau, eval, th, out.evaluations);
    solved = why.empty();
  }
  // The likelihood is the weighted one (weights average 1, so with equal weights it is the
  // classic n·log(SSE/n)); RMSE and R² are in the reading's own unit.
  const Covariance cv = covariance(fam, th, eval);  // first: its Jacobian pass serves the sums below
  const double wsse = eval(fam, th);
  const double sse = eval.plain_sse(fam, th);
  const double n = static_cast<double>(tau.size());
  const double sst = eval.total_sum_sq();
  out.rmse = std::sqrt(sse / n);
  out.r2 = sst > 0 ? 1.0 - sse / sst : nan;
  const double ll = n * std::log(std::max(wsse / n, 1e-300));
  out.aic = ll + 2.0 * p;
  out.bic = ll + p * std::log(n);
  out.t_stop_pred_s = stop_time(th);
  out.omega0 = th.u0 / k;
  out.rate = th.alpha;
  out.decel = th.beta / k;

  out.converged = solved && cv.ok;
  if (!solved) out.message = why;
  else if (!cv.ok) out.message = "parameters are not identifiable from this run (singular Jacobian)";
  const Eigen::Matrix3d& c = cv.cov;
  const double J = bench.inertia_kg_m2;
  const auto se = [&](double du0, double dal, double dbe) { return cv.ok ? delta_se(fam, c, du0, dal, dbe) : nan; };
  const std::string ru(runit), rate_unit = ru + "/s";
  switch (kind) {
    case ModelKind::viscous:
      out.params = {make_param("c1", th.alpha * J, se(0, J, 0), "N*m*s/rad"),
                    make_param("omega0", out.omega0, se(1 / k, 0, 0), "rad/s"),
                    make_param("A", th.u0, se(1, 0, 0), ru), make_param("B", th.alpha, se(0, 1, 0), "1/s")};
      break;
    case ModelKind::coulomb:
      out.params = {make_param("c2", th.beta * J / k, se(0, 0, J / k), "N*m"),
                    make_param("omega0", out.omega0, se(1 / k, 0, 0), "rad/s"),
                    make_param("A", -th.beta, se(0, 0, 1), rate_unit), make_param("B", th.u0, se(1, 0, 0), ru)};
      break;
    case ModelKind::combined: {
      // y = A + B·e^(Cτ): A = −β/α, B = u0 + β/α, C = −α (the lab's seed curve). With α at its
      // bound 0 the curve is Coulomb's straight line and A, B are infinite: no number to give.
      const double a = th.alpha;
      const bool curve = a > 0;
      const auto curve_se = [&](double du0, double dal, double dbe) { return curve ? se(du0, dal, dbe) : nan; };
      out.params = {make_param("c3", th.alpha * J, se(0, J, 0), "N*m*s/rad"),
                    make_param("c4", th.beta * J / k, se(0, 0, J / k), "N*m"),
                    make_param("omega0", out.omega0, se(1 / k, 0, 0), "rad/s"),
                    make_param("A", curve ? -th.beta / a : -inf, curve_se(0, th.beta / (a * a), -1 / a), ru),
                    make_param("B", curve ? th.u0 + th.beta / a : inf, curve_se(1, -th.beta / (a * a), 1 / a), ru),
                    make_param("C", -th.alpha, se(0, -1, 0), "1/s")};
      break;
    }
  }
  return out;
}

}  // namespace

std::string_view model_name(ModelKind k) {
  switch (k) {
    case ModelKind::viscous: return "viscous";
    case ModelKind::coulomb: return "coulomb";
    case ModelKind::combined: return "combined";
  }
  return "?";
}

std::optional<ModelKind> parse_model(std::string_view name) {
  for (ModelKind k : all_models)
    if (model_name(k) == name) return k;
  return std::nullopt;
}

const Parameter* ModelFit::param(std::string_view name) const {
  for (const auto& p : params)
    if (p.name == name) return &p;
  return nullptr;
}

double ModelFit::omega_at(double tau) const {
  const Family f = family_of(kind);
  const Theta th{omega0, rate, decel};  // in ω units (k = 1)
  return reading(f, th, std::max(tau, 0.0), nullptr);
}

const ModelFit* RunFit::model(ModelKind k) const {
  for (const auto& m : models)
    if (m.kind == k) return &m;
  return nullptr;
}

bool FitOptions::is_valid(std::string* why) const {
  if (!bench.is_valid(why)) return false;
  if (models.empty()) {
    if (why) *why = "no model chosen";
    return false;
  }
  return true;
}

RunFit fit_run(std::span<const double> t_s, std::span<const double> value, Quantity q, const Run& run,
               const FitOptions& opt) {
  RunFit out;
  out.run = run;
  out.bench = opt.bench;
  out.quantity = q;
  const std::size_t begin = std::min(run.cut_index, t_s.size());
  const std::size_t end = std::clamp(run.end_index, begin, t_s.size());
  const std::size_t stop = std::clamp(run.stop_index, begin, end);
  const double k = value_per_rad_per_s(q, opt.bench.kb_v_s_per_rad);

  // The run's outliers (dropouts, glitches) are left out: the samples kept, and those of them moving.
  const auto out_lo = std::lower_bound(run.outliers.begin(), run.outliers.end(), begin);
  const auto out_hi = std::lower_bound(out_lo, run.outliers.end(), end);
  const std::size_t n = end - begin - std::size_t(out_hi - out_lo);
  // τ, y and the weights in one buffer, written before they are read: no zeroing.
  const auto buffer = std::make_unique_for_overwrite<double[]>(3 * n);
  const std::span<double> tau(buffer.get(), n), y(buffer.get() + n, n), weight(buffer.get() + 2 * n, n);
  if (out_lo != out_hi) {
    std::size_t j = 0;
    auto next = out_lo;
    for (std::size_t i = begin; i < end; ++i) {
      if (next != out_hi && *next == i) {
        ++next;
        continue;
      }
      tau[j] = t_s[i] - run.t_cut_s, y[j] = value[i] - run.zero_level;
      ++j;
    }
  } else {
    // Restrict: the buffer is our own, so the loop vectorises without a test for overlap.
    const double *__restrict t_in = t_s.data() + begin, *__restrict v_in = value.data() + begin;
    double *__restrict t_out = tau.data(), *__restrict y_out = y.data();
    const double t_cut = run.t_cut_s, zero = run.zero_level;
#pragma omp simd
    for (std::size_t i = 0; i < n; ++i) t_out[i] = t_in[i] - t_cut, y_out[i] = v_in[i] - zero;
  }
  const std::size_t moving_end = run.stopped ? stop : end;
  const std::size_t moving =
      moving_end - begin - std::size_t(std::lower_bound(out_lo, out_hi, moving_end) - out_lo);
  const std::string_view runit = quantity_unit(q);
  // Weights from the run's own noise (σ² growing with the reading), shared by every model.
  if (opt.weighted) weigh_by_noise_into(y, weight);
  else std::fill(weight.begin(), weight.end(), 1.0);
  Evaluator eval(tau, y, weight);  // one workspace for every model of the run
  const IntegralForm form = integral_form(tau, y, moving);
  for (ModelKind kind : opt.models)
    out.models.push_back(fit_model(kind, tau, y, moving, k, opt.bench, runit, &eval, form));
  // The combined model nests the other two, but from a poor start LM can come to rest on the bound
  // α = 0 or β = 0 short of their fit (seen on a damaged log: RMSE 0.34 V beside Coulomb's 0.08 V).
  // Then it starts again from the better nested fit: LM takes only steps that lower the SSE, so the
  // combined fit ends at least as good as both.
  for (auto& m : out.models) {
    if (m.kind != ModelKind::combined || !m.converged) continue;
    // Compared by n·log(SSE/n), the AIC without its 2p: no pass over the data unless LM starts again.
    const ModelFit* from = nullptr;
    double least = m.aic - 6;
    for (const auto& nested : out.models)
      if (nested.kind != ModelKind::combined && nested.converged && nested.aic - 4 < least)
        least = nested.aic - 4, from = &nested;
    if (!from) continue;
    const Theta restart{from->omega0 * k, from->rate, from->decel * k};
    ModelFit again = fit_model(ModelKind::combined, tau, y, moving, k, opt.bench, runit, &eval, form, &restart);
    again.evaluations += m.evaluations;
    if (again.converged && again.aic < m.aic) m = std::move(again);
  }

  // Best model: lowest BIC among converged fits (BIC penalises the extra parameter).
  const ModelFit* best = nullptr;
  const ModelFit* second = nullptr;
  for (const auto& m : out.models) {
    if (!m.converged) continue;
    if (!best || m.bic < best->bic) {
      second = best;
      best = &m;
    } else if (!second || m.bic < second->bic) {
      second = &m;
    }
  }
  if (best) {
    out.best = std::string(model_name(best->kind));
    if (second) {
      const double dbic = second->bic - best->bic;
      const char* strength = dbic > 10 ? "very strong" : dbic > 6 ? "strong" : dbic > 2 ? "positive" : "weak";
      out.best_reason = fmt::format("lowest BIC, {:.1f} below {} ({} evidence); RMSE {:.4g} {} vs {:.4g} {}", dbic,
                                    model_name(second->kind), strength, best->rmse, runit, second->rmse, runit);
    } else {
      out.best_reason = out.models.size() == 1 ? "the only model asked for" : "the only model that converged";
    }
  }
  return out;
}

RunFit fit_run(const Recording& rec, const Run& run, const FitOptions& opt) {
  return fit_run(rec.t_s, rec.value, rec.quantity, run, opt);
}

}  // namespace spindown
