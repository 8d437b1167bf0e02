#include "spindown/run_trace.hpp"

#include <algorithm>
#include <fmt/format.h>

namespace spindown {

RunTrace::RunTrace(std::size_t max_samples, std::size_t max_display)
    : max_samples_(std::max<std::size_t>(max_samples, 1)), max_display_(std::max<std::size_t>(max_display, 2)) {}

void RunTrace::add(double t_s, double value) {
  ++received_;
  if (samples_.size() >= max_samples_) return;
  if (samples_.capacity() == samples_.size())
    samples_.reserve(std::min(max_samples_, std::max<std::size_t>(256, 2 * samples_.size())));
  samples_.push_back({t_s, value});
  while (display_size() > max_display_) stride_ *= 2;
}

std::string RunTrace::csv() const {
  std::string out = "t_s,value\n";
  out.reserve(out.size() + samples_.size() * 24);
  for (const TracePoint& p : samples_) fmt::format_to(std::back_inserter(out), "{},{}\n", p.t_s, p.value);
  return out;
}

}  // namespace spindown
