// The lab sketch's line parser alone (parse_lab_line), per line: what the serial bridge and the
// file reader pay for each sample before anything else. The whole-file reader (header, cut
// first line, resets) is BM_ParseArduinoText in bench_fit_pipeline.
#include <benchmark/benchmark.h>

#include <string>
#include <string_view>
#include <vector>

#include "spindown/lab_line.hpp"
#include "spindown/synthetic_run.hpp"

namespace {

// One lab run's lines (~1500, "millis\tvolts\r" as the sketch prints, CR kept), without terminators.
std::vector<std::string> lab_lines() {
  spindown::SyntheticRunSpec spec;
  spec.lead_in_s = 1.0;
  spec.tail_s = 2.0;
  spec.noise_v = 0.004;
  spec.ripple = 0.01;
  const std::string text = spindown::to_arduino_text(spindown::make_synthetic_run(spec), 2, false);
  std::vector<std::string> lines;
  std::size_t from = 0;
  for (std::size_t nl = text.find('\n'); nl != std::string::npos; nl = text.find('\n', from)) {
    lines.push_back(text.substr(from, nl - from));
    from = nl + 1;
  }
  return lines;
}

void BM_ParseLabLine(benchmark::State& state) {
  const auto lines = lab_lines();
  std::size_t bytes = 0;
  for (const auto& l : lines) bytes += l.size() + 1;
  std::int64_t samples = 0;
  for (auto _ : state) {
    for (const auto& l : lines) {
      const spindown::LabLine p = spindown::parse_lab_line(l);
      samples += p.kind == spindown::LabLine::Kind::sample;
      benchmark::DoNotOptimize(p.value);
    }
  }
  state.SetItemsProcessed(state.iterations() * std::int64_t(lines.size()));
  state.SetBytesProcessed(state.iterations() * std::int64_t(bytes));
  state.counters["lines_per_s"] = benchmark::Counter(double(state.iterations()) * double(lines.size()),
                                                     benchmark::Counter::kIsRate);
  if (samples != std::int64_t(state.iterations()) * std::int64_t(lines.size()))
    state.SkipWithError("a generated line did not parse as a sample");
}
BENCHMARK(BM_ParseLabLine)->Unit(benchmark::kMicrosecond);

// Lines the parser must reject (garbled, cut, PuTTY header): the bad path must not be slow.
void BM_ParseLabLineGarbled(benchmark::State& state) {
  const std::vector<std::string> bad = {
      "=~=~=~=~=~=~=~=~=~=~=~= PuTTY log 2023.09.14 10:21:33 =~=~=~=~=~=~=~=~=~=~=~=",
      "52\t2.8\t1.0\r", "5254\t2.x8\r", "\t2.80\r", "12345678901234567890\t0.00", "5254\tnan", "-20\t1.00", ""};
  for (auto _ : state)
    for (const auto& l : bad) benchmark::DoNotOptimize(spindown::parse_lab_line(l).kind);
  state.SetItemsProcessed(state.iterations() * std::int64_t(bad.size()));
}
BENCHMARK(BM_ParseLabLineGarbled)->Unit(benchmark::kNanosecond);

}  // namespace
