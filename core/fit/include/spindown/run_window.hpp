#pragma once
// The samples one run is fitted on, computed once per run and used by fit, explain and the live
// fitter alike: the run's cut to its end less its outliers (dropouts, glitches) and any reading
// that is not a number, τ from the cut, the readings less the zero level, the weights from the
// run's own noise (reading_noise.hpp), the part before the stop and the reading noise σ.
// It views the caller's readings (readings()): build it where they live, use it while they do.
#include <cstddef>
#include <memory>
#include <span>

#include "spindown/reading_noise.hpp"
#include "spindown/runs.hpp"

namespace spindown {

class RunWindow {
 public:
  // weighted: weights 1/σ²(u) from the run's noise; false: all ones (the lab's plain least squares).
  RunWindow(std::span<const double> t_s, std::span<const double> value, const Run& run, bool weighted);
  RunWindow(const RunWindow&) = delete;
  RunWindow& operator=(const RunWindow&) = delete;

  std::size_t size() const { return n_; }
  std::span<const double> tau() const { return {buffer_.get(), n_}; }                // s since the cut
  std::span<const double> y() const { return {buffer_.get() + stride_, n_}; }         // reading − zero level
  std::span<const double> weight() const { return {buffer_.get() + 2 * stride_, n_}; }  // average 1
  // Samples kept before the stop (all of them when the run did not stop).
  std::size_t moving() const { return moving_; }
  double zero_level() const { return zero_level_; }
  bool weighted() const { return weighted_; }
  const ReadingNoise& noise() const { return noise_; }  // σ²(u); known == false: unweighted
  // σ of one reading over the coast (reading_noise_sigma of y before the stop; all of y when fewer
  // than 3 samples move).
  double reading_noise() const { return reading_noise_; }
  // The caller's readings from the cut to the end, outliers included (the readings' step and peak).
  std::span<const double> readings() const { return readings_; }

 private:
  std::unique_ptr<double[]> buffer_;  // τ, y and the weights in one allocation, stride_ apart
  std::size_t stride_ = 0;
  std::size_t n_ = 0;
  std::size_t moving_ = 0;
  double zero_level_ = 0;
  bool weighted_ = true;
  ReadingNoise noise_;
  double reading_noise_ = 0;
  std::span<const double> readings_;
};

}  // namespace spindown
