#include "spindown/run_window.hpp"

#include <algorithm>
#include <cmath>

namespace spindown {

RunWindow::RunWindow(std::span<const double> t_s, std::span<const double> value, const Run& run, bool weighted)
    : zero_level_(std::isfinite(run.zero_level) ? run.zero_level : 0.0), weighted_(weighted) {
  const std::size_t size = std::min(t_s.size(), value.size());
  const std::size_t begin = std::min(run.cut_index, size);
  const std::size_t end = std::clamp(run.end_index, begin, size);
  const std::size_t moving_end = run.stopped ? std::clamp(run.stop_index, begin, end) : end;
  readings_ = value.subspan(begin, end - begin);

  const auto out_lo = std::lower_bound(run.outliers.begin(), run.outliers.end(), begin);
  const auto out_hi = std::lower_bound(out_lo, run.outliers.end(), end);
  stride_ = end - begin - static_cast<std::size_t>(out_hi - out_lo);
  // τ, y and the weights in one buffer, written before they are read: no zeroing.
  buffer_ = std::make_unique_for_overwrite<double[]>(3 * stride_);
  double* const tau = buffer_.get();
  double* const y = tau + stride_;
  const double t_cut = run.t_cut_s, zero = zero_level_;
  bool all_finite = out_lo == out_hi;
  if (all_finite) {
    // Restrict: the buffer is our own, so the loop vectorises without a test for overlap.
    const double *__restrict t_in = t_s.data() + begin, *__restrict v_in = value.data() + begin;
    double *__restrict t_out = tau, *__restrict y_out = y;
    double probe = 0;  // NaN when a time or a reading is not a finite number
#pragma omp simd reduction(+ : probe)
    for (std::size_t i = 0; i < stride_; ++i) {
      t_out[i] = t_in[i] - t_cut, y_out[i] = v_in[i] - zero;
      probe += t_out[i] * 0.0 + y_out[i] * 0.0;
    }
    all_finite = std::isfinite(probe);
    n_ = stride_;
    moving_ = moving_end - begin;
  }
  if (!all_finite) {  // outliers, or a sample that is not a number: left out one by one
    n_ = moving_ = 0;
    auto next = out_lo;
    for (std::size_t i = begin; i < end; ++i) {
      if (next != out_hi && *next == i) {
        ++next;
        continue;
      }
      if (!std::isfinite(t_s[i]) || !std::isfinite(value[i])) continue;
      tau[n_] = t_s[i] - t_cut, y[n_] = value[i] - zero;
      ++n_;
      moving_ += i < moving_end;
    }
  }
  reading_noise_ = reading_noise_sigma(std::span<const double>(y, moving_ >= 3 ? moving_ : n_));
  // Weights from the run's own noise (σ² growing with the reading), shared by every model.
  const std::span<double> w(buffer_.get() + 2 * stride_, n_);
  if (weighted) noise_ = weigh_by_noise_into(std::span<const double>(y, n_), w);
  else std::fill(w.begin(), w.end(), 1.0);
}

}  // namespace spindown
