#pragma once
// A bench in software: simulated runs (make_synthetic_run) turned into the exact bytes an
// Arduino would print, each with the time its last byte leaves the wire, plus the faults a
// lab meets (resets, unplugging, garbage, cut lines, over-long lines). spindown-virtual-bench
// writes these to a pseudo-terminal; tests compare what the bridge published with sent().
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "spindown/synthetic_run.hpp"

namespace spindown {

enum class BenchProtocol { lab, spindown_v1 };

struct VirtualBenchOptions {
  BenchProtocol protocol = BenchProtocol::lab;
  int baud = 0;                 // 0: 9600 for lab, 115200 for spindown-v1
  int runs = 1;                 // spin up, steady, cut, coast, stop, tail — repeated
  double idle_s = 1.0;          // motor at rest between runs (reads ~0)
  SyntheticRunSpec spec;        // friction, bench, lead-in, noise, ADC, period, jitter…
  double e0_step_v = 0.0;       // run k starts at e0 + k·step (varied runs)
  double boot_s = 0.3;          // silence after a reset (bootloader) before the sketch runs
  std::string firmware = "spindown-coast";
  std::string version = "1.0.0";
  // Faults, in seconds of bench time since start (negative = never).
  std::vector<double> reset_at_s;
  double unplug_at_s = -1;
  double unplug_for_s = 1.0;
  long garbage_every = 0;       // a garbage line after every N-th sample line
  long partial_every = 0;       // every N-th sample line cut short (its sample is lost)
  double long_line_at_s = -1;
  std::size_t long_line_bytes = 0;  // junk without newline, then CR LF
  std::uint64_t seed = 1;

  int effective_baud() const { return baud ? baud : (protocol == BenchProtocol::lab ? 9600 : 115200); }
  bool is_valid(std::string* why) const;
};

struct BenchEmission {
  enum class Kind { sample, banner, garbage, partial, long_line, unplug };
  Kind kind = Kind::sample;
  double wire_s = 0;          // bench time when the last byte is on the wire
  std::string bytes;          // what to write (empty for unplug)
  double unplug_for_s = 0;    // Kind::unplug: how long the cable stays out
};

// What a correct bridge publishes for one sample line.
struct SentSample {
  std::int32_t epoch = 0;          // device resets before this sample
  std::int64_t device_time_us = 0; // as the bridge unwraps it (millis·1000 or micros)
  double value = 0;                // volts printed (lab) or counts·ref/(2^bits−1) (spindown-v1)
  std::int32_t raw_adc = -1;       // spindown-v1 only
  std::uint32_t device_seq = 0;    // spindown-v1 only
};

class VirtualBench {
 public:
  explicit VirtualBench(VirtualBenchOptions options);  // throws std::invalid_argument
  // Everything the bench will send, in wire order.
  const std::vector<BenchEmission>& emissions() const { return emissions_; }
  const std::vector<SentSample>& sent() const { return sent_; }
  // Parameters, per-run truth (cut and stop device times per epoch) and faults as JSON.
  const nlohmann::json& truth() const { return truth_; }
  double duration_s() const { return emissions_.empty() ? 0.0 : emissions_.back().wire_s; }

 private:
  VirtualBenchOptions o_;
  std::vector<BenchEmission> emissions_;
  std::vector<SentSample> sent_;
  nlohmann::json truth_;
};

// What a UART set to reader_baud makes of bytes sent at sender_baud: framing garbage, about
// reader/sender as many bytes, mostly high bytes, now and then a newline. Deterministic.
std::string garble_for_baud(std::string_view bytes, int sender_baud, int reader_baud, std::uint64_t& state);

}  // namespace spindown
