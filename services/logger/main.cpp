// spindown-logger: records LCM traffic (SPINDOWN.* by default) into standard LCM event logs,
// with rotation by size and time, a flush on a timer, nothing lost on SIGINT/SIGTERM, and its
// counters (events, bytes, files, drops, write errors, flushes) on SPINDOWN.logger.STATUS and
// in the logs themselves; retention (--keep-files, --keep-mb) deletes its oldest files; under
// systemd Type=notify with a watchdog. The logic lives in spindown::EventLogWriter,
// spindown::LogRecorder, spindown::LogRetentionOptions and spindown::ServiceNotifier.
#include <CLI/CLI.hpp>
#include <cstdint>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <optional>
#include <string>

#include "spindown/clock.hpp"
#include "spindown/event_log_writer.hpp"
#include "service_command_line.hpp"
#include "spindown/lab_settings.hpp"
#include "spindown/lcm_loop.hpp"
#include "spindown/lcm_status.hpp"
#include "spindown/lcm_url.hpp"
#include "spindown/log_recorder.hpp"
#include "spindown/message_gate.hpp"
#include "spindown/message_stamp.hpp"
#include "spindown/loop_watchdog.hpp"
#include "spindown/udp_socket_drops.hpp"
#include "spindown/service_notifier.hpp"
#include "spindown/stop_signal.hpp"

