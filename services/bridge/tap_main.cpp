// spindown-bridge-tap: subscribes to one bench's SAMPLE, CONFIG and STATUS channels and writes
// what arrives to files (samples as TSV, config and status as JSON lines). The integration
// tests compare these with what the virtual bench sent.
#include <CLI/CLI.hpp>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <fmt/format.h>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <nlohmann/json.hpp>

#include <spindown/config_t.hpp>
#include <spindown/samples_t.hpp>
#include <spindown/status_t.hpp>

#include "spindown/lcm_channels.hpp"

namespace {

std::atomic<bool> g_stop{false};
extern "C" void on_signal(int) { g_stop = true; }

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

  void on_samples(const lcm::ReceiveBuffer*, const std::string&, const spindown::samples_t* m) {
    ++n_messages;
    for (int i = 0; i < m->n; ++i) {
      if (samples)
        fmt::print(samples.get(), "{}\t{}\t{}\t{}\t{:.17g}\t{}\t{}\n", m->seq + i, m->clock_epoch,
                   m->device_time_us[i], m->host_time_us[i], m->value[i], m->raw_adc[i], int(m->quantity));
      ++n_samples;
    }
    if (samples) std::fflush(samples.get());
  }
  void on_status(const lcm::ReceiveBuffer*, const std::string&, const spindown::status_t* m) {
    ++n_status;
    if (!status) return;
    nlohmann::json j{{"utime", m->utime},   {"service", m->service},   {"instance", m->instance},
                     {"state", m->state},   {"uptime_s", m->uptime_s}, {"last_error", m->last_error}};
    for (int i = 0; i < m->ncounters; ++i) j["counters"][m->counter_name[i]] = m->counter_value[i];
    for (int i = 0; i < m->ngauges; ++i) j["gauges"][m->gauge_name[i]] = m->gauge_value[i];
    fmt::print(status.get(), "{}\n", j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
    std::fflush(status.get());
  }
  void on_config(const lcm::ReceiveBuffer*, const std::string&, const spindown::config_t* m) {
    ++n_config;
    if (!config) return;
    nlohmann::json j{{"utime", m->utime},
                     {"bench", m->bench},
                     {"inertia_kg_m2", m->inertia_kg_m2},
                     {"inertia_source", m->inertia_source},
                     {"kb_v_s_per_rad", m->kb_v_s_per_rad},
                     {"kb_source", m->kb_source},
                     {"quantity", int(m->quantity)},
                     {"adc_volts_per_count", m->adc_volts_per_count},
                     {"adc_bits", m->adc_bits},
                     {"firmware", m->firmware},
                     {"protocol", m->protocol},
                     {"sample_period_s", m->sample_period_s},
                     {"baud", m->baud},
                     {"device", m->device}};
    fmt::print(config.get(), "{}\n", j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
    std::fflush(config.get());
  }
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"spindown-bridge-tap: record one bench's SAMPLE/CONFIG/STATUS messages to files"};
  std::string bench, url, samples_file, status_file, config_file, ready_file;
  long until_samples = 0;
  double timeout_s = 60;
  app.add_option("--bench", bench, "bench id")->required();
  app.add_option("--lcm-url", url, "LCM URL");
  app.add_option("--samples", samples_file, "TSV: seq epoch device_time_us host_time_us value raw_adc quantity");
  app.add_option("--status", status_file, "JSON lines of status_t");
  app.add_option("--config", config_file, "JSON lines of config_t");
  app.add_option("--ready", ready_file, "file created once subscribed (for scripts)");
  app.add_option("--until-samples", until_samples, "exit after this many samples (0: run to timeout)");
  app.add_option("--timeout", timeout_s, "exit after this many seconds")->check(CLI::Range(0.1, 3600.0));
  CLI11_PARSE(app, argc, argv);

  Tap tap;
  std::string why;
  if (!spindown::is_valid_bench_id(bench, &why)) {
    fmt::print(stderr, "spindown-bridge-tap: {}\n", why);
    return 2;
  }
  try {
    tap.samples = open_out(samples_file);
    tap.status = open_out(status_file);
    tap.config = open_out(config_file);
  } catch (const std::exception& e) {
    fmt::print(stderr, "spindown-bridge-tap: {}\n", e.what());
    return 1;
  }
  lcm::LCM lcm(url);
  if (!lcm.good()) {
    fmt::print(stderr, "spindown-bridge-tap: cannot start LCM\n");
    return 1;
  }
  using spindown::ChannelKind;
  // LCM drops messages silently past a subscription's queue capacity (default 30): a test
  // tool on a busy machine must not, so let the queues grow.
  for (auto* sub : {lcm.subscribe(spindown::channel_name(bench, ChannelKind::sample), &Tap::on_samples, &tap),
                    lcm.subscribe(spindown::channel_name(bench, ChannelKind::status), &Tap::on_status, &tap),
                    lcm.subscribe(spindown::channel_name(bench, ChannelKind::config), &Tap::on_config, &tap)})
    sub->setQueueCapacity(1'000'000);
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  if (!ready_file.empty()) File(std::fopen(ready_file.c_str(), "w"));

  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(long(timeout_s * 1000));
  while (!g_stop && std::chrono::steady_clock::now() < deadline) {
    lcm.handleTimeout(50);
    if (until_samples > 0 && tap.n_samples >= until_samples) break;
  }
  fmt::print(stderr, "spindown-bridge-tap: {} samples in {} messages, {} status, {} config\n", tap.n_samples,
             tap.n_messages, tap.n_status, tap.n_config);
  return 0;
}
