#pragma once
// A bench's SAMPLE stream, checked once for everyone who reads it: the live fitter
// (FitterCore) and the LCM log reader (read_lcm_log) take every message through
// SampleStream::take, so a refit of a log sees exactly the samples the fitter saw live, with the
// same words for what was wrong.
//
// Per message: the quantity code must be known and must not change; the sequence number tells
// lost samples (a jump forward), a repeated message (backward, times already seen: skipped)
// and a restarted bridge (backward, new times); a new clock epoch, or times that start again
// below the last, is a restarted device clock (a new timeline). Per sample: a value must be
// finite and a device time must advance.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <fmt/format.h>
#include <limits>
#include <optional>
#include <string>

#include <spindown/samples_t.hpp>

#include "spindown/message_decode.hpp"
#include "spindown/recording.hpp"

namespace spindown {

std::optional<Quantity> quantity_from_samples_code(std::int8_t code);  // samples_t::QUANTITY_*
std::int8_t samples_code_of(Quantity quantity);

enum class SampleProblem {
  unknown_quantity,  // message skipped
  quantity_change,   // message skipped
  samples_lost,      // count: samples missing before this message
  repeated,          // message skipped
  sequence_restart,  // the bridge restarted its sequence numbers
  clock_restart,     // the device clock restarted: a new timeline starts with this message
  bad_value,         // a NaN or infinite value: that sample skipped
  time_backwards,    // a device time that does not advance: that sample skipped
};

// A sample's device time and value from either form of samples_t.
inline std::int64_t sample_time_us(const samples_t& m, std::size_t i) { return m.device_time_us[i]; }
inline double sample_value(const samples_t& m, std::size_t i) { return m.value[i]; }
inline std::int64_t sample_time_us(const SamplesView& m, std::size_t i) {
  return m.device_time_us(static_cast<std::int32_t>(i));
}
inline double sample_value(const SamplesView& m, std::size_t i) { return m.value(static_cast<std::int32_t>(i)); }

struct SampleStream {
  bool quantity_known = false;
  Quantity quantity = Quantity::back_emf_volts;
  std::int8_t quantity_code = 0;  // the samples_t code that gave quantity
  bool have_seq = false, have_epoch = false;
  std::int64_t next_seq = 0;
  std::int32_t epoch = 0;
  std::int64_t last_t_us = std::numeric_limits<std::int64_t>::min();

  // Takes a message of n samples (n already checked against its arrays). For each thing wrong,
  // sink.problem(SampleProblem, count, text) with the words to report; for each sample kept,
  // sink.sample(seq, device_time_us, value). Returns false when the whole message is skipped.
  // Inlined: at one sample per message a call costs as much as the checks.
  template <class Message, class Sink>
  [[gnu::always_inline]] inline bool take(const Message& m, std::size_t n, Sink&& sink) {
    const auto count = static_cast<std::int64_t>(n);
    // The stream's own quantity code again (nearly always): nothing to check.
    if (!quantity_known || m.quantity != quantity_code) {
      const auto q = quantity_from_samples_code(m.quantity);
      if (!q) {
        sink.problem(SampleProblem::unknown_quantity, count,
                     fmt::format("unknown quantity code {} at seq {}; message of {} samples skipped", int(m.quantity),
                                 m.seq, n));
        return false;
      }
      if (!quantity_known) {
        quantity = *q;
        quantity_code = m.quantity;
        quantity_known = true;
      } else if (*q != quantity) {
        sink.problem(SampleProblem::quantity_change, count,
                     fmt::format("quantity changes from {} to {} at seq {}; message of {} samples skipped",
                                 quantity_unit(quantity), quantity_unit(*q), m.seq, n));
        return false;
      }
    }

    bool restart = have_epoch && m.clock_epoch != epoch;
    if (have_seq && m.seq != next_seq) {
      if (m.seq > next_seq) {
        sink.problem(SampleProblem::samples_lost, m.seq - next_seq,
                     fmt::format("{} samples lost: sequence number jumps from {} to {}", m.seq - next_seq,
                                 next_seq - 1, m.seq));
      } else if (!restart && n > 0 && sample_time_us(m, n - 1) <= last_t_us) {
        sink.problem(SampleProblem::repeated, count,
                     fmt::format("samples {} to {} were already received (repeated message); skipped", m.seq,
                                 m.seq + count - 1));
        return false;
      } else {
        sink.problem(SampleProblem::sequence_restart, 0,
                     fmt::format("sequence number restarts from {} at {} (bridge restarted?)", next_seq, m.seq));
        if (n > 0 && sample_time_us(m, 0) <= last_t_us) restart = true;
      }
    }
    have_seq = true;
    next_seq = m.seq + count;
    if (restart) {
      sink.problem(SampleProblem::clock_restart, 0,
                   have_epoch && m.clock_epoch != epoch
                       ? fmt::format("device clock restarted (clock epoch {} -> {}); a new timeline starts here and "
                                     "no run spans it",
                                     epoch, m.clock_epoch)
                       : std::string("device clock restarted (times start again); a new timeline starts here and "
                                     "no run spans it"));
      last_t_us = std::numeric_limits<std::int64_t>::min();
    }
    have_epoch = true;
    epoch = m.clock_epoch;

    for (std::size_t i = 0; i < n; ++i) {
      const std::int64_t t = sample_time_us(m, i);
      const double v = sample_value(m, i);
      const std::int64_t seq = m.seq + static_cast<std::int64_t>(i);
      if (!std::isfinite(v)) {
        sink.problem(SampleProblem::bad_value, 1, fmt::format("sample {}: value is NaN or infinite; skipped", seq));
        continue;
      }
      if (t <= last_t_us) {
        sink.problem(SampleProblem::time_backwards, 1,
                     fmt::format("sample {}: device time {} µs does not advance (previous {} µs); skipped", seq, t,
                                 last_t_us));
        continue;
      }
      last_t_us = t;
      sink.sample(seq, t, v);
    }
    return true;
  }
};

}  // namespace spindown
