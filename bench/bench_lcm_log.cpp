// Reading an LCM event log (what spindown-logger and lcm-logger write): LcmLogReader streaming
// events with samples_t decoded, and read_lcm_log gathering one Recording per bench. The log
// is 4 lab benches × 1 sample per message (bench/lab_lcm_log.hpp), 200,000 samples, on /tmp.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <filesystem>
#include <string>
#include <unistd.h>

#include "lab_lcm_log.hpp"
#include "spindown/lcm_log_reader.hpp"

namespace {

constexpr long long log_samples = 200'000;

// The log, written once per process and removed at exit.
const std::string& lab_log() {
  static const struct Log {
    std::string path = std::filesystem::temp_directory_path() / ("bench_lcm_log." + std::to_string(::getpid()) + ".lcm");
    Log() { bench_log::write_lab_lcm_log(path, log_samples, 4, 1); }
    ~Log() { std::remove(path.c_str()); }
  } log;
  return log.path;
}

void BM_LcmLogReaderEvents(benchmark::State& state) {
  const std::string& path = lab_log();
  std::int64_t samples = 0, events = 0, bytes = 0;
  for (auto _ : state) {
    spindown::LcmLogReader reader(path);
    spindown::LcmLogEvent ev;
    while (reader.next(ev)) {
      if (ev.kind == spindown::LcmLogEvent::Kind::samples) samples += ev.samples.n;
    }
    events += reader.events_read();
    bytes += reader.file_size();
  }
  state.counters["samples_per_s"] = benchmark::Counter(double(samples), benchmark::Counter::kIsRate);
  state.counters["events_per_s"] = benchmark::Counter(double(events), benchmark::Counter::kIsRate);
  state.SetBytesProcessed(bytes);
}
BENCHMARK(BM_LcmLogReaderEvents)->Unit(benchmark::kMillisecond);

void BM_ReadLcmLog(benchmark::State& state) {
  const std::string& path = lab_log();
  std::int64_t samples = 0;
  for (auto _ : state) {
    const spindown::LcmLogContents c = spindown::read_lcm_log(path);
    for (const auto& b : c.benches) samples += std::int64_t(b.recording.size());
  }
  state.counters["samples_per_s"] = benchmark::Counter(double(samples), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_ReadLcmLog)->Unit(benchmark::kMillisecond);

}  // namespace
