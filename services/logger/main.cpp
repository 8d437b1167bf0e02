// spindown-logger: records LCM traffic (SPINDOWN.* by default) into standard LCM event logs,
// with rotation by size and time, a flush on a timer, nothing lost on SIGINT/SIGTERM, and its
// counters (events, bytes, files, drops, write errors, flushes) on SPINDOWN.logger.STATUS and
// in the logs themselves. The logic lives in spindown::EventLogWriter and spindown::LogRecorder.
#include <CLI/CLI.hpp>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <fmt/format.h>
#include <lcm/lcm-cpp.hpp>
#include <cstdio>
#include <pthread.h>

#include "spindown/event_log_writer.hpp"
#include "spindown/lcm_status.hpp"
#include "spindown/lcm_url.hpp"
#include "spindown/log_recorder.hpp"
#include "spindown/network_checks.hpp"

namespace {

std::atomic<bool> g_stop{false};
extern "C" void on_signal(int) { g_stop = true; }

std::int64_t wall_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}


// A plain C callback on lcm_subscribe: LCM 1.3.1's C++ subscribe templates trip UBSan's vptr
// check inside LCM's own header, and a raw subscription is all the logger needs.
extern "C" void on_event(const lcm_recv_buf_t* rbuf, const char* channel, void* user) {
  static_cast<spindown::LogRecorder*>(user)->offer(rbuf->recv_utime, channel, rbuf->data,
                                                   static_cast<std::int32_t>(rbuf->data_size));
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"spindown-logger: LCM traffic -> standard LCM event logs (lcm-logplayer and lcm::LogFile read them)"};
  std::string lcm_url, channels;
  spindown::EventLogWriterOptions w;
  spindown::LogRecorderOptions r;
  long recv_buf = spindown::services_recv_buf_bytes;
  bool quiet = false;
  app.add_option("--lcm-url", lcm_url, "LCM URL (default: LCM_DEFAULT_URL or LCM's default)");
  app.add_option("--channels", channels,
                 "channel regex (default SPINDOWN\\..*, or SPINDOWN\\.<bench>\\..* with --bench)");
  app.add_option("--dir", w.dir, "directory for the logs (must exist)")->capture_default_str();
  app.add_option("--prefix", w.prefix, "file name prefix: PREFIX-YYYY-MM-DD-HHMMSS[-BENCH].lcm")
      ->capture_default_str();
  app.add_option("--bench", w.bench, "bench id: in the file names, and the default channels");
  app.add_option("--rotate-size", w.rotate_size_mb, "start a new file past this many MB (1e6 bytes); 0 = never")
      ->check(CLI::Range(0.0, 1e6));
  app.add_option("--rotate-time", w.rotate_time_s, "start a new file after this many seconds; 0 = never")
      ->check(CLI::Range(0.0, 1e9));
  app.add_option("--flush-interval", r.flush_interval_s, "seconds between flushes to the kernel (data a kill -9 can lose)")
      ->capture_default_str()
      ->check(CLI::Range(0.001, 3600.0));
  app.add_flag("--fsync", w.sync_on_flush, "also fdatasync at every flush (always done at rotation and exit)");
  app.add_option("--max-event-bytes", r.max_event_bytes,
                 "larger messages are not recorded (counted as oversize_drops and named in the heartbeat)")
      ->capture_default_str();
  app.add_option("--queue", r.queue_capacity, "events queued for the writer before drops are counted")
      ->capture_default_str()
      ->check(CLI::Range(1, 10000000));
  app.add_option("--recv-buf", recv_buf, "udpm receive buffer bytes added to the URL (0 = leave the URL alone)")
      ->capture_default_str();
  app.add_option("--status-channel", w.status_channel, "channel of the heartbeat and of the status events in the logs")
      ->capture_default_str();
  app.add_option("--name", w.instance, "status_t.instance (default: the bench, else the prefix)");
  app.add_flag("-q,--quiet", quiet, "only errors on stderr");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;  // --help is 0; any bad usage is 2 (design §5)
  }

  if (channels.empty()) channels = w.bench.empty() ? "SPINDOWN\\..*" : "SPINDOWN\\." + w.bench + "\\..*";
  std::string why;
  if (!w.is_valid(&why) || !r.is_valid(&why)) {
    fmt::print(stderr, "spindown-logger: {}\n", why);
    return 2;
  }

  // Only the main thread takes SIGINT/SIGTERM (LCM's and the writer's threads inherit the
  // block), so the signal interrupts handleTimeout at once.
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  std::signal(SIGPIPE, SIG_IGN);

  const std::string url = spindown::with_receive_buffer(lcm_url, recv_buf);
  lcm::LCM lcm(url);
  if (!lcm.good()) {
    fmt::print(stderr, "spindown-logger: cannot start LCM at {}\n", url);
    return 1;
  }

  const std::int64_t start = wall_us();
  spindown::EventLogWriter writer(w, start);
  try {
    writer.open(start);
  } catch (const spindown::EventLogError& e) {
    fmt::print(stderr, "spindown-logger: {}\n", e.what());
    return 1;
  }
  const std::string first_file = writer.current_path();
  spindown::LogRecorder recorder(writer, r);
  recorder.start();

  lcm_subscription_t* sub = lcm_subscribe(lcm.getUnderlyingLCM(), channels.c_str(), on_event, &recorder);
  if (!sub) {
    fmt::print(stderr, "spindown-logger: cannot subscribe to channels '{}' (bad regex?)\n", channels);
    recorder.stop("subscribe failed");
    return 2;
  }
  // LCM 1.3.1 drops silently past a subscription's queue capacity (30 unless set): no limit
  // there, so every message LCM reads reaches the recorder, whose queue is the one that bounds
  // memory and counts what it drops. (With the limit at --queue, a main thread that fell that
  // far behind LCM's receive thread lost the rest of a burst without a trace.)
  lcm_subscription_set_queue_capacity(sub, 0);
  pthread_sigmask(SIG_UNBLOCK, &stop_signals, nullptr);
  if (!quiet)
    fmt::print(stderr, "spindown-logger: channels '{}' on {} -> {} (flush every {} s{}{})\n", channels, url,
               first_file, r.flush_interval_s,
               w.rotate_size_mb > 0 ? fmt::format(", rotate at {} MB", w.rotate_size_mb) : "",
               w.rotate_time_s > 0 ? fmt::format(", rotate every {} s", w.rotate_time_s) : "");

  spindown::StatusHeartbeat beat("logger", "", start);  // only its schedule is used
  std::string reported_error, reported_state;
  std::int64_t lost_when_full = 0;
  // Datagrams the kernel dropped on the logger's own sockets (its receive buffer was full):
  // traffic that never reached the logger, so no counter of its own can see it.
  auto kernel_drops = [] {
    const auto d = spindown::own_udp_socket_drops();
    return d ? d->drops : std::int64_t{-1};
  };
  auto heartbeat = [&](std::int64_t now, const char* state) {
    spindown::status_t st = recorder.status(now);
    if (state) st.state = state;
    if (const std::int64_t drops = kernel_drops(); drops >= 0) {
      st.gauge_name.emplace_back("udp_drops");
      st.gauge_value.push_back(double(drops));
      st.ngauges = static_cast<std::int32_t>(st.gauge_name.size());
    }
    lcm.publish(w.status_channel, &st);
    beat.mark_sent(now);
    if (st.last_error != reported_error) {
      reported_error = st.last_error;
      if (!reported_error.empty()) fmt::print(stderr, "spindown-logger: {}\n", reported_error);
    }
    // A full disk is said once when it fills (last_error above) and once when space is back.
    const std::int64_t lost = spindown::find_counter(st, "events_lost").value_or(0);
    if (st.state == "disk full" && reported_state != "disk full") lost_when_full = lost;
    if (reported_state == "disk full" && st.state == "running")
      fmt::print(stderr,
                 "spindown-logger: space is back: writing on to the same file ({} events lost while the disk was "
                 "full)\n",
                 lost - lost_when_full);
    reported_state = st.state;
  };
  while (!g_stop) {
    lcm.handleTimeout(100);
    const std::int64_t now = wall_us();
    if (beat.due(now)) heartbeat(now, nullptr);
  }

  // Drain what has reached this host: LCM's receive thread may still hold packets from the
  // socket, so dispatch until 50 ms pass with nothing new (at most 2 s under continuous
  // traffic); then the writer writes everything queued.
  const auto drain_until = std::chrono::steady_clock::now() + std::chrono::seconds(2);
  for (int i = 0; i < 10000000 && std::chrono::steady_clock::now() < drain_until; ++i)
    if (lcm.handleTimeout(50) <= 0) break;
  lcm_unsubscribe(lcm.getUnderlyingLCM(), sub);
  recorder.stop("stopped");
  heartbeat(wall_us(), "stopped");

  const auto& c = writer.counters();
  if (!quiet) {
    fmt::print(stderr,
               "spindown-logger: stopped: {} events, {} bytes in {} files, {} drops, {} oversize drops, {} write "
               "errors, {} samples missing by sequence number, {} datagrams dropped by the kernel on the logger's "
               "socket\n",
               c.events, c.bytes, c.files, c.queue_drops + c.events_lost, c.oversize_drops, c.write_errors,
               c.samples_missing, kernel_drops());
    for (const auto& f : writer.files()) fmt::print(stderr, "spindown-logger: wrote {}\n", f);
  }
  if (c.write_errors > 0) {
    fmt::print(stderr, "spindown-logger: {} write errors, {} events lost; last: {}\n", c.write_errors, c.events_lost,
               writer.last_error());
    return 1;
  }
  return 0;
}
