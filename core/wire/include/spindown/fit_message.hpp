#pragma once
// The fitter's results as LCM messages and back: a RunFit becomes a flat fit_t on
// SPINDOWN.<bench>.FIT (model i: model[i], rmse[i]…; parameter k belongs to model
// param_model[k]), and a received fit_t becomes a RunFit again, so run_fit_json() prints a
// live result exactly as `spindown fit`/`spindown refit` print theirs and the two can be
// compared field by field (timing fields aside).
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include <spindown/fit_t.hpp>
#include <spindown/run_t.hpp>

#include "spindown/fit.hpp"
#include "spindown/fit_report.hpp"
#include "spindown/motor_health.hpp"
#include "spindown/runs.hpp"

namespace spindown {

// Where the numbers of one published fit came from, beside the fit itself.
struct FitProvenance {
  std::string bench;          // bench id
  std::string bench_source;   // "config" or why a default J/K_b was used
  std::int64_t first_seq = 0; // sequence numbers of the run's first and last sample
  std::int64_t last_seq = 0;
  double latency_s = 0;       // host seconds from detection to publishing (0 offline)
  std::optional<HealthVerdict> health;  // the motor health verdict, when the bench has a bench file
  std::string bridge_host;              // the source whose samples were fitted (samples_t.source_*)
  std::uint64_t bridge_session = 0;
};

fit_t to_fit_message(const RunFit& fit, const FitProvenance& about, std::int64_t utime);

// The RunFit a fit_t describes (indices: cut 0, stop and end relative to the cut). nullopt
// and *why when the arrays are inconsistent (sizes, a parameter of a model that is not there,
// an unknown model name).
std::optional<RunFit> from_fit_message(const fit_t& msg, std::string* why = nullptr);
// The health verdict a fit_t carries: nullopt when it was not assessed (verdict ""), or when
// the finding arrays are inconsistent or a level unknown (then *why says so).
std::optional<HealthVerdict> health_from_fit_message(const fit_t& msg, std::string* why = nullptr);

// run_fit_json() of the message, plus "bench" -> "id", "first_seq"/"last_seq" and "health" when
// the message carries a verdict; nullopt and
// *why when the message is inconsistent.
std::optional<Json> fit_message_json(const fit_t& msg, const ReportOptions& opt = {}, std::string* why = nullptr);

// A run's life on SPINDOWN.<bench>.RUN.
run_t to_run_message(std::string_view bench, const Run& run, std::int8_t state, std::int64_t first_seq,
                     std::int64_t last_seq, std::int32_t samples, std::string note, std::int64_t utime);
std::string_view run_state_name(std::int8_t state);  // "powered", "coasting", "stopped", "abandoned"

// The fields that differ between two runs of the same fit on different hosts or times
// (latency, host clocks); removed before comparing JSON.
Json without_timing_fields(Json run_json);

}  // namespace spindown
