#pragma once
// What the FitterCore tests share: a sink that keeps everything, generated streams of runs on
// one device clock, and samples_t batches fed through the service's path.
#include <fmt/format.h>

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "spindown/fit_message.hpp"
#include "spindown/fitter_core.hpp"
#include "spindown/synthetic_run.hpp"
#include "lab_messages.hpp"

namespace spindown::test {

struct CollectingSink : FitterSink {
  std::vector<std::pair<std::string, Diagnostic>> diagnostics;
  void diagnostic(const std::string& bench, const Diagnostic& d) override { diagnostics.emplace_back(bench, d); }
  std::vector<FitResult> fits;          // spans cleared: only valid during the call
  std::vector<run_t> runs;
  std::vector<std::string> problems;
  void run_changed(const run_t& r) override { runs.push_back(r); }
  void fit_ready(const FitResult& r) override {
    FitResult copy = r;
    copy.t_s = {};
    copy.value = {};
    fits.push_back(std::move(copy));
  }
  void problem(const std::string& text) override { problems.push_back(text); }
  std::vector<const FitResult*> of(const std::string& bench) const {
    std::vector<const FitResult*> out;
    for (const auto& f : fits)
      if (f.bench == bench) out.push_back(&f);
    return out;
  }
};

// Two runs back to back on one device clock, as (t_us, volts).
struct Stream {
  std::vector<std::int64_t> t_us;
  std::vector<double> v;
};
inline Stream make_stream(int runs, std::uint64_t seed, double e0 = 2.8) {
  Stream s;
  double t0_ms = 1000;
  for (int r = 0; r < runs; ++r) {
    SyntheticRunSpec spec;
    spec.seed = seed + r;
    spec.e0_v = e0 + 0.2 * r;
    spec.t0_ms = t0_ms;
    const SyntheticRun run = make_synthetic_run(spec);
    for (std::size_t i = 0; i < run.t_ms.size(); ++i) {
      s.t_us.push_back(std::llround(run.t_ms[i] * 1000));
      s.v.push_back(run.volts[i]);
    }
    t0_ms = run.t_ms.back() + 20;
  }
  return s;
}

inline samples_t batch(const std::string& bench, const Stream& s, std::size_t from, std::size_t n, std::int64_t seq) {
  samples_t m{};  // every field zero (lcm-gen types leave them uninitialised)
  m.bench = bench;
  m.seq = seq;
  m.quantity = samples_t::QUANTITY_BACK_EMF_V;
  for (std::size_t i = from; i < from + n && i < s.t_us.size(); ++i) {
    m.device_time_us.push_back(s.t_us[i]);
    m.host_time_us.push_back(0);
    m.value.push_back(s.v[i]);
    m.raw_adc.push_back(-1);
  }
  m.n = static_cast<std::int32_t>(m.value.size());
  return m;
}

inline std::vector<unsigned char> encode(const samples_t& m) {
  std::vector<unsigned char> buf(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(buf.data(), 0, static_cast<int>(buf.size()));
  return buf;
}

// Feeds a whole stream in batches of `per` samples through on_message (the service's path).
inline void feed(FitterCore& core, const std::string& bench, const Stream& s, std::size_t per, std::int64_t& utime) {
  std::int64_t seq = 0;
  for (std::size_t i = 0; i < s.t_us.size(); i += per) {
    const auto bytes = encode(batch(bench, s, i, per, seq));
    seq += static_cast<std::int64_t>(std::min(per, s.t_us.size() - i));
    utime += 20000 * static_cast<std::int64_t>(per);
    core.on_message("SPINDOWN." + bench + ".SAMPLE", bytes.data(), static_cast<std::int64_t>(bytes.size()), utime);
  }
}

}  // namespace spindown::test
