#include "spindown/bench_state.hpp"

#include <cmath>

#include <spindown/run_t.hpp>
#include <spindown/samples_t.hpp>

namespace spindown {

namespace {

bool heard_within(std::int64_t last_us, std::int64_t now_us, double seconds) {
  return last_us > 0 && 1e-6 * double(now_us - last_us) <= seconds;
}

}  // namespace

std::string_view bench_state_name(BenchState s) {
  switch (s) {
    case BenchState::idle: return "idle";
    case BenchState::powered: return "powered";
    case BenchState::coasting: return "coasting";
    case BenchState::stopped: return "stopped";
    case BenchState::partial: return "partial";
    case BenchState::silent: return "silent";
  }
  return "idle";
}

double standstill_threshold(std::int8_t quantity) {
  switch (quantity) {
    case samples_t::QUANTITY_RPM: return 10.0;
    case samples_t::QUANTITY_RAD_S: return 1.0;
    default: return 0.1;
  }
}

BenchState bench_state(const LabBenchRow* row, const BenchActivity& a, std::int64_t now_us, double silent_after_s) {
  if (!heard_within(a.last_sample_us, now_us, silent_after_s)) return BenchState::silent;
  const bool turning =
      std::isfinite(a.last_value) && std::fabs(a.last_value - a.zero_level) > standstill_threshold(a.quantity);
  if (row && row->has_run && row->run_state == run_t::STATE_COASTING)
    return row->run_partial ? BenchState::partial : BenchState::coasting;
  // A coast longer than the fitter keeps was fitted up to its bound ("cap") and goes on: still coasting.
  if (turning && row && row->has_fit && row->fit_end == "cap" && row->fit_run == row->run) return BenchState::coasting;
  if (turning) return BenchState::powered;
  if (row && row->has_run && row->run_state == run_t::STATE_STOPPED)
    return row->run_partial ? BenchState::partial : BenchState::stopped;
  return BenchState::idle;
}

std::string_view bridge_health(const LabBenchRow* row, const BenchActivity& a, std::int64_t now_us,
                               double silent_after_s) {
  if (!heard_within(a.last_sample_us, now_us, silent_after_s)) return "silent";
  const bool status_fresh = heard_within(a.last_status_us, now_us, silent_after_s);
  if (status_fresh && row && row->has_bridge && row->bridge_state == "disconnected") return "unplugged";
  if (a.reconnects > 0) return "replugged";
  if (!status_fresh) return "no heartbeat";
  return "ok";
}

}  // namespace spindown
