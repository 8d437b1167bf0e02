// explain on one ~1500-sample run with the five library effects as candidates (target < 30 ms).
#include <benchmark/benchmark.h>

#include "explain_study.hpp"
#include "spindown/explain.hpp"
#include "spindown/runs.hpp"

namespace {

using namespace spindown;

// The lab's bench at 20 ms, combined friction plus windage, base viscous: two effects to find.
study::GeneratedRun lab_run() {
  study::GeneratedRun g;
  g.spec.friction = FrictionTerms{1.0e-7, 1.0e-4, 0, 0, 4e-10};
  g.spec.e0_v = 2.9;
  g.spec.ripple = 0.01;
  g.spec.noise_v = 0.003;
  g.run = make_synthetic_run(g.spec);
  for (std::size_t i = 0; i < g.run.t_ms.size(); ++i) g.recording.push(g.run.t_ms[i] / 1000.0, g.run.volts[i]);
  return g;
}

void BM_ExplainLabRun(benchmark::State& state) {
  const study::GeneratedRun g = lab_run();
  const Segmentation seg = find_runs(g.recording);
  if (seg.runs.empty()) {
    state.SkipWithError("no run found");
    return;
  }
  const Run& run = seg.runs.front();
  ExplainOptions opt;  // base viscous, all five effects as candidates
  std::size_t added = 0;
  for (auto _ : state) {
    const ExplainResult r = explain_run(g.recording, run, opt);
    added = r.steps.size();
    benchmark::DoNotOptimize(r.final_fit.rmse);
  }
  state.counters["samples"] = static_cast<double>(run.end_index - run.cut_index);
  state.counters["effects_added"] = static_cast<double>(added);
}
BENCHMARK(BM_ExplainLabRun)->Unit(benchmark::kMillisecond)->Repetitions(5)->ReportAggregatesOnly(true);

}  // namespace
