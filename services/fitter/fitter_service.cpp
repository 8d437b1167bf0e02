#include "fitter_service.hpp"

#include <chrono>
#include <deque>
#include <utility>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <unistd.h>

#include <spindown/status_t.hpp>

#include "spindown/clock.hpp"
#include "spindown/explain_message.hpp"
#include "spindown/fit_message.hpp"
#include "spindown/host_name.hpp"
#include "spindown/lcm_channels.hpp"
#include "spindown/lcm_status.hpp"
#include "spindown/loop_watchdog.hpp"
#include "spindown/udp_socket_drops.hpp"

namespace spindown {

namespace {

// SPINDOWN\.(<bench regex>)\.(SAMPLE|CONFIG): LCM anchors the channel regex at both ends.
std::string subscription_regex(const std::string& bench_regex) {
  return fmt::format("SPINDOWN\\.({})\\.(SAMPLE|CONFIG)", bench_regex);
}

}  // namespace

FitterService::FitterService(FitterServiceOptions options)
    : opt_(std::move(options)),
      stamp_(this_process_identity(opt_.lab.lab, opt_.lcm_url), opt_.lab.key),
      loop_(opt_.lcm_url),
      core_(opt_.core, *this),
      status_channel_(channel_name(opt_.instance, ChannelKind::status)),
      instances_("fitter", opt_.instance),
      host_(host_name()),
      queue_({.max_messages = opt_.max_queue_messages,
              .max_bytes = opt_.max_queue_bytes,
              .max_message_bytes = opt_.max_queue_bytes}) {}

FitterService::~FitterService() {
  queue_.close();
  if (worker_.joinable()) worker_.join();
}

void FitterService::run_changed(const run_t& run) {
  const std::string channel = channel_name(run.bench, ChannelKind::run);
  publish_.sent(loop_.publish(channel, run), channel, wall_us());
  if (opt_.verbose)
    fmt::print(stderr, "spindown-fitter: {} run {} {}: {}\n", run.bench, run.run, run_state_name(run.state), run.note);
}

void FitterService::fit_ready(const FitResult& r) {
  FitProvenance about;
  about.bench = r.bench;
  about.bench_source = r.bench_source;
  about.first_seq = r.first_seq;
  about.last_seq = r.last_seq;
  const std::int64_t now = wall_us();
  about.latency_s = 1e-6 * double(steady_wall_us() - r.detected_utime);  // the core's times never step
  about.health = r.health;
  about.bridge_host = r.bridge_host;
  about.bridge_session = r.bridge_session;
  const fit_t msg = to_fit_message(r.fit, about, now);
  const std::string channel = channel_name(r.bench, ChannelKind::fit);
  publish_.sent(loop_.publish(channel, msg), channel, now);
  last_latency_s_ = about.latency_s;
  max_latency_s_ = std::max(max_latency_s_, about.latency_s);
  last_fit_s_ = r.fit_seconds;
  if (opt_.verbose) {
    fmt::print(stderr, "spindown-fitter: {} run {} fitted: best {} ({} samples, fit {:.1f} ms, latency {:.1f} ms)\n",
               r.bench, r.fit.run.number, r.fit.best.empty() ? "none" : r.fit.best, msg.samples, 1e3 * r.fit_seconds,
               1e3 * about.latency_s);
    if (r.health)
      fmt::print(stderr, "spindown-fitter: {} run {} health: {} — {}\n", r.bench, r.fit.run.number,
                 health_level_name(r.health->level), r.health->reason);
  }
}

// The discrepancy workflow (design §6), run by the core on the FIT's own window (FitResult::explain).
void FitterService::explain_ready(const FitResult& r) {
  if (!r.explain) return;
  const ExplainResult& ex = *r.explain;
  const Run& run = ex.run;
  if (!ex.ok) ++explain_failures_;
  const explain_t msg = to_explain_message(ex, r.bench, wall_us());
  const std::string channel = channel_name(r.bench, ChannelKind::explain);
  publish_.sent(loop_.publish(channel, msg), channel, wall_us());
  ++explains_;
  if (opt_.verbose)
    fmt::print(stderr, "spindown-fitter: {} run {} explained: {} -> {} (RMSE {:.4g} -> {:.4g})\n", r.bench,
               run.number, fmt::join(msg.base, "+"), fmt::join(msg.final_effects, "+"), msg.rmse_base, msg.rmse_final);
}

void FitterService::diagnostic(const std::string& bench, const Diagnostic& d) {
  // What changes a result (a run cut short, a coast joined mid-way) is said without -v.
  if (opt_.verbose || d.severity != Diagnostic::Severity::note)
    fmt::print(stderr, "spindown-fitter: {}: {}\n", bench, d.to_string());
}

// Said on stderr at once, at most once a minute per kind and channel (another lab's traffic or a
// forger would otherwise flood the journal); the counts are in the heartbeat.
void FitterService::notice(std::string_view kind, std::string_view channel, const std::string& text) {
  constexpr std::int64_t every_us = 60'000'000;
  const std::int64_t now = wall_us();
  std::string key = fmt::format("{} {}", kind, channel);
  auto it = said_.find(key);
  if (it == said_.end()) {
    if (said_.size() >= 1000) said_.clear();  // bounded: a flood of channel names starts afresh
    it = said_.emplace(std::move(key), Said{}).first;
  } else if (now - it->second.at_us < every_us) {
    ++it->second.quiet;
    return;
  }
  const std::int64_t quiet = std::exchange(it->second.quiet, 0);
  it->second.at_us = now;
  fmt::print(stderr, "spindown-fitter: {}{}\n", text,
             quiet > 0 ? fmt::format(" ({} more of these in the last minute not shown)", quiet) : std::string());
}

void FitterService::publish_status(std::int64_t now_us, const char* state) {
  status_t s = core_.make_status(now_us, opt_.instance, host_, static_cast<std::int32_t>(::getpid()), state,
                                 1e-6 * double(now_us - start_us_));
  const MessageQueueCounts q = queue_.counts();
  const std::int64_t samples = core_.counters().samples;
  if (last_rate_us_ > 0 && now_us > last_rate_us_)
    rate_hz_ = double(samples - last_samples_) / (1e-6 * double(now_us - last_rate_us_));
  last_rate_us_ = now_us;
  last_samples_ = samples;
  const std::pair<const char*, std::int64_t> counters[] = {
      {"queue_drops", q.full_drops},
      {"oversize_drops", q.oversize_drops},
      {"publish_failures", publish_.failures()},
      {"heartbeats_unheard", publish_.unheard_heartbeats()},
      {"stalls", stalls_},
      {"explains", explains_},
      {"explain_failures", explain_failures_},
  };
  add_counters(s, counters);
  // Datagrams the kernel dropped on the fitter's own sockets (a full receive buffer): lost
  // before LCM read them, so only sequence gaps would show them otherwise.
  if (const std::int64_t kernel = own_udp_drop_count(); kernel >= 0) {
    const std::pair<const char*, std::int64_t> udp[] = {{"udp_drops", kernel}};
    add_counters(s, udp);
  }
  const std::pair<const char*, double> gauges[] = {
      {"sample_rate_hz", rate_hz_},               {"queue_depth", double(q.depth)},
      {"queue_high_water", double(q.high_water)}, {"last_latency_s", last_latency_s_},
      {"max_latency_s", max_latency_s_},      {"last_fit_s", last_fit_s_},
  };
  add_gauges(s, gauges);
  if (s.last_error.empty() && q.oversize_drops > 0)
    s.last_error = fmt::format("{} messages dropped: larger than the receive queue's limit of {} bytes (last: {} "
                               "bytes on {}; a forged LCM fragment header claims any size)",
                               q.oversize_drops, opt_.max_queue_bytes, q.last_oversize_bytes, q.last_oversize_channel);
  if (s.last_error.empty() && publish_.failures() + publish_.unheard_heartbeats() > 0) {
    s.last_error = publish_.last_error();
    s.last_error_utime = publish_.last_error_utime();
  }
  if (s.last_error.empty() && q.full_drops > 0)
    s.last_error = fmt::format("{} messages dropped: receive queue full", q.full_drops);
  // Another fitter with this name alive now: said in every heartbeat while it lasts.
  s.counter_name.emplace_back("instance_collisions");
  s.counter_value.push_back(instances_.collisions());
  s.ncounters = static_cast<std::int32_t>(s.counter_name.size());
  if (instances_.alive(now_us).size() > 1 && !collision_.empty()) s.last_error = collision_;
  s.start_utime = stamp_.identity().start_utime;
  const std::string channel = channel_name(opt_.instance, ChannelKind::status);
  publish_.heartbeat_sent(loop_.publish(channel, s), channel, s.utime, wall_us(), !draining_);
}

bool FitterService::nothing_waiting() const {
  return queue_.counts().depth == 0 && !loop_.messages_waiting() && own_udp_queued_bytes() <= 0;
}

void FitterService::worker() {
  using std::chrono::steady_clock;
  const auto period = std::chrono::microseconds(static_cast<std::int64_t>(opt_.status_period_s * 1e6));
  auto next_status = steady_clock::now();
  constexpr auto poll_wait = std::chrono::microseconds(FitterCore::poll_period_us);
  // A round that starts this long after the one before was a stall (SIGSTOP, a suspended VM, a
  // starved machine): what arrived meanwhile waits in LCM's queue and in the socket, and LCM
  // stamps it with the time it reads it, after the stall. No bench is judged silent until that
  // backlog has been handled (nothing waits any more), so a frozen fitter never takes its own
  // backlog for silence.
  constexpr auto stall_after = poll_wait + std::chrono::seconds(1);
  constexpr std::int64_t drain_at_most_us = 5'000'000;  // then live traffic is flowing anyway
  std::deque<QueuedMessage> batch;
  std::int64_t next_poll = 0;
  auto last_round = steady_clock::now(), next_drain_check = last_round;
  std::int64_t drain_from_us = 0, drained_messages = 0;
  for (;;) {
    worker_alive_ns_.store(monotonic_ns(), std::memory_order_relaxed);
    // Closed (the service stops): this batch is the last.
    const bool open = queue_.take_all(batch, std::min(next_status, steady_clock::now() + poll_wait));
    const auto round = steady_clock::now();
    if (round - last_round > stall_after) {
      ++stalls_;
      const double stalled_s = std::chrono::duration<double>(round - last_round).count();
      fmt::print(stderr,
                 "spindown-fitter: no message handled for {:.1f} s (the fitter was stopped, suspended, starved or "
                 "busy): no bench is judged silent until what arrived meanwhile has been handled\n",
                 stalled_s);
      draining_ = true;
      drain_from_us = steady_wall_us();
      drained_messages = 0;
    }
    last_round = round;
    for (const QueuedMessage& m : batch) {
      if (m.channel == status_channel_)
        own_channel_status(m);
      else
        core_.on_message(m.channel, m.data.data(), static_cast<std::int64_t>(m.data.size()), m.recv_utime,
                         m.host_utime);
    }
    // Benches gone silent mid-coast, by the time of the traffic just handled (as refit does with
    // a log); by the clock only when none came and nothing received still waits. The core's times
    // never step (clock.hpp steady_wall_us): a lab PC's wall clock stepped by NTP is not silence.
    const bool idle = batch.empty();
    const std::int64_t now = idle ? steady_wall_us() : batch.back().host_utime;
    drained_messages += static_cast<std::int64_t>(batch.size());
    batch.clear();
    if (draining_ && round >= next_drain_check) {
      next_drain_check = round + std::chrono::milliseconds(100);
      if (nothing_waiting() || now - drain_from_us > drain_at_most_us) {
        draining_ = false;
        fmt::print(stderr, "spindown-fitter: the backlog is handled ({} messages); silence is judged again\n",
                   drained_messages);
      }
    }
    if (!draining_ && now >= next_poll && (!idle || !core_.silence_due(now) || nothing_waiting())) {
      core_.poll(now);
      next_poll = now + FitterCore::poll_period_us;
    }
    if (steady_clock::now() >= next_status) {
      publish_status(wall_us(), "running");
      next_status += period;
      if (next_status < steady_clock::now()) next_status = steady_clock::now() + period;
    }
    if (!open) break;
  }
}

void FitterService::own_channel_status(const QueuedMessage& m) {
  const auto size = static_cast<std::int64_t>(m.data.size());
  if (!core_.admit(m.channel, m.data.data(), size, m.recv_utime, m.host_utime)) return;  // another lab's, unsigned, …
  status_t s{};
  if (!decode_message(s, m.data.data(), size)) return;
  if (auto text = instances_.heard(s, m.recv_utime)) {
    collision_ = *text;
    fmt::print(stderr, "spindown-fitter: {}\n", collision_);
  }
}

int FitterService::run(const StopSignals& stop) {
  start_us_ = wall_us();
  loop_.set_stamp(&stamp_);
  instances_.set_own({host_, static_cast<std::int32_t>(::getpid()), stamp_.identity().session,
                      stamp_.identity().start_utime, 0, true});
  // The handler only copies into the service's queue, but LCM's own default of 30 queued
  // messages drops silently in a burst (design §7).
  const bool subscribed = loop_.subscribe_raw(
      subscription_regex(opt_.core.bench_regex),
      [this](const LcmMessage& m) { queue_.offer(m.recv_utime, m.channel, m.data, static_cast<std::size_t>(m.size)); },
      {.queue_capacity = 100000});
  // Its own heartbeat channel too: another fitter started with the same --instance is heard there.
  const bool own_channel = loop_.subscribe_raw(
      status_channel_,
      [this](const LcmMessage& m) { queue_.offer(m.recv_utime, m.channel, m.data, static_cast<std::size_t>(m.size)); },
      {.queue_capacity = 1000});
  if (!subscribed || !own_channel) {
    fmt::print(stderr, "spindown-fitter: cannot subscribe (bad --bench regex?)\n");
    return 2;
  }
  // Its own heartbeats, back through the network stack: the check that what it publishes
  // goes where the lab listens (PublishHealth).
  const std::int32_t pid = static_cast<std::int32_t>(::getpid());
  loop_.subscribe<status_t>(channel_name(opt_.instance, ChannelKind::status), [this, pid](const status_t& st) {
    if (st.service == "fitter" && st.pid == pid && st.host == host_) publish_.echoed(st.utime);
  });
  worker_alive_ns_.store(monotonic_ns());
  worker_ = std::thread([this] { worker(); });
  feed_watchdog_from_loop(loop_, notify_, [this](std::int64_t now_ns) {
    return now_ns - worker_alive_ns_.load(std::memory_order_relaxed) < notify_.stuck_after_ns();
  });
  notify_.ready(fmt::format("fitting benches matching '{}'", opt_.core.bench_regex));
  if (loop_.run({.stop = &stop}) == LcmLoopEnd::failed)
    fmt::print(stderr, "spindown-fitter: LCM keeps failing to receive; stopping\n");
  notify_.stopping("stopping: finishing the queued messages");
  loop_.unsubscribe_all();
  queue_.close();
  worker_.join();
  // Runs still open are closed as abandoned (not fitted: a restarted fitter takes the rest of
  // the coast as partial), so no client shows them coasting for ever; then the last heartbeat.
  core_.abandon_open_runs(steady_wall_us(), "fitter stopping: the run was not finished; a fitter started again takes the "
                                     "rest of its coast as a partial run");
  publish_status(wall_us(), "stopping");
  const FitterCounters& c = core_.counters();
  const MessageQueueCounts q = queue_.counts();
  fmt::print(stderr,
             "spindown-fitter: stopped: {} benches, {} samples, {} runs, {} fits, {} decode errors, {} sequence gaps, "
             "{} duplicates, {} NaN values, {} time backwards, {} benches evicted, {} benches refused, {} partial runs, "
             "{} silent benches, {} runs abandoned, {} flood drops, {} queue drops, {} oversize drops, {} publish "
             "failures, {} datagrams dropped by the kernel on the fitter's socket\n",
             core_.bench_count(), c.samples, c.runs, c.fits, c.decode_errors, c.seq_gaps, c.duplicates, c.nan_values,
             c.time_backwards, c.dropped_benches, c.benches_refused, c.partial_runs, c.silent_benches,
             c.runs_abandoned, c.flood_drops, q.full_drops, q.oversize_drops, publish_.failures(),
             own_udp_drop_count());
  fmt::print(stderr,
             "spindown-fitter: sources: {} new sources, {} two sources at once ({} samples refused), {} far jumps "
             "dropped ({} samples); not used: {} of another lab, {} unsigned, {} badly signed, {} replayed; {} "
             "instance collisions\n",
             c.new_sources, c.two_sources, c.other_source_samples, c.seq_jumps, c.seq_jump_samples, c.other_lab,
             c.unsigned_messages, c.bad_signatures, c.replays, instances_.collisions());
  return 0;
}

}  // namespace spindown
