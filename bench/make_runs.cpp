// make_runs: writes generated lab runs as the Arduino sketch prints them (PuTTY log, millis<TAB>
// volts, 10-bit ADC on 5 V, 2 decimals, CR LF), one file per run, for the side-by-side with
// SciPy (bench/fit_vs_scipy.sh). Beside them, index.tsv names each file with the truth a
// hand fit would be given for free: the cut and stop on the file's clock, J, K_b, c_v, c_c.
//
// usage: make_runs OUT_DIR [COUNT=1000] [SEED=1]
// Runs differ in seed (noise, jitter), back-EMF at the cut (2.5–3.3 V) and lead-in kind
// (zeros, floating pin, supply); friction is the lab's 3 V run (design §1), noise 4 mV and
// 1 % commutator ripple as in data/seed-3v-run1, ~1500 samples per file.
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <iostream>
#include <string>

#include "spindown/synthetic_run.hpp"

int main(int argc, char** argv) {
  if (argc < 2 || argc > 4) {
    std::cerr << "usage: make_runs OUT_DIR [COUNT=1000] [SEED=1]\n";
    return 2;
  }
  const std::filesystem::path dir = argv[1];
  const long count = argc > 2 ? std::strtol(argv[2], nullptr, 10) : 1000;
  const long seed = argc > 3 ? std::strtol(argv[3], nullptr, 10) : 1;
  if (count < 1 || count > 1'000'000 || seed < 0) {
    std::cerr << "make_runs: COUNT must be 1…1000000 and SEED ≥ 0\n";
    return 2;
  }
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) {
    std::cerr << fmt::format("make_runs: cannot create {}: {}\n", dir.string(), ec.message());
    return 1;
  }
  std::ofstream index(dir / "index.tsv");
  index << "file\tt_cut_s\tt_stop_s\tJ\tKb\tc_v\tc_c\te0\tsamples\n";
  std::size_t samples = 0;
  for (long i = 0; i < count; ++i) {
    spindown::SyntheticRunSpec spec;  // the lab's bench and friction (c_v 1.822e-7, c_c 1.1389e-4)
    spec.seed = static_cast<std::uint64_t>(seed * 1'000'003 + i);
    spec.e0_v = 2.5 + 0.8 * static_cast<double>((i * 7919) % 1000) / 1000.0;
    spec.supply_v = spec.e0_v + 0.2;
    spec.lead_in = spindown::LeadIn(i % 3);
    spec.lead_in_s = 1.0;
    spec.tail_s = 2.0;
    spec.noise_v = 0.004;
    spec.ripple = 0.01;
    const spindown::SyntheticRun run = spindown::make_synthetic_run(spec);
    const std::string name = fmt::format("run{:05d}.txt", i + 1);
    std::ofstream out(dir / name, std::ios::binary);
    out << spindown::to_arduino_text(run, 2, true);
    if (!out) {
      std::cerr << fmt::format("make_runs: cannot write {}\n", (dir / name).string());
      return 1;
    }
    samples += run.t_ms.size();
    index << fmt::format("{}\t{:.6f}\t{:.6f}\t{:.9g}\t{:.9g}\t{:.9g}\t{:.9g}\t{:.4f}\t{}\n", name,
                         run.t_cut_ms / 1000.0, run.t_cut_ms / 1000.0 + run.t_stop_s, spec.bench.inertia_kg_m2,
                         spec.bench.kb_v_s_per_rad, spec.friction.viscous, spec.friction.coulomb, spec.e0_v,
                         run.t_ms.size());
  }
  if (!index) {
    std::cerr << "make_runs: cannot write index.tsv\n";
    return 1;
  }
  std::cout << fmt::format("{} runs, {} samples ({:.0f} per run) in {}\n", count, samples,
                           double(samples) / double(count), dir.string());
  return 0;
}
