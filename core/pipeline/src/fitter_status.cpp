// FitterCore's options checked and its STATUS heartbeat.
#include "spindown/fitter_core.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <fmt/format.h>
#include <limits>
#include <regex>

#include "spindown/fail_why.hpp"
#include "spindown/fit_message.hpp"
#include "spindown/lab_name.hpp"
#include "spindown/lcm_channels.hpp"
#include "spindown/lcm_status.hpp"

#include "fitter_bench.hpp"

namespace spindown {

bool FitterOptions::is_valid(std::string* why) const {
  std::string inner;
  if (!runs.is_valid(&inner)) return fail_why(why, "run options: " + inner);
  FitOptions fo;
  fo.bench = default_bench;
  fo.models = models;
  if (!fo.is_valid(&inner)) return fail_why(why, "fit options: " + inner);
  if (max_benches < 1) return fail_why(why, "max_benches must be at least 1");
  if (!(std::isfinite(admit_rate_hz) && admit_rate_hz > 0))
    return fail_why(why, fmt::format("admit_rate_hz must be > 0 (got {})", admit_rate_hz));
  if (!(silent_s > 0)) return fail_why(why, fmt::format("silent_s must be > 0 (got {})", silent_s));
  if (!(std::isfinite(max_rate_hz) && max_rate_hz >= 0))
    return fail_why(why, fmt::format("max_rate_hz must be >= 0 (got {})", max_rate_hz));
  if (!(std::isfinite(burst_s) && burst_s > 0)) return fail_why(why, fmt::format("burst_s must be > 0 (got {})", burst_s));
  if (!(std::isfinite(gate.replay_window_s) && gate.replay_window_s > 0))
    return fail_why(why, fmt::format("replay window must be > 0 s (got {})", gate.replay_window_s));
  if (!gate.lab.empty() && !is_valid_lab_name(gate.lab, &inner)) return fail_why(why, inner);
  if (!(std::isfinite(stream.takeover_s) && stream.takeover_s >= 0))
    return fail_why(why, fmt::format("takeover must be >= 0 s (got {})", stream.takeover_s));
  if (!(std::isfinite(stream.confirm_s) && stream.confirm_s >= 0))
    return fail_why(why, fmt::format("confirm must be >= 0 s (got {})", stream.confirm_s));
  try {
    std::regex re(bench_regex);
  } catch (const std::regex_error& e) {
    return fail_why(why, fmt::format("bench regex '{}' is not a valid regular expression ({})", bench_regex, e.what()));
  }
  return true;
}

std::size_t FitterCore::buffered_samples() const {
  std::size_t n = 0;
  for (const auto& [id, b] : benches_) n += b->detector.buffered() + b->mirror.size();
  return n;
}

status_t FitterCore::make_status(std::int64_t now_utime, std::string_view instance, std::string_view host,
                                 std::int32_t pid, std::string_view state, double uptime_s) const {
  const FitterCounters& c = counters_;
  const std::pair<const char*, std::int64_t> counters[] = {
      {"messages", c.messages},           {"sample_messages", c.sample_messages},
      {"config_messages", c.config_messages}, {"samples", c.samples},
      {"runs_started", c.runs_started},   {"runs", c.runs},
      {"runs_ignored", c.runs_ignored},   {"fits", c.fits},
      {"fit_failures", c.fit_failures},   {"decode_errors", c.decode_errors},
      {"invalid_bench", c.invalid_bench}, {"bench_mismatch", c.bench_mismatch},
      {"filtered", c.filtered},           {"other_channels", c.other_channels},
      {"seq_gaps", c.seq_gaps},           {"samples_lost", c.samples_lost},
      {"duplicates", c.duplicates},       {"late_samples", c.late_samples},
      {"seq_restarts", c.seq_restarts},
      {"clock_restarts", c.clock_restarts}, {"nan_values", c.nan_values},
      {"time_backwards", c.time_backwards}, {"quantity_errors", c.quantity_errors},
      {"bad_configs", c.bad_configs},     {"dropped_benches", c.dropped_benches},
      {"benches_refused", c.benches_refused}, {"partial_runs", c.partial_runs},
      {"runs_abandoned", c.runs_abandoned},
      {"silent_benches", c.silent_benches},
      {"flood_drops", c.flood_drops},     {"flood_messages", c.flood_messages},
      {"internal_errors", c.internal_errors},
      {"other_lab", c.other_lab},         {"unsigned_messages", c.unsigned_messages},
      {"bad_signatures", c.bad_signatures}, {"replays", c.replays},
      {"new_sources", c.new_sources},     {"two_sources", c.two_sources},
      {"other_source_samples", c.other_source_samples}, {"seq_jumps", c.seq_jumps},
      {"seq_jump_samples", c.seq_jump_samples},
  };
  std::size_t coasting = 0;
  for (const auto& [id, b] : benches_) coasting += b->open_state != 0;
  const std::pair<const char*, double> gauges[] = {
      {"benches", double(benches_.size())},
      {"benches_coasting", double(coasting)},
      {"buffered_samples", double(buffered_samples())},
  };
  return status_message(now_utime,
                        {.service = "fitter",
                         .instance = instance,
                         .host = host,
                         .pid = pid,
                         .state = state,
                         .uptime_s = uptime_s,
                         .last_error = last_error_,
                         .last_error_utime = last_error_utime_},
                        counters, gauges);
}

}  // namespace spindown
