// spindown-bridge: reads a bench's Arduino over a serial port and publishes its samples,
// config and heartbeat on LCM (SPINDOWN.<bench>.SAMPLE|CONFIG|STATUS). Survives unplugging,
// resets, wrong baud rates and garbage; SIGINT/SIGTERM end it with exit code 0. Under systemd
// (Type=notify): READY=1 when its serial loop starts, WATCHDOG=1 from that loop, STOPPING=1.
#include <CLI/CLI.hpp>
#include <array>
#include <chrono>
#include <fmt/format.h>
#include <lcm/lcm-cpp.hpp>
#include <optional>

#include "spindown/bridge_settings.hpp"
#include "spindown/clock.hpp"
#include "service_command_line.hpp"
#include "spindown/lab_settings.hpp"
#include "spindown/lcm_channels.hpp"
#include "spindown/message_stamp.hpp"
#include "spindown/serial_bridge.hpp"
#include "spindown/serial_port.hpp"
#include "spindown/service_notifier.hpp"
#include "spindown/session_id.hpp"
#include "spindown/stop_signal.hpp"

namespace {

using spindown::wall_us;

// Every message carries this bridge's source (lab, host, session) and, with the lab key, its
// signature: the stamp encodes it.
class LcmSink : public spindown::BridgeSink {
 public:
  LcmSink(lcm::LCM& lcm, const std::string& bench, spindown::MessageStamp& stamp)
      : lcm_(lcm),
        stamp_(stamp),
        sample_(spindown::channel_name(bench, spindown::ChannelKind::sample)),
        config_(spindown::channel_name(bench, spindown::ChannelKind::config)),
        status_(spindown::channel_name(bench, spindown::ChannelKind::status)) {}
  void publish(const spindown::samples_t& m) override { send(sample_, m); }
  void publish(const spindown::config_t& m) override { send(config_, m); }
  void publish(const spindown::status_t& m) override { send(status_, m); }

