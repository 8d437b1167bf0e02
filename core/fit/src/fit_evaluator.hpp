#pragma once
// The friction models' evaluator: the weighted SSE, JᵀJ, Jᵀr and the Newey–West sums of one
// family at one point, in one vectorised pass over the run (fit_family.hpp).
#include <Eigen/Dense>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "fit_family.hpp"
#include "vector_clones.hpp"

namespace spindown::friction {

// One pass of the model over the run: the closed form is decreasing, so every sample after
// the predicted stop reads exactly 0 and only the moving samples need the model; the stopped
// tail contributes Σw·y² from a precomputed suffix sum. Each pass is one branch-free, vectorised
// loop that gathers the weighted SSE, the plain SSE, JᵀJ and Jᵀr together (w the samples'
// weights, reading_noise.hpp) and keeps each sample's score for the Newey–West matrix, which the
// covariance asks for.
class Evaluator {
 public:
  Evaluator(std::span<const double> tau, std::span<const double> y, std::span<const double> weight);

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
  SPINDOWN_VECTOR_CLONES DecaySums decay_sums(double alpha);

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
  double plain_sse(const Family& f, const Theta& th);

 private:
  void evaluate(const Family& f, const Theta& th);

  // The pass itself for a family of P parameters, branch-free so that it vectorises (the
  // sums' order then differs from a plain loop's only in rounding). Samples before the stop
  // where the model already reads 0 (rounding at the stop) count as stopped: residual y, no
  // gradient. Each sample's score g·w·r is kept for the moving sums, should the covariance ask.
  template <int P, class Row>
  SPINDOWN_VECTOR_CLONES void accumulate(const Row& row);

  // Σ_t S_t·S_tᵀ over the scores of the last pass, S_t = s_t + … + s_(t−L) for t from 0 to
  // m + L − 1 (while a window still holds a score). With the running totals C_t = s_0 + … + s_t
  // (C_t = C_(m−1) past the stop, 0 before the start) each window is S_t = C_t − C_(t−L−1): one
  // sequential pass turns the scores into their totals in place, then branch-free passes over
  // four ranges of t (which of C_t and C_(t−L−1) are real decided per range) add the products.
  template <int P>
  void moving_sums();

  // Adds S_t·S_tᵀ for t in [lo, hi) to omega: S_t = C_t, or C_(m−1) once Stopped, minus
  // C_(t−span) where Leaves.
  template <int P, bool Stopped, bool Leaves>
  SPINDOWN_VECTOR_CLONES void add_window_products(std::size_t lo, std::size_t hi, std::size_t m, std::size_t span,
                                                  double* omega) const;

  // e_i = exp(−α·τ_i) for the first m samples. A device clock ticks in whole units, so the
  // steps τ_i − τ_(i−1) take a handful of values: then e_i = e_(i−1)·exp(−α·Δ) needs one
  // exponential per distinct step instead of one per sample. Exact anchors every
  // anchor_every samples keep the product's rounding drift below 10⁻¹³; four blocks are worked
  // side by side so that their chains of products overlap instead of waiting on each other.
  // Which way e_i is computed depends on the run, not on m, so e_ is kept for the next call
  // with the same α (the viscous solution's covariance asks for the α it was found at).
  void decay(double alpha, std::size_t m);

  // Codes each sample's step τ_i − τ_(i−1) by its distinct value, bit for bit. The steps of a
  // run are a few clock periods, each in a few rounding variants (~15 in a PuTTY log, in no
  // order a branch could learn), so they are found through a small open-addressed table. Every
  // sample looks in its step's home slot first, where nearly all of them are: one test that
  // nearly always holds, not one on whether the step changed, which a PuTTY log's rounding
  // makes a coin toss.
  // Out of line: inlined into fit_run, its loop kept its pointers and the step on the stack.
  [[gnu::noinline]] void index_time_steps();

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

}  // namespace spindown::friction
