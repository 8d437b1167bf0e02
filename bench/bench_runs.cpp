// Segmentation speed: find_runs on one lab run (~1500 samples at 50 Hz) and on a five-run
// recording, and the streaming detector's cost per sample.
#include <benchmark/benchmark.h>

#include "spindown/run_detector.hpp"
#include "spindown/runs.hpp"
#include "spindown/synthetic_run.hpp"

namespace {

spindown::Recording lab_run() {
  spindown::SyntheticRunSpec spec;  // the lab's bench, combined friction, ~27 s coast
  spec.ripple = 0.01;
  spec.noise_v = 0.004;
  spec.lead_in_s = 1.0;
  spec.tail_s = 2.0;
  const auto s = spindown::make_synthetic_run(spec);
  spindown::Recording rec;
  for (std::size_t i = 0; i < s.t_ms.size(); ++i) rec.push(s.t_ms[i] / 1000.0, s.volts[i]);
  return rec;
}

spindown::Recording five_runs() {
  spindown::Recording rec;
  double t0_ms = 1000;
  for (int k = 0; k < 5; ++k) {
    spindown::SyntheticRunSpec spec;
    spec.lead_in = spindown::LeadIn(k % 3);
    spec.t0_ms = t0_ms;
    spec.supply_v = spec.e0_v + 0.25;
    spec.seed = 10 + k;
    const auto s = spindown::make_synthetic_run(spec);
    for (std::size_t i = 0; i < s.t_ms.size(); ++i) rec.push(s.t_ms[i] / 1000.0, s.volts[i]);
    t0_ms = s.t_ms.back() + 20;
  }
  return rec;
}

void BM_FindRunsLabRun(benchmark::State& state) {
  const auto rec = lab_run();
  for (auto _ : state) {
    auto seg = spindown::find_runs(rec);
    benchmark::DoNotOptimize(seg);
  }
  state.counters["samples"] = double(rec.size());
  state.SetItemsProcessed(state.iterations() * std::int64_t(rec.size()));
}
BENCHMARK(BM_FindRunsLabRun)->Unit(benchmark::kMicrosecond);

void BM_FindRunsFiveRuns(benchmark::State& state) {
  const auto rec = five_runs();
  for (auto _ : state) {
    auto seg = spindown::find_runs(rec);
    benchmark::DoNotOptimize(seg);
  }
  state.counters["samples"] = double(rec.size());
  state.SetItemsProcessed(state.iterations() * std::int64_t(rec.size()));
}
BENCHMARK(BM_FindRunsFiveRuns)->Unit(benchmark::kMicrosecond);

// The live fitter's use: one push() per sample, events taken as they come.
void BM_DetectorPerSample(benchmark::State& state) {
  const auto rec = lab_run();
  for (auto _ : state) {
    spindown::RunDetector det;
    std::size_t events = 0;
    for (std::size_t i = 0; i < rec.size(); ++i) {
      det.push(rec.t_s[i], rec.value[i]);
      if (det.has_events()) events += det.take_events().size();
    }
    det.finish();
    events += det.take_events().size();
    benchmark::DoNotOptimize(events);
  }
  state.counters["samples"] = double(rec.size());
  state.SetItemsProcessed(state.iterations() * std::int64_t(rec.size()));
}
BENCHMARK(BM_DetectorPerSample)->Unit(benchmark::kMicrosecond);

}  // namespace
