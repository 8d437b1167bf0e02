// spindown-bridge-tap: subscribes to one bench's SAMPLE, CONFIG and STATUS channels and writes
// what arrives to files (samples as TSV, config and status as JSON lines). The integration
// tests compare these with what the virtual bench sent.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <fmt/format.h>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>

#include <spindown/config_t.hpp>
#include <spindown/samples_t.hpp>
#include <spindown/status_t.hpp>

#include "spindown/lcm_channels.hpp"
#include "spindown/lcm_loop.hpp"
#include "spindown/stop_signal.hpp"

namespace {

struct FileCloser {
  void operator()(std::FILE* f) const {
    if (f) std::fclose(f);
  }
};
using File = std::unique_ptr<std::FILE, FileCloser>;

File open_out(const std::string& path) {
  if (path.empty()) return nullptr;
  File f(std::fopen(path.c_str(), "w"));
  if (!f) throw std::runtime_error(fmt::format("cannot write {}", path));
  return f;
}

struct Tap {
  File samples, status, config;
  long n_samples = 0, n_status = 0, n_config = 0, n_messages = 0;

  void on_samples(const spindown::samples_t& m) {
    ++n_messages;
    for (int i = 0; i < m.n; ++i) {
      if (samples)
        fmt::print(samples.get(), "{}\t{}\t{}\t{}\t{:.17g}\t{}\t{}\n", m.seq + i, m.clock_epoch,
                   m.device_time_us[i], m.host_time_us[i], m.value[i], m.raw_adc[i], int(m.quantity));
      ++n_samples;
    }
    if (samples) std::fflush(samples.get());
  }
  void on_status(const spindown::status_t& m) {
    ++n_status;
    if (!status) return;
    nlohmann::json j{{"utime", m.utime},   {"service", m.service},   {"instance", m.instance},
                     {"state", m.state},   {"uptime_s", m.uptime_s}, {"last_error", m.last_error}};
    for (int i = 0; i < m.ncounters; ++i) j["counters"][m.counter_name[i]] = m.counter_value[i];
    for (int i = 0; i < m.ngauges; ++i) j["gauges"][m.gauge_name[i]] = m.gauge_value[i];
    fmt::print(status.get(), "{}\n", j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
    std::fflush(status.get());
  }
  void on_config(const spindown::config_t& m) {
    ++n_config;
    if (!config) return;
    nlohmann::json j{{"utime", m.utime},
                     {"bench", m.bench},
                     {"inertia_kg_m2", m.inertia_kg_m2},
                     {"inertia_source", m.inertia_source},
                     {"kb_v_s_per_rad", m.kb_v_s_per_rad},
                     {"kb_source", m.kb_source},
                     {"quantity", int(m.quantity)},
                     {"adc_volts_per_count", m.adc_volts_per_count},
                     {"adc_bits", m.adc_bits},
                     {"firmware", m.firmware},
                     {"protocol", m.protocol},
                     {"sample_period_s", m.sample_period_s},
                     {"baud", m.baud},
                     {"device", m.device}};
    fmt::print(config.get(), "{}\n", j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
    std::fflush(config.get());
  }
};

struct TapOptions {
  std::string bench, url, samples_file, status_file, config_file, ready_file;
  long until_samples = 0;
  double timeout_s = 60;
};

// The command line into o; an exit code when the program ends here.
std::optional<int> parse_options(int argc, char** argv, TapOptions& o) {
  CLI::App app{"spindown-bridge-tap: record one bench's SAMPLE/CONFIG/STATUS messages to files"};
  app.add_option("--bench", o.bench, "bench id")->required();
  app.add_option("--lcm-url", o.url, "LCM URL");
  app.add_option("--samples", o.samples_file, "TSV: seq epoch device_time_us host_time_us value raw_adc quantity");
  app.add_option("--status", o.status_file, "JSON lines of status_t");
  app.add_option("--config", o.config_file, "JSON lines of config_t");
  app.add_option("--ready", o.ready_file, "file created once subscribed (for scripts)");
  app.add_option("--until-samples", o.until_samples, "exit after this many samples (0: run to timeout)");
  app.add_option("--timeout", o.timeout_s, "exit after this many seconds")->check(CLI::Range(0.1, 3600.0));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  std::string why;
  if (!spindown::is_valid_bench_id(o.bench, &why)) {
    fmt::print(stderr, "spindown-bridge-tap: {}\n", why);
    return 2;
  }
  return std::nullopt;
}

}  // namespace

int main(int argc, char** argv) {
  TapOptions o;
  if (const auto exit_code = parse_options(argc, argv, o)) return *exit_code;
  Tap tap;
  try {
    tap.samples = open_out(o.samples_file);
    tap.status = open_out(o.status_file);
    tap.config = open_out(o.config_file);
  } catch (const std::exception& e) {
    fmt::print(stderr, "spindown-bridge-tap: {}\n", e.what());
    return 1;
  }
  spindown::LcmLoop loop(o.url);
  if (!loop.good()) {
    fmt::print(stderr, "spindown-bridge-tap: cannot start LCM\n");
    return 1;
  }
  using spindown::ChannelKind;
  // LCM drops messages silently past a subscription's queue capacity (default 30): a test
  // tool on a busy machine must not, so let the queues grow.
  const spindown::LcmSubscribeOptions grow{.queue_capacity = 1'000'000};
  loop.subscribe<spindown::samples_t>(
      spindown::channel_name(o.bench, ChannelKind::sample),
      [&](const spindown::samples_t& m) {
        tap.on_samples(m);
        if (o.until_samples > 0 && tap.n_samples >= o.until_samples) loop.stop();
      },
      grow);
  loop.subscribe<spindown::status_t>(spindown::channel_name(o.bench, ChannelKind::status),
                                     [&](const spindown::status_t& m) { tap.on_status(m); }, grow);
  loop.subscribe<spindown::config_t>(spindown::channel_name(o.bench, ChannelKind::config),
                                     [&](const spindown::config_t& m) { tap.on_config(m); }, grow);
  loop.on_decode_error(
      [](const spindown::LcmDecodeError& e) { fmt::print(stderr, "spindown-bridge-tap: {}\n", e.text()); });
  spindown::StopSignals stop;
  if (!o.ready_file.empty()) File(std::fopen(o.ready_file.c_str(), "w"));

  loop.run({.stop = &stop, .timeout_s = o.timeout_s, .max_wait_ms = 50, .max_failures = -1});
  fmt::print(stderr, "spindown-bridge-tap: {} samples in {} messages, {} status, {} config\n", tap.n_samples,
             tap.n_messages, tap.n_status, tap.n_config);
  return 0;
}
