// FitterCore: messages in (SAMPLE, CONFIG), the bench table and its admission, the stream checks
// and the per-sample path into the run detector.
#include "spindown/fitter_core.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <fmt/format.h>
#include <limits>
#include <regex>

#include "spindown/fit_message.hpp"
#include "spindown/lcm_channels.hpp"
#include "spindown/lcm_log_reader.hpp"
#include "spindown/short_string_equal.hpp"
#include "spindown/message_decode.hpp"
#include "spindown/text_support.hpp"

#include "fitter_bench.hpp"

namespace spindown {

FitterCore::FitterCore(FitterOptions options, FitterSink& sink)
    : opt_(std::move(options)), sink_(sink), gate_(opt_.gate), bench_filter_(opt_.bench_regex) {}

FitterCore::~FitterCore() = default;

void FitterCore::error(std::string text, std::int64_t utime) {
  sink_.problem(text);
  last_error_ = std::move(text);
  last_error_utime_ = utime;
}

std::vector<std::string> FitterCore::benches() const {
  std::vector<const Bench*> order;
  for (const auto& [id, b] : benches_) order.push_back(b.get());
  std::sort(order.begin(), order.end(), [](const Bench* a, const Bench* b) { return a->arrival < b->arrival; });
  std::vector<std::string> ids;
  for (const Bench* b : order) ids.push_back(b->id);
  return ids;
}

inline FitterCore::Bench* FitterCore::bench_for(std::string_view id, std::int64_t recv_utime, std::string_view kind) {
  ++activity_;
  // Nearly always a bench already held, found by its cache slot without the map.
  if (Bench* cached = bench_cache_.slot(id); cached && short_string_equal(cached->id, id)) {
    cached->last_active = activity_;
    return cached;
  }
  return find_bench(id, recv_utime, kind);
}

FitterCore::Bench* FitterCore::find_bench(std::string_view id, std::int64_t recv_utime, std::string_view kind) {
  if (auto it = benches_.find(id); it != benches_.end()) {
    Bench* found = it->second.get();
    found->last_active = activity_;
    bench_cache_.slot(id) = found;
    return found;
  }
  std::string why;
  if (!is_valid_bench_id(id, &why)) {
    ++counters_.invalid_bench;
    error(fmt::format("SPINDOWN.{}.{}: {}; message ignored", id, kind, why), recv_utime);
    return nullptr;
  }
  if (!std::regex_match(id.begin(), id.end(), bench_filter_)) {
    ++counters_.filtered;
    return nullptr;
  }
  if (!admit(id, recv_utime, kind)) return nullptr;
  auto b = std::make_unique<Bench>(std::string(id), opt_.runs, opt_.stream);
  b->last_active = activity_;
  b->arrival = ++arrivals_;
  Bench* p = b.get();
  benches_.emplace(p->id, std::move(b));
  bench_cache_.slot(id) = p;
  return p;
}

bool FitterCore::admit(std::string_view id, std::int64_t recv_utime, std::string_view kind) {
  // The admission bucket: max_benches at once (a lab starting), then admit_rate_hz.
  const double capacity = double(opt_.max_benches);
  if (admit_tokens_ < 0) {
    admit_tokens_ = capacity;
  } else if (recv_utime > admit_utime_) {
    admit_tokens_ = std::min(capacity, admit_tokens_ + 1e-6 * double(recv_utime - admit_utime_) * opt_.admit_rate_hz);
  }
  admit_utime_ = std::max(admit_utime_, recv_utime);
  auto victim = benches_.end();
  if (benches_.size() >= opt_.max_benches) {
    for (auto it = benches_.begin(); it != benches_.end(); ++it)
      if (it->second->open_state == 0 && (victim == benches_.end() || it->second->last_active < victim->second->last_active))
        victim = it;
  }
  const bool full = benches_.size() >= opt_.max_benches && victim == benches_.end();
  if (full || admit_tokens_ < 1) {
    ++counters_.benches_refused;
    error(fmt::format("SPINDOWN.{}.{}: new bench ids refused: {} so far ({}); a flood of bench ids?", id, kind,
                      counters_.benches_refused,
                      full ? fmt::format("all {} places hold a run in progress", opt_.max_benches)
                           : fmt::format("more than {:g} new benches per second", opt_.admit_rate_hz)),
          recv_utime);
    return false;
  }
  admit_tokens_ -= 1;
  if (victim != benches_.end()) {
    Bench& v = *victim->second;
    ++counters_.dropped_benches;
    error(fmt::format("SPINDOWN.{}.{}: bench {} is new and {} benches are held (max_benches): least recently "
                      "active bench {} (no run in progress) evicted",
                      id, kind, id, benches_.size(), v.id),
          recv_utime);
    bench_cache_.forget(&v);
    std::replace(bench_by_channel_.begin(), bench_by_channel_.end(), &v, static_cast<Bench*>(nullptr));
    benches_.erase(victim);
  }
  return true;
}

void FitterCore::on_message(std::string_view channel, const void* data, std::int64_t size, std::int64_t recv_utime) {
  on_message(channel, data, size, recv_utime, recv_utime);
}

void FitterCore::on_message(std::string_view channel, const void* data, std::int64_t size, std::int64_t wall_utime,
                            std::int64_t recv_utime) {
  ++counters_.messages;
  const auto parts = split_channel(channel);
  const auto kind = parts ? channel_kind(parts->suffix) : std::nullopt;
  if (kind != ChannelKind::sample && kind != ChannelKind::config) {
    ++counters_.other_channels;
    return;
  }
  const std::string_view bench = parts->bench;
  std::string why;
  if (!is_valid_bench_id(bench, &why)) {
    ++counters_.invalid_bench;
    error(fmt::format("{}: {}; message ignored", channel, why), recv_utime);
    return;
  }
  if (size < 0 || (size > 0 && data == nullptr)) {
    ++counters_.decode_errors;
    error(fmt::format("{}: no payload", channel), recv_utime);
    return;
  }
  if (kind == ChannelKind::sample) {
    SamplesView msg;
    if (!view_samples_message(msg, data, size, &why)) {
      ++counters_.decode_errors;
      error(fmt::format("{}: {}; message skipped", channel, why), recv_utime);
      return;
    }
    if (!admit_samples(channel, msg, data, size, wall_utime, recv_utime)) return;
    on_samples(bench, msg, recv_utime);
  } else {
    if (!admit(channel, data, size, wall_utime, recv_utime)) return;
    config_t msg{};
    if (!decode_message(msg, data, size, &why)) {
      ++counters_.decode_errors;
      error(fmt::format("{}: {}; message skipped", channel, why), recv_utime);
      return;
    }
    on_config(bench, msg, recv_utime);
  }
}

bool FitterCore::admit(std::string_view channel, const void* data, std::int64_t size, std::int64_t wall_utime,
                       std::int64_t recv_utime) {
  const GateResult g = gate_.check(channel, data, size, wall_utime);
  switch (g.verdict) {
    case GateVerdict::accepted:
    case GateVerdict::undecodable: return true;  // the decoder names what is wrong
    case GateVerdict::other_lab: ++counters_.other_lab; break;
    case GateVerdict::not_signed: ++counters_.unsigned_messages; break;
    case GateVerdict::other_key:
    case GateVerdict::bad_signature: ++counters_.bad_signatures; break;
    case GateVerdict::replayed:
    case GateVerdict::outside_window: ++counters_.replays; break;
  }
  sink_.notice(gate_verdict_name(g.verdict), channel, g.text);
  error(g.text, recv_utime);
  // Samples of this lab that arrive and are refused (unsigned, another key, a replay) are not
  // silence: the bench's run waits (poll()). Another lab's bench of the same name is not this one.
  if (const auto parts = split_channel(channel);
      g.verdict != GateVerdict::other_lab && parts && channel_kind(parts->suffix) == ChannelKind::sample)
    if (auto it = benches_.find(parts->bench); it != benches_.end()) {
      it->second->last_refused_utime = recv_utime;
      it->second->last_refused = g.text;
    }
  return false;
}

void FitterCore::on_config(std::string_view bench, const config_t& msg, std::int64_t recv_utime) {
  ++counters_.config_messages;
  Bench* b = bench_for(bench, recv_utime, "CONFIG");
  if (!b) return;
  if (msg.bench != b->id) {
    ++counters_.bench_mismatch;
    error(fmt::format("SPINDOWN.{}.CONFIG: message names bench '{}'; the channel's bench is used", b->id,
                      text::escape_invalid_utf8(msg.bench.substr(0, 40))),
          recv_utime);
  }
  std::string why;
  std::optional<BenchParams> params = bench_params_from_config(msg, &why);
  if (!params) {
    ++counters_.bad_configs;
    error(fmt::format("SPINDOWN.{}.CONFIG: {}; not used", b->id, why), recv_utime);
  }
  // Another source's CONFIG is kept for when that source takes over the stream, never used for
  // the stream's own samples (two sources at once: the second's J and K_b are not the first's).
  const auto session = static_cast<std::uint64_t>(msg.source_session);
  if (b->stream.have_source && (session != b->stream.session || msg.source_host != b->stream.host)) {
    auto it = std::find_if(b->other_configs.begin(), b->other_configs.end(), [&](const Bench::OtherConfig& c) {
      return c.session == session && c.host == msg.source_host;
    });
    if (it == b->other_configs.end()) {
      if (b->other_configs.size() >= 4) b->other_configs.erase(b->other_configs.begin());
      b->other_configs.push_back({session, msg.source_host, {}, {}});
      it = b->other_configs.end() - 1;
    }
    it->params = params;
    it->problem = params ? std::string() : why;
    return;
  }
  if (params) {
    b->config = *params;
    b->config_problem.clear();
  } else {
    b->config_problem = why;
  }
}

void FitterCore::on_samples(std::string_view bench, const samples_t& m, std::int64_t recv_utime) {
  ++counters_.sample_messages;
  Bench* bp = bench_for(bench, recv_utime, "SAMPLE");
  if (!bp) return;
  const std::size_t n = std::min<std::size_t>(static_cast<std::size_t>(std::max(m.n, 0)),
                                              std::min({m.device_time_us.size(), m.value.size()}));
  if (m.n < 0 || n != static_cast<std::size_t>(m.n)) {
    ++counters_.decode_errors;
    error(fmt::format("{}: message at seq {} says n = {} but carries {} times and {} values; skipped", bp->channel,
                      m.seq, m.n, m.device_time_us.size(), m.value.size()),
          recv_utime);
    return;
  }
  take_samples(*bp, m, n, recv_utime);
}

void FitterCore::on_samples(std::string_view bench, const SamplesView& m, std::int64_t recv_utime) {
  on_samples(-1, bench, m, recv_utime);
}

// One flat function per message at one sample per message (refit): the bench by its channel's
// number, the checks and the push inlined, so only the detector is a call.
void FitterCore::on_samples(std::int32_t channel_id, std::string_view bench, const SamplesView& m,
                            std::int64_t recv_utime) {
  ++counters_.sample_messages;
  // A negative id wraps to a huge index: one comparison covers both ends.
  Bench* bp = static_cast<std::uint32_t>(channel_id) < bench_by_channel_.size()
                  ? bench_by_channel_[static_cast<std::uint32_t>(channel_id)]
                  : nullptr;
  if (bp) {  // bench_for()'s bookkeeping for a bench it would find in its cache
    bp->last_active = ++activity_;
  } else {
    bp = bench_for_channel(channel_id, bench, recv_utime);
    if (!bp) return;
  }
  take_samples(*bp, m, static_cast<std::size_t>(m.n), recv_utime);  // n checked against the bytes
}

FitterCore::Bench* FitterCore::bench_for_channel(std::int32_t channel_id, std::string_view bench,
                                                 std::int64_t recv_utime) {
  Bench* b = bench_for(bench, recv_utime, "SAMPLE");
  if (b && channel_id >= 0 && channel_id < max_channel_ids) {
    const auto slot = static_cast<std::size_t>(channel_id);
    if (slot >= bench_by_channel_.size()) bench_by_channel_.resize(slot + 1, nullptr);
    bench_by_channel_[slot] = b;
  }
  return b;
}

// The per-bench stream's words become the core's counters and errors; its samples go to the
// detector.
struct FitterCore::StreamSink {
  FitterCore& core;
  Bench& b;
  std::int64_t recv_utime;
  void problem(SampleProblem kind, std::int64_t count, std::string text) {
    FitterCounters& c = core.counters_;
    switch (kind) {
      case SampleProblem::unknown_quantity:
      case SampleProblem::quantity_change: ++c.quantity_errors; break;
      case SampleProblem::samples_lost: ++c.seq_gaps, c.samples_lost += count; break;
      case SampleProblem::repeated: c.duplicates += count; break;
      case SampleProblem::late: c.late_samples += count; break;
      case SampleProblem::sequence_restart: ++c.seq_restarts; return;  // the clock's restart says it
      case SampleProblem::clock_restart:  // the detector says it when it closes the run
        ++c.clock_restarts;
        b.pending_restart = true;
        return;
      case SampleProblem::new_source:  // a restart too, with its own reason
        ++c.new_sources;
        b.pending_restart = true;
        b.pending_new_source = text;
        core.sink_.notice("new source", b.channel, b.channel + ": " + text);
        break;
      case SampleProblem::two_sources: {
        ++c.two_sources;
        std::string named = b.channel + " " + text;  // "SPINDOWN.b.SAMPLE has two sources: …"
        core.sink_.notice("two sources", b.channel, named);
        core.error(std::move(named), recv_utime);
        return;
      }
      case SampleProblem::other_source: c.other_source_samples += count; break;
      case SampleProblem::jump:
        ++c.seq_jumps, c.seq_jump_samples += count;
        core.sink_.notice("jump", b.channel, b.channel + ": " + text);
        break;
      case SampleProblem::bad_value: ++c.nan_values; break;
      case SampleProblem::time_backwards: ++c.time_backwards; break;
    }
    core.error(b.channel + ": " + text, recv_utime);
  }
  [[gnu::always_inline]] void sample(std::int64_t seq, std::int64_t t_us, double v) {
    core.push_sample(b, seq, static_cast<double>(t_us) / 1e6, v, recv_utime);
  }
};

void FitterCore::flush_stream(Bench& b, std::int64_t utime) { b.stream.flush(StreamSink{*this, b, utime}); }
void FitterCore::expire_stream(Bench& b, std::int64_t utime) { b.stream.expire(utime, StreamSink{*this, b, utime}); }

// Inlined into each on_samples(): at one sample per message a call's register saves and
// argument moves cost as much as the checks.
template <class Message>
[[gnu::always_inline]] inline void FitterCore::take_samples(Bench& b, const Message& m, std::size_t n,
                                                             std::int64_t recv_utime) {
  const std::string& ch = b.channel;

  // Rate cap first: a flood costs one comparison per message.
  if (opt_.max_rate_hz > 0) {
    const double capacity = opt_.max_rate_hz * opt_.burst_s;
    if (!b.bucket_started) {
      b.bucket_started = true;
      b.tokens = capacity;
      b.tokens_utime = recv_utime;
    } else if (recv_utime > b.tokens_utime) {
      b.tokens = std::min(capacity, b.tokens + 1e-6 * double(recv_utime - b.tokens_utime) * opt_.max_rate_hz);
      b.tokens_utime = recv_utime;
    }
    if (double(n) > b.tokens) {
      ++counters_.flood_messages;
      counters_.flood_drops += static_cast<std::int64_t>(n);
      error(fmt::format("{}: more than {:g} samples/s: message of {} samples at seq {} dropped (rate cap)", ch,
                        opt_.max_rate_hz, n, m.seq),
            recv_utime);
      return;
    }
    b.tokens -= double(n);
  }
  b.last_sample_utime = recv_utime;

  if (!short_string_equal(m.bench, b.id)) {
    ++counters_.bench_mismatch;
    error(fmt::format("{}: message names bench '{}'; the channel's bench is used", ch,
                      text::escape_invalid_utf8(m.bench.substr(0, 40))),
          recv_utime);
  }
  b.stream.take(m, n, recv_utime, StreamSink{*this, b, recv_utime});
}

void FitterCore::restart_clock(Bench& b, std::int64_t recv_utime) {
  b.pending_restart = false;
  const std::string new_source = std::move(b.pending_new_source);
  b.pending_new_source.clear();
  // find_runs() restarts the detector only between samples, never before the first one.
  if (b.detector.samples_seen() > 0) {
    if (new_source.empty())
      b.detector.clock_restart();
    else
      b.detector.new_source(new_source);
    handle_events(b, recv_utime);  // the old stream's run is closed and fitted with its own J, K_b
    trim_mirror(b);
  }
  if (!new_source.empty()) {  // then the new source's own CONFIG, when it sent one before taking over
    auto it = std::find_if(b.other_configs.begin(), b.other_configs.end(), [&](const Bench::OtherConfig& c) {
      return c.session == b.stream.session && c.host == b.stream.host;
    });
    if (it != b.other_configs.end()) {
      if (it->params) b.config = it->params;
      b.config_problem = it->problem;
      b.other_configs.erase(it);
    }
  }
}

// Inlined into the per-sample loop (not left to the compiler, which kept it a call): everything
// rare is a call.
[[gnu::always_inline]] inline void FitterCore::push_sample(Bench& b, std::int64_t seq, double t_s, double value,
                                                           std::int64_t recv_utime) {
  if (b.pending_restart) restart_clock(b, recv_utime);
  if (!b.sampled) [[unlikely]] {  // its first sample: one flag on the hot path, not a call
    b.sampled = true;
    b.detector.set_quantity(b.stream.quantity);
    if (seq > 0) b.detector.joined_stream();  // the bridge's stream began before this fitter heard it
  }
  ++counters_.samples;
  b.mirror.push_back({t_s, value, seq});
  b.lowest_reading = std::min(b.lowest_reading, value);  // a NaN reading leaves it as it was
  try {
    b.detector.push(t_s, value);
    if (b.detector.has_events()) handle_events(b, recv_utime);
  } catch (const std::exception& e) {  // never let one bench's trouble stop the others
    internal_error(b, seq, e, recv_utime);
  }
  if (b.open_state == 2 && b.detector.state() == RunDetector::State::coasting) retract_stop(b, recv_utime);
  trim_mirror(b);
}

void FitterCore::internal_error(const Bench& b, std::int64_t seq, const std::exception& e, std::int64_t recv_utime) {
  ++counters_.internal_errors;
  error(fmt::format("{}: internal error at seq {}: {}", b.channel, seq, e.what()), recv_utime);
}

// A provisional stop the detector took back: the run is coasting again.
void FitterCore::retract_stop(Bench& b, std::int64_t recv_utime) {
  b.open_run.stopped = false;
  b.open_run.t_stop_s = std::numeric_limits<double>::quiet_NaN();
  publish_run(b, b.open_run, run_t::STATE_COASTING, "standstill retracted: the reading kept falling", recv_utime);
  b.open_state = 1;
}

}  // namespace spindown
