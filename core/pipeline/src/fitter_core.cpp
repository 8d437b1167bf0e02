#include "spindown/fitter_core.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <fmt/format.h>
#include <limits>

#include "spindown/fit_message.hpp"
#include "spindown/lcm_channels.hpp"
#include "spindown/lcm_log_reader.hpp"
#include "spindown/short_string_equal.hpp"
#include "spindown/message_decode.hpp"
#include "spindown/text_support.hpp"

namespace spindown {

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

bool FitterOptions::is_valid(std::string* why) const {
  auto fail = [&](std::string text) {
    if (why) *why = std::move(text);
    return false;
  };
  std::string inner;
  if (!runs.is_valid(&inner)) return fail("run options: " + inner);
  FitOptions fo;
  fo.bench = default_bench;
  fo.models = models;
  if (!fo.is_valid(&inner)) return fail("fit options: " + inner);
  if (max_benches < 1) return fail("max_benches must be at least 1");
  if (!(std::isfinite(admit_rate_hz) && admit_rate_hz > 0))
    return fail(fmt::format("admit_rate_hz must be > 0 (got {})", admit_rate_hz));
  if (!(silent_s > 0)) return fail(fmt::format("silent_s must be > 0 (got {})", silent_s));
  if (!(std::isfinite(max_rate_hz) && max_rate_hz >= 0))
    return fail(fmt::format("max_rate_hz must be >= 0 (got {})", max_rate_hz));
  if (!(std::isfinite(burst_s) && burst_s > 0)) return fail(fmt::format("burst_s must be > 0 (got {})", burst_s));
  try {
    std::regex re(bench_regex);
  } catch (const std::regex_error& e) {
    return fail(fmt::format("bench regex '{}' is not a valid regular expression ({})", bench_regex, e.what()));
  }
  return true;
}

// ---------------------------------------------------------------------------------------------

struct FitterCore::Bench {
  struct Sample {
    double t_s;
    double value;
    std::int64_t seq;
  };
  // The detector's buffer again, with sequence numbers, oldest first: a ring that grows to the
  // largest buffer seen (at most RunOptions::max_buffer + 1) and allocates no more after that.
  class Mirror {
   public:
    std::size_t size() const { return count_; }
    const Sample& operator[](std::size_t i) const { return slots_[(head_ + i) & mask_]; }
    void push_back(const Sample& s) {
      if (count_ == slots_.size()) grow();
      slots_[(head_ + count_) & mask_] = s;
      ++count_;
    }
    void drop_front(std::size_t n) {
      head_ = (head_ + n) & mask_;
      count_ -= n;
    }

   private:
    void grow() {
      std::vector<Sample> bigger(std::max<std::size_t>(256, 2 * slots_.size()));
      for (std::size_t i = 0; i < count_; ++i) bigger[i] = (*this)[i];
      slots_.swap(bigger);
      head_ = 0;
      mask_ = slots_.size() - 1;
    }
    std::vector<Sample> slots_;  // size a power of two
    std::size_t head_ = 0, count_ = 0, mask_ = 0;
  };
  Bench(std::string bench_id, const RunOptions& runs)
      : id(std::move(bench_id)), channel(fmt::format("SPINDOWN.{}.SAMPLE", id)), detector(runs, channel) {}

  std::string id;
  std::string channel;
  RunDetector detector;
  Mirror mirror;  // samples of a run, with the sequence numbers a published run names
  std::uint64_t last_active = 0, arrival = 0;
  std::int64_t last_sample_utime = 0;  // host time of its last samples (poll(): silent benches)

  std::optional<BenchParams> config;
  std::string config_problem;

  SampleStream stream;  // the log reader's checks too (sample_stream.hpp), so refit == fit
  bool pending_restart = false;  // the clock restarted: tell the detector before the next sample

  // Rate cap (token bucket on host receive time).
  double tokens = 0;
  std::int64_t tokens_utime = 0;
  bool bucket_started = false;

  // The open run as last published: 0 none, 1 coasting, 2 stopped (provisional).
  int open_state = 0;
  Run open_run;

