// Line-to-publish latency of the serial bridge (target p99 < 1 ms): from a complete line to the
// return of lcm publish. Three paths: a lab line and a spindown-v1 line handed to the bridge
// logic, and the full path through a pseudo-terminal (write on the device side, poll + read
// on the bridge side, parse, encode, publish). LCM uses memq:// here so a benchmark never puts
// traffic on a network; the integration tests report the same gauge over real UDP multicast.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <lcm/lcm-cpp.hpp>
#include <string>
#include <vector>

#include "spindown/lcm_channels.hpp"
#include "spindown/pseudo_terminal.hpp"
#include "spindown/serial_bridge.hpp"
#include "spindown/serial_port.hpp"

using namespace spindown;

namespace {

struct LcmSink : BridgeSink {
  explicit LcmSink(lcm::LCM& l) : lcm(l) {}
  lcm::LCM& lcm;
  const std::string sample = channel_name("bench", ChannelKind::sample);
  const std::string config = channel_name("bench", ChannelKind::config);
  const std::string status = channel_name("bench", ChannelKind::status);
  void publish(const samples_t& m) override { lcm.publish(sample, &m); }
  void publish(const config_t& m) override { lcm.publish(config, &m); }
  void publish(const status_t& m) override { lcm.publish(status, &m); }
};

BridgeSettings settings() {
  BridgeSettings s;
  s.bench = "bench";
  s.device = "/dev/bench";
  return s;
}

using Clock = std::chrono::steady_clock;

void report(benchmark::State& state, std::vector<double>& us) {
  if (us.empty()) return;
  std::sort(us.begin(), us.end());
  auto q = [&](double p) { return us[std::min(us.size() - 1, std::size_t(p * double(us.size() - 1) + 0.5))]; };
  state.counters["p50_us"] = q(0.50);
  state.counters["p99_us"] = q(0.99);
  state.counters["p999_us"] = q(0.999);
  state.counters["max_us"] = us.back();
}

// Drains memq so its queue does not grow (memq keeps every message until handled).
struct Drain {
  void on(const lcm::ReceiveBuffer*, const std::string&) {}
};

void run_logic(benchmark::State& state, bool v1) {
  lcm::LCM lcm("memq://");
  Drain drain;
  lcm.subscribe("SPINDOWN\\..*", &Drain::on, &drain);
  LcmSink sink(lcm);
  SerialBridge bridge(settings(), sink);
  bridge.start(0);
  std::vector<double> us;
  us.reserve(1 << 20);
  std::uint32_t i = 0;
  for (auto _ : state) {
    state.PauseTiming();
    const std::string line = v1 ? format_spindown_sample(i, 5000 * i, int(i % 1024))
                                : std::to_string(1000 + 20 * std::uint64_t(i)) + "\t2.81\r\n";
    ++i;
    state.ResumeTiming();
    const auto t0 = Clock::now();
    bridge.feed(line, 0);
    const auto t1 = Clock::now();
    us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
    state.PauseTiming();
    lcm.handleTimeout(0);
    state.ResumeTiming();
  }
  if (bridge.counters().samples != std::int64_t(i)) state.SkipWithError("samples were lost");
  report(state, us);
}

void BM_LineToPublish_Lab(benchmark::State& state) { run_logic(state, false); }
void BM_LineToPublish_SpindownV1(benchmark::State& state) { run_logic(state, true); }

void BM_LineToPublish_ThroughPty(benchmark::State& state) {
  lcm::LCM lcm("memq://");
  Drain drain;
  lcm.subscribe("SPINDOWN\\..*", &Drain::on, &drain);
  LcmSink sink(lcm);
  PseudoTerminal device;
  SerialPort port(device.slave_path(), 115200);
  SerialBridge bridge(settings(), sink);
  bridge.start(0);
  std::array<char, 4096> buf{};
  std::vector<double> us;
  us.reserve(1 << 20);
  std::uint32_t i = 0;
  for (auto _ : state) {
    const std::string line = format_spindown_sample(i, 5000 * i, int(i % 1024));
    ++i;
    const auto t0 = Clock::now();
    device.write(line, std::chrono::milliseconds(100));  // the line's last byte arrives
    const auto before = bridge.counters().samples;
    for (int guard = 0; guard < 1000 && bridge.counters().samples == before; ++guard) {
      const auto n = port.read_some(buf, std::chrono::milliseconds(100));
      bridge.feed(std::string_view(buf.data(), n), 0);
    }
    const auto t1 = Clock::now();
    us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
    state.PauseTiming();
    lcm.handleTimeout(0);
    state.ResumeTiming();
  }
  if (bridge.counters().samples != std::int64_t(i)) state.SkipWithError("samples were lost");
  report(state, us);
}

void BM_LineSplitter(benchmark::State& state) {
  std::string text;
  for (int i = 0; i < 1000; ++i) text += std::to_string(100000 + 20 * i) + "\t2.81\r\n";
  LineSplitter splitter(1024);
  std::size_t lines = 0;
  const LineSplitter::Handler count = [&](const LineSplitter::Line&) { ++lines; };
  for (auto _ : state) {
    for (std::size_t off = 0; off < text.size(); off += 64) splitter.feed(std::string_view(text).substr(off, 64), count);
  }
  benchmark::DoNotOptimize(lines);
  state.SetBytesProcessed(std::int64_t(state.iterations()) * std::int64_t(text.size()));
}

}  // namespace

BENCHMARK(BM_LineToPublish_Lab)->Iterations(100000);
BENCHMARK(BM_LineToPublish_SpindownV1)->Iterations(100000);
BENCHMARK(BM_LineToPublish_ThroughPty)->Iterations(20000);
BENCHMARK(BM_LineSplitter);
