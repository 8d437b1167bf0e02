#pragma once
// One run's samples as spindown-web keeps them: every sample at full resolution up to a cap (for
// the run's CSV), and a display thinned to at most max_display points (every stride-th sample;
// the stride doubles when the display would pass the cap), so a page never gets more than that
// many points of one run however long it coasts. Bounded: past max_samples the trace keeps
// counting what arrived but stores nothing more (truncated()).
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace spindown {

struct TracePoint {
  double t_s = 0;    // device time (s), the fitter's clock
  double value = 0;  // the reading, in the bench's quantity unit
};

class RunTrace {
 public:
  explicit RunTrace(std::size_t max_samples = 30000, std::size_t max_display = 2000);

  void add(double t_s, double value);

  std::span<const TracePoint> samples() const { return samples_; }  // kept, in arrival order
  std::size_t kept() const { return samples_.size(); }
  std::int64_t received() const { return received_; }               // every sample added
  bool truncated() const { return received_ > static_cast<std::int64_t>(samples_.size()); }

  // The display: samples 0, stride, 2·stride, … of the kept ones (at most max_display).
  std::size_t stride() const { return stride_; }
  std::size_t display_size() const { return samples_.empty() ? 0 : (samples_.size() - 1) / stride_ + 1; }
  const TracePoint& display_point(std::size_t i) const { return samples_[i * stride_]; }

  // "t_s,value" then one row per kept sample (full precision: the numbers read back exactly).
  std::string csv() const;

 private:
  std::size_t max_samples_, max_display_;
  std::vector<TracePoint> samples_;
  std::int64_t received_ = 0;
  std::size_t stride_ = 1;
};

}  // namespace spindown