  std::size_t base() const { return detector.samples_seen() - mirror.size(); }
  const Sample* at(std::size_t index) const {
    const std::size_t b = base();
    return index >= b && index - b < mirror.size() ? &mirror[index - b] : nullptr;
  }
};

FitterCore::FitterCore(FitterOptions options, FitterSink& sink)
    : opt_(std::move(options)), sink_(sink), bench_filter_(opt_.bench_regex) {}

FitterCore::~FitterCore() = default;

void FitterCore::error(std::string text, std::int64_t utime) {
  sink_.problem(text);
  last_error_ = std::move(text);
  last_error_utime_ = utime;
}

std::size_t FitterCore::buffered_samples() const {
  std::size_t n = 0;
  for (const auto& [id, b] : benches_) n += b->detector.buffered() + b->mirror.size();
  return n;
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
  auto b = std::make_unique<Bench>(std::string(id), opt_.runs);
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
  ++counters_.messages;
  constexpr std::string_view prefix = "SPINDOWN.";
  const std::size_t dot = channel.rfind('.');
  if (!channel.starts_with(prefix) || dot == std::string_view::npos || dot < prefix.size()) {
    ++counters_.other_channels;
    return;
  }
  const std::string_view kind = channel.substr(dot + 1);
  const std::string_view bench = channel.substr(prefix.size(), dot - prefix.size());
  if (kind != "SAMPLE" && kind != "CONFIG") {
    ++counters_.other_channels;
    return;
  }
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
  if (kind == "SAMPLE") {
    SamplesView msg;
    if (!view_samples_message(msg, data, size, &why)) {
      ++counters_.decode_errors;
      error(fmt::format("{}: {}; message skipped", channel, why), recv_utime);
      return;
    }
    on_samples(bench, msg, recv_utime);
  } else {
    config_t msg;
    if (!decode_message(msg, data, size, &why)) {
      ++counters_.decode_errors;
      error(fmt::format("{}: {}; message skipped", channel, why), recv_utime);
      return;
    }
    on_config(bench, msg, recv_utime);
  }
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
  if (auto p = bench_params_from_config(msg, &why)) {
    b->config = *p;
    b->config_problem.clear();
  } else {
    ++counters_.bad_configs;
    b->config_problem = why;
    error(fmt::format("SPINDOWN.{}.CONFIG: {}; not used", b->id, why), recv_utime);
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
  struct Sink {
    FitterCore& core;
    Bench& b;
    std::int64_t recv_utime;
    void problem(SampleProblem kind, std::int64_t count, std::string text) {
      FitterCounters& c = core.counters_;
      switch (kind) {
        case SampleProblem::unknown_quantity:
        case SampleProblem::quantity_change: ++c.quantity_errors; break;
        case SampleProblem::samples_lost: ++c.seq_gaps, c.samples_lost += count; break;
        case SampleProblem::repeated: ++c.duplicates; break;
        case SampleProblem::sequence_restart: ++c.seq_restarts; return;  // the clock's restart says it
        case SampleProblem::clock_restart:  // the detector says it when it closes the run
          ++c.clock_restarts;
          b.pending_restart = true;
          return;
        case SampleProblem::bad_value: ++c.nan_values; break;
        case SampleProblem::time_backwards: ++c.time_backwards; break;
      }
      core.error(b.channel + ": " + text, recv_utime);
    }
    [[gnu::always_inline]] void sample(std::int64_t seq, std::int64_t t_us, double v) {
      core.push_sample(b, seq, static_cast<double>(t_us) / 1e6, v, recv_utime);
    }
  };
  b.stream.take(m, n, Sink{*this, b, recv_utime});
}

void FitterCore::restart_clock(Bench& b, std::int64_t recv_utime) {
  b.pending_restart = false;
  // find_runs() restarts the detector only between samples, never before the first one.
  if (b.detector.samples_seen() == 0) return;
  b.detector.clock_restart();
  handle_events(b, recv_utime);
  trim_mirror(b);
}

// Inlined into the per-sample loop (not left to the compiler, which kept it a call): everything
// rare is a call.
[[gnu::always_inline]] inline void FitterCore::push_sample(Bench& b, std::int64_t seq, double t_s, double value,
                                                           std::int64_t recv_utime) {
  if (b.pending_restart) restart_clock(b, recv_utime);
  ++counters_.samples;
  b.mirror.push_back({t_s, value, seq});
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

inline void FitterCore::trim_mirror(Bench& b) {
  const std::size_t keep = b.detector.buffered();
  if (b.mirror.size() > keep) b.mirror.drop_front(b.mirror.size() - keep);
}

void FitterCore::publish_run(Bench& b, const Run& run, std::int8_t state, std::string note, std::int64_t utime) {
  const Bench::Sample* first = b.at(run.cut_index);
  const std::size_t last_index = b.detector.samples_seen() > 0 ? b.detector.samples_seen() - 1 : 0;
  std::size_t end = last_index + 1;
  if (state == run_t::STATE_ABANDONED || (state == run_t::STATE_STOPPED && run.end_index > run.cut_index))
    end = std::max(run.end_index, run.cut_index + 1);
  const Bench::Sample* last = b.at(end - 1);
  const std::int64_t samples = end > run.cut_index ? std::int64_t(end - run.cut_index) : 0;
  sink_.run_changed(to_run_message(b.id, run, state, first ? first->seq : -1, last ? last->seq : -1,
                                   static_cast<std::int32_t>(samples), std::move(note), utime));
}

void FitterCore::handle_events(Bench& b, std::int64_t recv_utime) {
  for (RunEvent& e : b.detector.take_events()) {
    if (e.has_diagnostic) sink_.diagnostic(b.id, e.diagnostic);
    switch (e.kind) {
      case RunEvent::Kind::cut:
        ++counters_.runs_started;
        b.open_state = 1;
        b.open_run = e.run;
        publish_run(b, e.run, run_t::STATE_COASTING,
                    e.run.partial() ? std::string("cut not seen: joined mid-coast, a partial run from its first sample")
                                    : fmt::format("cut (lead-in: {})", e.run.lead_in),
                    recv_utime);
        break;
      case RunEvent::Kind::stop:
        b.open_state = 2;
        b.open_run = e.run;
        publish_run(b, e.run, run_t::STATE_STOPPED, "standstill: collecting the tail before fitting", recv_utime);
        break;
      case RunEvent::Kind::complete:
        b.open_state = 0;
        counters_.partial_runs += e.run.partial();
        counters_.silent_benches += e.run.end == Run::End::silent;
        fit_and_publish(b, e.run, e.has_diagnostic && !e.run.stopped ? e.diagnostic.message : std::string(),
                        recv_utime);
        break;
      case RunEvent::Kind::ignored:
        ++counters_.runs_ignored;
        b.open_state = 0;
        publish_run(b, e.run, run_t::STATE_ABANDONED, e.has_diagnostic ? e.diagnostic.message : "ignored",
                    recv_utime);
        break;
      case RunEvent::Kind::diagnostic: break;
    }
  }
}

void FitterCore::fit_and_publish(Bench& b, const Run& run, const std::string& why_unstopped, std::int64_t recv_utime) {
  ++counters_.runs;
  const Bench::Sample* first = b.at(run.cut_index);
  const Bench::Sample* last = run.end_index > run.cut_index ? b.at(run.end_index - 1) : first;
  if (!first || !last) {
    ++counters_.internal_errors;
    error(fmt::format("{}: run {} (samples {}..{}) is no longer buffered; not fitted", b.channel, run.number,
                      run.cut_index, run.end_index),
          recv_utime);
    return;
  }
  const std::string note = run.stopped ? std::string("complete: fitted")
                                       : why_unstopped.empty()
                                           ? fmt::format("closed without a stop ({}); fitted", end_name(run.end))
                                           : fmt::format("closed without a stop: {}; fitted", why_unstopped);
  publish_run(b, run, run.stopped ? run_t::STATE_STOPPED : run_t::STATE_ABANDONED, note, recv_utime);

  // The run's samples as contiguous arrays, indices relative to the cut.
  const std::size_t base = b.base();
  const std::size_t count = run.end_index > run.cut_index ? run.end_index - run.cut_index : 0;
  scratch_t_.resize(count);
  scratch_v_.resize(count);
  for (std::size_t k = 0; k < count; ++k) {
    const Bench::Sample& s = b.mirror[run.cut_index + k - base];
    scratch_t_[k] = s.t_s;
    scratch_v_[k] = s.value;
  }
  Run local = run;
  local.cut_index = 0;
  local.stop_index = run.stop_index - run.cut_index;
  local.end_index = run.end_index - run.cut_index;
  for (std::size_t& k : local.outliers) k -= run.cut_index;

  FitResult r;
  r.bench = b.id;
  r.first_seq = first->seq;
  r.last_seq = last->seq;
  r.detected_utime = recv_utime;
  FitOptions fo;
  fo.models = opt_.models;
  if (opt_.ignore_config) {
    fo.bench = opt_.default_bench;
    r.bench_source = "default (CONFIG ignored by option)";
  } else if (b.config) {
    fo.bench = *b.config;
    r.bench_source = "config";
  } else {
    fo.bench = opt_.default_bench;
    r.bench_source = b.config_problem.empty()
                         ? fmt::format("default ({}): no CONFIG received from bench {}", opt_.default_bench.inertia_source,
                                       b.id)
                         : fmt::format("default ({}): {}", opt_.default_bench.inertia_source, b.config_problem);
  }
  const auto t0 = std::chrono::steady_clock::now();
  try {
    r.fit = fit_run(scratch_t_, scratch_v_, b.stream.quantity, local, fo);
  } catch (const std::exception& e) {
    ++counters_.internal_errors;
    error(fmt::format("{}: run {}: the fit failed: {}", b.channel, run.number, e.what()), recv_utime);
    return;
  }
  r.fit_seconds = seconds_since(t0);
  r.fit.run = run;  // indices as in the bench's stream
  if (r.fit.best.empty()) {
    ++counters_.fit_failures;
    error(fmt::format("{}: run {}: no model converged", b.channel, run.number), recv_utime);
  }
  if (auto h = opt_.health.find(b.id); h != opt_.health.end()) {
    try {
      r.health = assess_health(r.fit, h->second);
    } catch (const std::exception& e) {
      ++counters_.internal_errors;
      error(fmt::format("{}: run {}: the health verdict failed: {}", b.channel, run.number, e.what()), recv_utime);
    }
  }
  r.t_s = scratch_t_;
  r.value = scratch_v_;
  ++counters_.fits;
  sink_.fit_ready(r);
}

void FitterCore::finish(std::int64_t now_utime) {
  std::vector<Bench*> order;
  for (auto& [id, b] : benches_) order.push_back(b.get());
  std::sort(order.begin(), order.end(), [](const Bench* a, const Bench* b) { return a->arrival < b->arrival; });
  for (Bench* b : order) {
    try {
      b->detector.finish();
      handle_events(*b, now_utime);
    } catch (const std::exception& e) {
      ++counters_.internal_errors;
      error(fmt::format("{}: internal error at the end: {}", b->channel, e.what()), now_utime);
    }
    trim_mirror(*b);
  }
}

void FitterCore::poll(std::int64_t now_utime) {
  const auto silent_us = static_cast<std::int64_t>(opt_.silent_s * 1e6);
  for (auto& [id, b] : benches_) {
    if (b->open_state == 0 || now_utime - b->last_sample_utime < silent_us) continue;
    try {
      b->detector.went_silent(opt_.silent_s);  // not the silence measured: live and refit say the same
      handle_events(*b, now_utime);
    } catch (const std::exception& e) {
      ++counters_.internal_errors;
      error(fmt::format("{}: internal error closing a silent bench's run: {}", b->channel, e.what()), now_utime);
    }
    trim_mirror(*b);
  }
}

status_t FitterCore::make_status(std::int64_t now_utime, std::string_view instance, std::string_view host,
                                 std::int32_t pid, std::string_view state, double uptime_s) const {
  status_t s;
  s.utime = now_utime;
  s.service = "fitter";
  s.instance = std::string(instance);
  s.host = std::string(host);
  s.pid = pid;
  s.state = std::string(state);
  s.uptime_s = uptime_s;
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
      {"duplicates", c.duplicates},       {"seq_restarts", c.seq_restarts},
      {"clock_restarts", c.clock_restarts}, {"nan_values", c.nan_values},
      {"time_backwards", c.time_backwards}, {"quantity_errors", c.quantity_errors},
      {"bad_configs", c.bad_configs},     {"dropped_benches", c.dropped_benches},
      {"benches_refused", c.benches_refused}, {"partial_runs", c.partial_runs},
      {"silent_benches", c.silent_benches},
      {"flood_drops", c.flood_drops},     {"flood_messages", c.flood_messages},
      {"internal_errors", c.internal_errors},
  };
  for (const auto& [name, value] : counters) {
    s.counter_name.emplace_back(name);
    s.counter_value.push_back(value);
  }
  s.ncounters = static_cast<std::int32_t>(s.counter_name.size());
  std::size_t coasting = 0;
  for (const auto& [id, b] : benches_) coasting += b->open_state != 0;
  const std::pair<const char*, double> gauges[] = {
      {"benches", double(benches_.size())},
      {"benches_coasting", double(coasting)},
      {"buffered_samples", double(buffered_samples())},
  };
  for (const auto& [name, value] : gauges) {
    s.gauge_name.emplace_back(name);
    s.gauge_value.push_back(value);
  }
  s.ngauges = static_cast<std::int32_t>(s.gauge_name.size());
  s.last_error = last_error_;
  s.last_error_utime = last_error_utime_;
  return s;
}

}  // namespace spindown
