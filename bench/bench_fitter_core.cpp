// FitterCore without LCM: samples per second through decode, checks, run detection and the
// fits, one sample per message as the bridge publishes the lab sketch. The LCM load test with
// CPU and latency is bench/bench_fitter_lcm.sh.
#include <benchmark/benchmark.h>

#include <cmath>
#include <string>
#include <vector>

#include "spindown/fitter_core.hpp"
#include "spindown/synthetic_run.hpp"

namespace {

struct NullSink : spindown::FitterSink {
  long fits = 0;
  void run_changed(const spindown::run_t&) override {}
  void fit_ready(const spindown::FitResult&) override { ++fits; }
};

// One bench's messages: two runs, one sample each, encoded.
std::vector<std::vector<unsigned char>> bench_messages(const std::string& bench, std::uint64_t seed) {
  std::vector<std::vector<unsigned char>> out;
  double t0_ms = 1000;
  std::int64_t seq = 0;
  for (int r = 0; r < 2; ++r) {
    spindown::SyntheticRunSpec spec;
    spec.seed = seed + r;
    spec.t0_ms = t0_ms;
    const auto run = spindown::make_synthetic_run(spec);
    for (std::size_t i = 0; i < run.t_ms.size(); ++i) {
      spindown::samples_t m{};  // every field zero (lcm-gen types leave them uninitialised)
      m.bench = bench;
      m.seq = seq++;
      m.quantity = spindown::samples_t::QUANTITY_BACK_EMF_V;
      m.n = 1;
      m.device_time_us = {std::llround(run.t_ms[i] * 1000)};
      m.host_time_us = {0};
      m.value = {run.volts[i]};
      m.raw_adc = {run.adc[i]};
      std::vector<unsigned char> buf(static_cast<std::size_t>(m.getEncodedSize()));
      m.encode(buf.data(), 0, static_cast<int>(buf.size()));
      out.push_back(std::move(buf));
    }
    t0_ms = run.t_ms.back() + 20;
  }
  return out;
}

void BM_FitterCoreTwoRuns(benchmark::State& state) {
  const auto msgs = bench_messages("b001", 3);
  long samples = 0, fits = 0;
  for (auto _ : state) {
    NullSink sink;
    spindown::FitterCore core({}, sink);
    std::int64_t t = 0;
    for (const auto& m : msgs) core.on_message("SPINDOWN.b001.SAMPLE", m.data(), std::int64_t(m.size()), t += 20000);
    core.finish(t);
    samples += static_cast<long>(msgs.size());
    fits += sink.fits;
  }
  state.counters["samples_per_s"] = benchmark::Counter(double(samples), benchmark::Counter::kIsRate);
  state.counters["fits"] = double(fits) / double(state.iterations());
}
BENCHMARK(BM_FitterCoreTwoRuns)->Unit(benchmark::kMillisecond);

}  // namespace
