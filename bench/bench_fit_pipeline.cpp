// The offline pipeline on one lab-like run of ~1500 samples: parse the Arduino text, find the
// run, fit all three models — as a whole (target: under 1 ms per run) and stage by stage.
// Run: build/bin/bench_fit_pipeline --benchmark_repetitions=10 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <stdexcept>
#include <string>

#include "spindown/arduino_text.hpp"
#include "spindown/fit.hpp"
#include "spindown/runs.hpp"
#include "spindown/synthetic_run.hpp"

using namespace spindown;

namespace {

// The lab's 3 V run (design §1): combined friction, ~27 s coast at 20 ms, PuTTY log.
const std::string& lab_run_text() {
  static const std::string text = [] {
    SyntheticRunSpec spec;
    spec.lead_in_s = 1.0;
    spec.tail_s = 2.0;
    spec.noise_v = 0.004;
    spec.ripple = 0.01;
    return to_arduino_text(make_synthetic_run(spec), 2, true);
  }();
  return text;
}

const Recording& lab_recording() {
  static const Recording rec = read_arduino_text(lab_run_text(), "bench.tsv");
  return rec;
}

const Run& lab_run() {
  static const Run run = [] {
    const Segmentation seg = find_runs(lab_recording());
    if (seg.runs.size() != 1) throw std::runtime_error("benchmark data: expected exactly one run");
    return seg.runs.front();
  }();
  return run;
}

void BM_Pipeline(benchmark::State& state) {
  const std::string& text = lab_run_text();
  const FitOptions opt;
  std::size_t samples = 0;
  for (auto _ : state) {
    const Recording rec = read_arduino_text(text, "bench.tsv");
    const Segmentation seg = find_runs(rec);
    for (const Run& run : seg.runs) {
      RunFit fit = fit_run(rec, run, opt);
      benchmark::DoNotOptimize(fit);
    }
    samples = rec.size();
  }
  state.counters["samples"] = static_cast<double>(samples);
}
BENCHMARK(BM_Pipeline)->Unit(benchmark::kMicrosecond);

void BM_ParseArduinoText(benchmark::State& state) {
  const std::string& text = lab_run_text();
  for (auto _ : state) {
    Recording rec = read_arduino_text(text, "bench.tsv");
    benchmark::DoNotOptimize(rec);
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * text.size()));
  state.counters["samples"] = static_cast<double>(lab_recording().size());
}
BENCHMARK(BM_ParseArduinoText)->Unit(benchmark::kMicrosecond);

void BM_FindRuns(benchmark::State& state) {
  const Recording& rec = lab_recording();
  for (auto _ : state) {
    Segmentation seg = find_runs(rec);
    benchmark::DoNotOptimize(seg);
  }
}
BENCHMARK(BM_FindRuns)->Unit(benchmark::kMicrosecond);

// One model at a time (arg = index into all_models), then all three as the CLI does.
void BM_FitModel(benchmark::State& state) {
  const Recording& rec = lab_recording();
  const Run& run = lab_run();
  FitOptions opt;
  opt.models = {all_models[state.range(0)]};
  state.SetLabel(std::string(model_name(opt.models.front())));
  for (auto _ : state) {
    RunFit fit = fit_run(rec, run, opt);
    benchmark::DoNotOptimize(fit);
  }
  state.counters["samples"] = static_cast<double>(run.end_index - run.cut_index);
}
BENCHMARK(BM_FitModel)->DenseRange(0, 2)->Unit(benchmark::kMicrosecond);

void BM_FitAllModels(benchmark::State& state) {
  const Recording& rec = lab_recording();
  const Run& run = lab_run();
  const FitOptions opt;
  for (auto _ : state) {
    RunFit fit = fit_run(rec, run, opt);
    benchmark::DoNotOptimize(fit);
  }
}
BENCHMARK(BM_FitAllModels)->Unit(benchmark::kMicrosecond);

}  // namespace
