#pragma once
// A large, varied set of recordings for the run detector, and a canonical text of everything
// the detector says about one: every event (all Run fields, diagnostics, the sample at which it
// came) and its buffered()/state() after every sample (the live fitter mirrors the buffer).
// Used to show that a faster detector finds exactly the same runs as the one it replaces
// (tests/test_run_detector_corpus.cpp; a checker build can plug in a copy of the old detector
// through the Detector template parameter).
#include <cmath>
#include <cstdint>
#include <fmt/format.h>
#include <random>
#include <string>
#include <vector>

#include "spindown/read_recording.hpp"
#include "spindown/recording.hpp"
#include "spindown/run_detector.hpp"
#include "spindown/runs.hpp"
#include "spindown/synthetic_run.hpp"

namespace spindown::corpus {

struct Case {
  std::string name;
  Recording rec;
  RunOptions opt;
};

inline void append(Recording& rec, const SyntheticRun& s, double t_shift_s = 0.0) {
  for (std::size_t i = 0; i < s.t_ms.size(); ++i) rec.push(s.t_ms[i] / 1000.0 + t_shift_s, s.volts[i]);
}

// One generated run's spec, varied by the case number k and a random stream.
inline SyntheticRunSpec varied_spec(int k, std::mt19937_64& rng) {
  auto pick = [&](auto... xs) {
    const double v[] = {double(xs)...};
    return v[rng() % sizeof...(xs)];
  };
  SyntheticRunSpec s;
  s.seed = 1000 + std::uint64_t(k);
  s.lead_in = LeadIn(k % 3);
  switch ((k / 3) % 6) {  // friction: lab's combined, Coulomb, pure viscous, windage, Stribeck, scaled
    case 0: break;
    case 1: s.friction = {0.0, 1.5e-4}; break;
    case 2: s.friction = {pick(2e-7, 6e-7, 1.5e-6), 0.0}; break;
    case 3: s.friction = {1e-7, 8e-5, 0, 0, 2e-9}; break;
    case 4: s.friction = {1.822e-7, 1.1389e-4, 1.6e-4, 8.0}; break;
    case 5: s.friction = {pick(0.5e-7, 4e-7), pick(0.3e-4, 3e-4)}; break;
  }
  s.e0_v = pick(2.8, 1.2, 3.3, 0.4);
  s.supply_v = s.e0_v + pick(0.2, 0.05, -0.1, 0.5);
  s.lead_in_s = pick(3.0, 1.0, 0.0, 0.3, 8.0);
  s.tail_s = pick(3.0, 2.0, 0.0, 0.5, 6.0);
  s.max_coast_s = pick(120.0, 20.0, 6.0);
  s.period_s = pick(0.020, 0.020, 0.005, 0.050, 0.100);
  s.jitter_s = pick(0.0005, 0.0, 0.002) * s.period_s / 0.02;
  s.noise_v = pick(0.003, 0.0, 0.001, 0.01, 0.03);
  s.ripple = pick(0.0, 0.01, 0.05);
  s.offset_v = pick(0.0, 0.0, 0.02, -0.01);
  s.adc_bits = int(pick(10, 10, 12, 0, 8));
  s.adc_floor = rng() % 4 == 0;
  s.adc_ref_v = pick(5.0, 5.0, 3.3, 2.5);  // 2.5 V clips a 2.8 V coast: a pinned start
  s.sketch_gain = rng() % 3 == 0;
  s.decimals = int(pick(2, 2, 3, -1));
  s.t0_ms = pick(5234, 0, 123456);
  return s;
}

// Runs ending before their stop, samples lost in bursts, NaNs, clock restarts (declared and not).
inline void mangle(Recording& rec, int k, std::mt19937_64& rng) {
  const std::size_t n = rec.size();
  if (n < 20) return;
  switch (k % 7) {
    case 0: break;
    case 1: {  // recording ends mid-coast
      const std::size_t keep = n / 3 + rng() % (n / 2);
      rec.t_s.resize(keep);
      rec.value.resize(keep);
      break;
    }
    case 2: {  // packet loss: bursts of samples missing
      Recording out;
      for (std::size_t i = 0; i < n;) {
        if (rng() % 40 == 0) {
          i += 1 + rng() % 30;
          continue;
        }
        out.push(rec.t_s[i], rec.value[i]);
        ++i;
      }
      rec.t_s = std::move(out.t_s);
      rec.value = std::move(out.value);
      break;
    }
    case 3: {  // non-finite samples
      for (int j = 0; j < 5; ++j) {
        const std::size_t at = rng() % n;
        (j % 2 ? rec.value : rec.t_s)[at] = j % 3 ? NAN : INFINITY;
      }
      break;
    }
    case 4: {  // device reset mid-recording, declared by the reader
      const std::size_t at = n / 4 + rng() % (n / 2);
      const double shift = rec.t_s[at] - 0.5;
      for (std::size_t i = at; i < n; ++i) rec.t_s[i] -= shift;
      rec.clock_restarts.push_back(at);
      break;
    }
    case 5: {  // time goes back without a declared restart
      const std::size_t at = n / 4 + rng() % (n / 2);
      for (std::size_t i = at; i < n; ++i) rec.t_s[i] -= 3.0;
      break;
    }
    case 6: {  // a stall: the same reading repeated (pinned converter mid-stream)
      const std::size_t at = rng() % (n - 10), len = 5 + rng() % 60;
      for (std::size_t i = at + 1; i < std::min(n, at + len); ++i) rec.value[i] = rec.value[at];
      break;
    }
  }
}

inline RunOptions varied_options(int k) {
  RunOptions o;
  switch (k % 11) {
    case 3: o.stop_hold_s = 0.5; break;
    case 5: o.stop_hold_s = 2.0; o.tail_s = 0.0; break;
    case 7: o.max_buffer = 400; break;
    case 9: o.max_coast_s = 8.0; o.min_coast_s = 1.0; break;
    case 10: o.min_samples = 200; break;
    default: break;
  }
  return o;
}

// The shared sample data, then `generated` synthetic recordings (single runs, and every fifth
// one several runs back to back), mangled in turn.
inline std::vector<Case> make_cases(const std::string& shared_data_dir, int generated) {
  std::vector<Case> cases;
  for (const char* f : {"offset-example.tsv", "seed-3v-run1.tsv", "seed-3v5-run2.tsv", "stribeck-example.tsv",
                        "supply-leadin.tsv", "viscous-only.tsv", "windage-example.tsv"}) {
    for (Recording& r : read_recordings(shared_data_dir + "/" + f)) {
      r.source = f;  // diagnostics name it: the same text wherever the data lies
      cases.push_back({f, std::move(r), {}});
    }
  }
  std::mt19937_64 rng(20261122);
  for (int k = 0; k < generated; ++k) {
    Case c;
    c.name = fmt::format("generated {}", k);
    const int runs = k % 5 == 4 ? 2 + int(rng() % 3) : 1;
    double t_shift = 0;
    for (int r = 0; r < runs; ++r) {
      SyntheticRunSpec spec = varied_spec(k * 7 + r, rng);
      if (r > 0) spec.t0_ms = 0;
      const SyntheticRun s = make_synthetic_run(spec);
      append(c.rec, s, t_shift);
      t_shift = c.rec.t_s.back() + spec.period_s;
    }
    mangle(c.rec, k, rng);
    c.opt = varied_options(k);
    cases.push_back(std::move(c));
  }
  return cases;
}

// FNV-1a over text, continuing from h.
inline std::uint64_t fnv1a(std::uint64_t h, const std::string& text) {
  for (unsigned char c : text) h = (h ^ c) * 1099511628211ull;
  return h;
}

inline std::string describe(const Run& r) {
  return fmt::format("#{} cut {} stop {} end {} t_cut {:a} t_stop {:a} stopped {} zero {:a} noise {:a} lead {} period {:a}",
                     r.number, r.cut_index, r.stop_index, r.end_index, r.t_cut_s, r.t_stop_s, r.stopped, r.zero_level,
                     r.noise_level, r.lead_in, r.period_s);
}

inline std::string describe(const Diagnostic& d) {
  return fmt::format("[{} {} {}] {}", int(d.severity), d.source, d.line, d.message);
}

// Everything find_runs returns.
inline std::string describe(const Segmentation& seg) {
  std::string out;
  for (const Run& r : seg.runs) out += "run " + describe(r) + "\n";
  for (const Diagnostic& d : seg.diagnostics) out += "diag " + describe(d) + "\n";
  return out;
}

// The streaming detector fed sample by sample as the live fitter feeds it: every event, when
// it came, and a running hash of state() and buffered() after each sample.
template <class Detector, class Event = RunEvent>
std::string stream_events(const Recording& rec, const RunOptions& opt) {
  Detector det(opt, rec.source);
  std::string out;
  std::uint64_t h = 1469598103934665603ull;
  auto mix = [&](std::uint64_t x) { h = (h ^ x) * 1099511628211ull; };
  auto take = [&](std::size_t at) {
    for (const Event& e : det.take_events()) {
      out += fmt::format("@{} kind {} {}", at, int(e.kind), describe(e.run));
      if (e.has_diagnostic) out += " " + describe(e.diagnostic);
      out += "\n";
    }
  };
  std::size_t restart = 0;
  for (std::size_t i = 0; i < rec.size(); ++i) {
    if (restart < rec.clock_restarts.size() && rec.clock_restarts[restart] == i) {
      det.clock_restart();
      ++restart;
    }
    det.push(rec.t_s[i], rec.value[i]);
    take(i);
    mix(det.buffered());
    mix(std::uint64_t(det.state()));
  }
  det.finish();
  take(rec.size());
  out += fmt::format("buffer/state hash {:016x}\n", h);
  return out;
}

}  // namespace spindown::corpus