namespace {

struct LoggerOptions {
  std::string channels;
  spindown::service::LabConnection connection;
  spindown::EventLogWriterOptions writer;
  spindown::LogRecorderOptions recorder;
  bool quiet = false;
};

// The command line into o; an exit code when the program ends here (--help 0, bad usage 2).
std::optional<int> parse_options(int argc, char** argv, LoggerOptions& o) {
  CLI::App app{"spindown-logger: LCM traffic -> standard LCM event logs (lcm-logplayer and lcm::LogFile read them)"};
  spindown::EventLogWriterOptions& w = o.writer;
  spindown::LogRecorderOptions& r = o.recorder;
  spindown::service::LabConnectionOptions connection;
  connection.add_to(
      app, /*receives=*/true,
      "lab name: every message is recorded, and another lab's messages are counted (other_lab) and named; the "
      "heartbeat names it (default: $SPINDOWN_LAB, else 'lab')",
      "lab key file: every message is recorded, and unsigned, wrongly signed and replayed ones are counted and named; "
      "the heartbeat is signed (default: the systemd credential lab-key when loaded); NEW,OLD while keys change: "
      "signs with NEW, accepts both");
  app.add_option("--channels", o.channels,
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
  app.add_option("--keep-files", w.retention.keep_files,
                 "retention: at most this many log files (the one being written included), the oldest deleted first; "
                 "0 = keep all")
      ->capture_default_str();
  app.add_option("--keep-mb", w.retention.keep_mb,
                 "retention: at most this many MB (1e6 bytes) of log files, the oldest deleted first, never the one "
                 "being written; 0 = no limit")
      ->capture_default_str();
  app.add_flag("--fsync", w.sync_on_flush, "also fdatasync at every flush (always done at rotation and exit)");
  app.add_option("--max-event-bytes", r.max_event_bytes,
                 "larger messages are not recorded (counted as oversize_drops and named in the heartbeat)")
      ->capture_default_str();
  app.add_option("--queue", r.queue_capacity, "events queued for the writer before drops are counted")
      ->capture_default_str()
      ->check(CLI::Range(1, 10000000));
  app.add_option("--status-channel", w.status_channel, "channel of the heartbeat and of the status events in the logs")
      ->capture_default_str();
  app.add_option("--name", w.instance, "status_t.instance (default: the bench, else the prefix)");
  app.add_flag("-q,--quiet", o.quiet, "only errors on stderr");
  if (const auto exit_code = spindown::service::parse(app, argc, argv)) return exit_code;

  if (o.channels.empty()) o.channels = w.bench.empty() ? "SPINDOWN\\..*" : "SPINDOWN\\." + w.bench + "\\..*";
  std::string why;
  if (!w.is_valid(&why) || !r.is_valid(&why)) return spindown::service::bad_usage("spindown-logger", why);
  auto lab = connection.resolve(&why);
  if (!lab) return spindown::service::bad_usage("spindown-logger", why);
  o.connection = std::move(*lab);
  return std::nullopt;
}

// The heartbeat on the status channel (the recorder's status, with the kernel's drops on the
// logger's own sockets: traffic that never reached it, so no counter of its own can see it),
// and its problems said once on stderr when they start (and a full disk once when it ends).
class Heartbeat {
 public:
  Heartbeat(spindown::LcmLoop& loop, spindown::LogRecorder& recorder, std::string channel,
            const spindown::MessageGate& gate)
      : loop_(loop), recorder_(recorder), channel_(std::move(channel)), gate_(gate) {}

  // A message the gate refused (recorded all the same): in the heartbeat's last_error while
  // nothing else is (and so on stderr, once per change, as every last_error).
  void refused(const spindown::GateResult& g) { last_refusal_ = g.text; }

  void beat(std::int64_t now, const char* state = nullptr) {
    spindown::status_t st = recorder_.status(now);
    if (state) st.state = state;
    const spindown::GateCounters& g = gate_.counters();
    const std::pair<const char*, std::int64_t> gate_counts[] = {
        {"other_lab", g.other_lab},
        {"unsigned_messages", g.not_signed},
        {"bad_signatures", g.other_key + g.bad_signature},
        {"replays", g.replayed + g.outside_window},
    };
    spindown::add_counters(st, gate_counts);
    if (st.last_error.empty() && !last_refusal_.empty()) st.last_error = "recorded, not this lab's own: " + last_refusal_;
    if (const std::int64_t drops = spindown::own_udp_drop_count(); drops >= 0) {
      const std::pair<const char*, double> udp[] = {{"udp_drops", double(drops)}};
      spindown::add_gauges(st, udp);
    }
    loop_.publish(channel_, st);
    if (st.last_error != reported_error_) {
      reported_error_ = st.last_error;
      if (!reported_error_.empty()) fmt::print(stderr, "spindown-logger: {}\n", reported_error_);
    }
    // A full disk is said once when it fills (last_error above) and once when space is back.
    const std::int64_t lost = spindown::find_counter(st, "events_lost").value_or(0);
    if (st.state == "disk full" && reported_state_ != "disk full") lost_when_full_ = lost;
    if (reported_state_ == "disk full" && st.state == "running")
      fmt::print(stderr,
                 "spindown-logger: space is back: writing on to the same file ({} events lost while the disk was "
                 "full)\n",
                 lost - lost_when_full_);
    reported_state_ = st.state;
  }

 private:
  spindown::LcmLoop& loop_;
  spindown::LogRecorder& recorder_;
  std::string channel_;
  const spindown::MessageGate& gate_;
  std::string last_refusal_;
  std::string reported_error_, reported_state_;
  std::int64_t lost_when_full_ = 0;
};

// The last words on stderr: the counts and the files (unless --quiet), the write errors always;
// the exit code (1 after write errors).
int report_stop(const spindown::EventLogWriter& writer, bool quiet) {
  const auto& c = writer.counters();
  if (!quiet) {
    fmt::print(stderr,
               "spindown-logger: stopped: {} events, {} bytes in {} files, {} drops, {} oversize drops, {} write "
               "errors, {} samples missing by sequence number, {} datagrams dropped by the kernel on the logger's "
               "socket\n",
               c.events, c.bytes, c.files, c.queue_drops + c.events_lost, c.oversize_drops, c.write_errors,
               c.samples_missing, spindown::own_udp_drop_count());
    for (const auto& f : writer.files()) fmt::print(stderr, "spindown-logger: wrote {}\n", f);
    if (c.files_deleted > 0)
      fmt::print(stderr, "spindown-logger: retention deleted {} files ({} bytes{}): {}\n", c.files_deleted,
                 c.bytes_deleted,
                 c.files_deleted_for_space > 0
                     ? fmt::format("; {} of them to make room on a disk about to fill", c.files_deleted_for_space)
                     : std::string(),
                 fmt::join(writer.deleted_files(), ", "));
  }
  if (c.write_errors > 0) {
    fmt::print(stderr, "spindown-logger: {} write errors, {} events lost; last: {}\n", c.write_errors, c.events_lost,
               writer.last_error());
    return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  LoggerOptions o;
  if (const auto exit_code = parse_options(argc, argv, o)) return *exit_code;
  const spindown::EventLogWriterOptions& w = o.writer;
  const spindown::LogRecorderOptions& r = o.recorder;

  spindown::StopSignals stop({.ignore_sigpipe = true});
  const std::string& url = o.connection.lcm_url;
  spindown::LcmLoop loop(url);
  if (!loop.good()) {
    fmt::print(stderr, "spindown-logger: cannot start LCM at {}\n", url);
    return 1;
  }

  const std::int64_t start = spindown::wall_us();
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
  spindown::MessageStamp stamp(spindown::this_process_identity(o.connection.lab.lab, url), o.connection.lab.key);
  loop.set_stamp(&stamp);
  spindown::MessageGate gate(o.connection.gate());
  Heartbeat heartbeat(loop, recorder, w.status_channel, gate);

  // LCM 1.3.1 drops silently past a subscription's queue capacity (30 unless set): no limit
  // there, so every message LCM reads reaches the recorder, whose queue is the one that bounds
  // memory and counts what it drops. (With the limit at --queue, a main thread that fell that
  // far behind LCM's receive thread lost the rest of a burst without a trace.)
  const bool subscribed = loop.subscribe_raw(
      o.channels,
      [&](const spindown::LcmMessage& m) {
        // Recorded whatever it is (the log is the evidence); counted when it is not the lab's own,
        // and then kept out of the samples' sequence counters (a forged stream's gaps are no loss).
        const spindown::GateResult g = gate.check(m.channel, m.data, m.size, m.recv_utime);
        recorder.offer(m.recv_utime, m.channel, m.data, static_cast<std::int32_t>(m.size), !g.refused());
        if (g.refused()) heartbeat.refused(g);
      },
      {.queue_capacity = 0});
  if (!subscribed) {
    fmt::print(stderr, "spindown-logger: cannot subscribe to channels '{}' (bad regex?)\n", o.channels);
    recorder.stop("subscribe failed");
    return 2;
  }
  const std::string retention =
      (w.retention.keep_files > 0 ? fmt::format(", keep {} files", w.retention.keep_files) : std::string()) +
      (w.retention.keep_mb > 0 ? fmt::format(", keep {} MB", w.retention.keep_mb) : std::string());
  if (!o.quiet)
    fmt::print(stderr, "spindown-logger: channels '{}' on {} -> {} (flush every {} s{}{}{}); {}\n", o.channels, url,
               first_file, r.flush_interval_s,
               w.rotate_size_mb > 0 ? fmt::format(", rotate at {} MB", w.rotate_size_mb) : "",
               w.rotate_time_s > 0 ? fmt::format(", rotate every {} s", w.rotate_time_s) : "", retention,
               spindown::lab_settings_text(o.connection.lab));

  loop.every(1.0, [&](std::int64_t now) { heartbeat.beat(now); }, 0);
  spindown::ServiceNotifier notify;
  spindown::feed_watchdog_from_loop(loop, notify, [&](std::int64_t now_ns) {
    return now_ns - recorder.writer_alive_ns() < notify.stuck_after_ns();
  });
  notify.ready(fmt::format("recording '{}' into {}", o.channels, w.dir));
  loop.run({.stop = &stop, .max_failures = -1});
  notify.stopping("stopping: draining LCM and closing the log");

  // Drain what has reached this host: LCM's receive thread may still hold packets from the
  // socket, so dispatch until 50 ms pass with nothing new (at most 2 s under continuous
  // traffic); then the writer writes everything queued.
  loop.drain(50, 2.0);
  loop.unsubscribe_all();
  recorder.stop("stopped");
  heartbeat.beat(spindown::wall_us(), "stopped");

  return report_stop(writer, o.quiet);
}