 private:
  template <class Msg>
  void send(const std::string& channel, const Msg& m) {
    const std::vector<unsigned char> bytes = stamp_.encode(channel, m);
    const int rc = bytes.empty() ? -1 : lcm_.publish(channel, bytes.data(), static_cast<unsigned>(bytes.size()));
    if (rc != 0 && ++failures_ % 100 == 1)
      fmt::print(stderr, "spindown-bridge: publishing on {} failed ({} times so far)\n", channel, failures_);
  }
  lcm::LCM& lcm_;
  spindown::MessageStamp& stamp_;
  std::string sample_, config_, status_;
  long failures_ = 0;
};

struct BridgeOptions {
  spindown::BridgeSettings settings;
  std::string lcm_url;
  spindown::LabSettings lab;
  bool exit_on_missing = false;
  double retry_s = 0.25;
};

// The command line (and --config) into o; an exit code when the program ends here.
std::optional<int> parse_options(int argc, char** argv, BridgeOptions& o) {
  CLI::App app{"spindown-bridge: a bench's serial port -> LCM SPINDOWN.<bench>.SAMPLE|CONFIG|STATUS"};
  spindown::BridgeSettings& s = o.settings;
  std::string config_file;
  app.add_option("--device", s.device, "serial device, e.g. /dev/ttyACM0");
  app.add_option("--bench", s.bench, "bench id [A-Za-z0-9_-]{1,32}");
  auto* baud_opt = app.add_option("--baud", s.baud, "baud rate (lab sketch 9600, spindown firmware 115200)");
  spindown::service::LabConnectionOptions connection;
  connection.add_to(app, /*receives=*/false);
  app.add_option("--config", config_file, "TOML file: bench J, K_b, quantity, ADC, serial (see README)")
      ->check(CLI::ExistingFile);
  bool retry_flag = false;
  auto* retry = app.add_flag("--retry", retry_flag, "keep retrying a missing device every --retry-interval (default)");
  app.add_flag("--exit-on-missing", o.exit_on_missing, "exit with code 1 when the device cannot be opened")
      ->excludes(retry);
  app.add_option("--retry-interval", o.retry_s, "seconds between attempts to open the device")
      ->check(CLI::Range(0.01, 0.5));
  if (const auto exit_code = spindown::service::parse(app, argc, argv)) return exit_code;

  // CLI beats the file: remember what the command line said before reading the file.
  const spindown::BridgeSettings cli = s;
  if (!config_file.empty()) {
    try {
      spindown::load_bridge_settings(config_file, s);
    } catch (const std::exception& e) {
      return spindown::service::bad_usage("spindown-bridge", e.what());
    }
    for (const auto& w : s.warnings) fmt::print(stderr, "spindown-bridge: {}\n", w);
    if (!cli.bench.empty()) s.bench = cli.bench;
    if (!cli.device.empty()) s.device = cli.device;
    if (baud_opt->count() > 0) s.baud = cli.baud;
  }
  std::string why;
  if (!s.is_valid(&why)) return spindown::service::bad_usage("spindown-bridge", why);
  auto lab = connection.resolve(&why);
  if (!lab) return spindown::service::bad_usage("spindown-bridge", why);
  o.lcm_url = lab->lcm_url;
  o.lab = std::move(lab->lab);
  return std::nullopt;
}

// The serial loop: open the device (again after an unplug, every --retry-interval), feed what
// it sends to the bridge, tick the bridge's heartbeat; until a stop signal. The exit code.
int pump(const BridgeOptions& o, spindown::SerialBridge& bridge, const spindown::StopSignals& stop,
         spindown::ServiceNotifier& notify) {
  const spindown::BridgeSettings& s = o.settings;
  spindown::SerialPort port;
  std::array<char, 4096> buf{};
  const auto retry_every = std::chrono::microseconds(static_cast<long>(o.retry_s * 1e6));
  auto next_try = std::chrono::steady_clock::now();
  std::string last_open_error;
  bool said_wrong_baud = false;
  notify.ready(fmt::format("bench {}: reading {}", s.bench, s.device));
  while (!stop.requested()) {
    // Each round of this loop is progress (a read returns within 100 ms, a retry within 20 ms),
    // so the watchdog is fed here and nowhere else: a hung read or publish stops the pings.
    notify.stall_point();
    notify.watchdog();
    if (!port.is_open()) {
      if (std::chrono::steady_clock::now() >= next_try) {
        try {
          port = spindown::SerialPort(s.device, s.baud);
          bridge.connected(wall_us());
          last_open_error.clear();
          fmt::print(stderr, "spindown-bridge: connected to {}\n", s.device);
        } catch (const std::exception& e) {
          bridge.open_failed(wall_us(), e.what());
          if (o.exit_on_missing) {
            fmt::print(stderr, "spindown-bridge: {} (exiting: --exit-on-missing)\n", e.what());
            return 1;
          }
          if (last_open_error != e.what()) {
            fmt::print(stderr, "spindown-bridge: {} (retrying every {:.2f} s)\n", e.what(), o.retry_s);
            last_open_error = e.what();
          }
          next_try = std::chrono::steady_clock::now() + retry_every;
        }
      }
      if (!port.is_open()) {
        bridge.tick(wall_us());
        stop.sleep_for(std::chrono::milliseconds(20));
        continue;
      }
    }
    try {
      const std::size_t got = port.read_some(buf, std::chrono::milliseconds(100));
      if (got > 0) bridge.feed(std::string_view(buf.data(), got), wall_us());
      if (bridge.looks_like_wrong_baud() != said_wrong_baud) {  // said once, and once when it ends
        said_wrong_baud = bridge.looks_like_wrong_baud();
        if (said_wrong_baud)
          fmt::print(stderr, "spindown-bridge: {}: {}\n", s.device, bridge.state());
        else
          fmt::print(stderr, "spindown-bridge: {}: valid lines again at {} baud\n", s.device, s.baud);
      }
    } catch (const spindown::SerialError& e) {
      port.close();
      bridge.disconnected(wall_us(), e.what());
      said_wrong_baud = false;  // a new connection starts afresh
      fmt::print(stderr, "spindown-bridge: {}; reopening\n", e.what());
      next_try = std::chrono::steady_clock::now();  // try at once, then every retry interval
    }
    bridge.tick(wall_us());
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  BridgeOptions o;
  if (const auto exit_code = parse_options(argc, argv, o)) return *exit_code;
  const spindown::BridgeSettings& s = o.settings;

  lcm::LCM lcm(o.lcm_url);
  if (!lcm.good()) {
    fmt::print(stderr, "spindown-bridge: cannot start LCM{}{}\n", o.lcm_url.empty() ? "" : " at ", o.lcm_url);
    return 1;
  }
  spindown::StopSignals stop({.ignore_sigpipe = true});

  spindown::MessageStamp stamp(spindown::this_process_identity(o.lab.lab, o.lcm_url), o.lab.key);
  if (o.lab.key && !o.lab.key->warning.empty()) fmt::print(stderr, "spindown-bridge: warning: {}\n", o.lab.key->warning);
  LcmSink sink(lcm, s.bench, stamp);
  spindown::SerialBridge bridge(s, sink);
  bridge.start(wall_us());
  fmt::print(stderr, "spindown-bridge: bench {} device {} at {} baud; {}; session {}\n", s.bench, s.device, s.baud,
             spindown::lab_settings_text(o.lab), spindown::session_text(stamp.identity().session));
  spindown::ServiceNotifier notify;
  const int rc = pump(o, bridge, stop, notify);
  notify.stopping();
  bridge.stop(wall_us());
  const auto& c = bridge.counters();
  fmt::print(stderr,
             "spindown-bridge: stopped: {} samples, {} good / {} bad lines, {} reconnects, latency p99 {:.0f} us\n",
             c.samples, c.lines_good, c.lines_bad, c.reconnects, bridge.latency_quantile_us(0.99));
  return rc;
}
