// make_lcm_log: writes a large LCM event log of lab traffic (bench/lab_lcm_log.hpp) for the
// refit throughput benchmark (bench/refit_throughput.sh). Written straight to the file with
// lcm::LogFile (no network, no drops, deterministic): the bytes a logger writes, at disk speed
// rather than in real time.
//
// usage: make_lcm_log OUT.lcm SAMPLES [BENCHES=4] [BATCH=1]
#include <cstdlib>
#include <exception>
#include <fmt/format.h>
#include <iostream>

#include "lab_lcm_log.hpp"

int main(int argc, char** argv) {
  if (argc < 3 || argc > 5) {
    std::cerr << "usage: make_lcm_log OUT.lcm SAMPLES [BENCHES=4] [BATCH=1]\n";
    return 2;
  }
  const long long total = std::strtoll(argv[2], nullptr, 10);
  const int benches = argc > 3 ? std::atoi(argv[3]) : 4;
  const int batch = argc > 4 ? std::atoi(argv[4]) : 1;
  if (total < 1 || total > 2'000'000'000LL || benches < 1 || benches > 1000 || batch < 1 || batch > 1000) {
    std::cerr << "make_lcm_log: SAMPLES 1…2e9, BENCHES 1…1000, BATCH 1…1000\n";
    return 2;
  }
  try {
    const auto st = bench_log::write_lab_lcm_log(argv[1], total, benches, batch);
    std::cout << fmt::format("{}: {} samples in {} SAMPLE messages, {} benches, {} runs begun\n", argv[1], st.samples,
                             st.messages, benches, st.runs);
  } catch (const std::exception& e) {
    std::cerr << fmt::format("make_lcm_log: {}: {}\n", argv[1], e.what());
    return 1;
  }
  return 0;
}
