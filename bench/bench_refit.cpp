// Refit throughput: an LCM log read event by event and fed to FitterCore as `spindown refit`
// does (decode, checks, run detection, the three fits per run), samples per second on one core
// (target ≥ 5 M/s). The log is 4 lab benches with one sample per message as the lab bridge
// publishes (arg 1) or 25 per message (arg 25); 400,000 samples (~260 runs). The whole
// command on a 10 M-sample log, with its memory, is bench/refit_throughput.sh.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <unistd.h>

#include "lab_lcm_log.hpp"
#include "spindown/fitter_core.hpp"
#include "spindown/lcm_log_reader.hpp"

namespace {

constexpr long long log_samples = 400'000;

struct TempLog {
  std::string path;
  explicit TempLog(int batch)
      : path(std::filesystem::temp_directory_path() /
             ("bench_refit." + std::to_string(::getpid()) + "." + std::to_string(batch) + ".lcm")) {
    bench_log::write_lab_lcm_log(path, log_samples, 4, batch);
  }
  ~TempLog() { std::remove(path.c_str()); }
};

const std::string& lab_log(int batch) {
  static std::map<int, std::unique_ptr<TempLog>> logs;
  auto& log = logs[batch];
  if (!log) log = std::make_unique<TempLog>(batch);
  return log->path;
}

struct CountingSink : spindown::FitterSink {
  long fits = 0;
  void run_changed(const spindown::run_t&) override {}
  void fit_ready(const spindown::FitResult&) override { ++fits; }
};

void BM_RefitLog(benchmark::State& state) {
  const std::string& path = lab_log(static_cast<int>(state.range(0)));
  spindown::FitterOptions opt;
  opt.max_rate_hz = 0;  // as refit: a log is read as fast as the disk allows
  std::int64_t samples = 0;
  long fits = 0;
  for (auto _ : state) {
    CountingSink sink;
    spindown::FitterCore core(opt, sink);
    spindown::LcmLogReader reader(path, spindown::LcmSamples::view_only);
    spindown::LcmLogEvent ev;
    std::int64_t last = 0;
    while (reader.next(ev)) {
      // As refit_log: the reader's decoded message goes to the core (decoded once).
      if (ev.kind == spindown::LcmLogEvent::Kind::samples)
        core.on_samples(ev.bench, ev.samples_view, ev.log_utime);
      else if (ev.kind == spindown::LcmLogEvent::Kind::config)
        core.on_config(ev.bench, ev.config, ev.log_utime);
      last = ev.log_utime;
    }
    core.finish(last);
    samples += core.counters().samples;
    fits = sink.fits;
  }
  state.counters["samples_per_s"] = benchmark::Counter(double(samples), benchmark::Counter::kIsRate);
  state.counters["fits"] = double(fits);
}
BENCHMARK(BM_RefitLog)->Arg(1)->Arg(25)->Unit(benchmark::kMillisecond);

}  // namespace
