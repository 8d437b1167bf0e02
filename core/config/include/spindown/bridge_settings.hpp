#pragma once
// Everything spindown-bridge needs to know about its bench and port, with the lab's defaults,
// and the TOML file that sets them (keys documented in services/bridge/README.md):
//
//   bench_id = "bench-3"              # CLI --bench wins
//   [serial]  device = "/dev/ttyACM0"  baud = 9600  max_line_bytes = 1024
//   [bench]   inertia_kg_m2 = 1.12687602e-5  inertia_source = "…"
//             (or flywheel_radius_m, flywheel_height_m, flywheel_density_kg_m3, rotor_inertia_kg_m2)
//             kb_v_s_per_rad = 0.0080926  kb_source = "…"  (or speed_constant_rpm_per_v = 1180)
//             quantity = "V" | "rpm" | "rad/s"
//   [adc]     bits = 10  ref_v = 5.0
//   [lab]     period_s = 0.020
//   [publish] max_batch = 32  config_interval_s = 3.0  status_interval_s = 1.0
#include <cstddef>
#include <string>

#include "spindown/bench.hpp"
#include "spindown/quantity.hpp"

namespace spindown {

struct BridgeSettings {
  std::string bench;
  std::string device;
  int baud = 9600;
  BenchParams params;                        // J, K_b (lab defaults)
  Quantity quantity = Quantity::back_emf_volts;
  int adc_bits = 10;                         // the lab sketch's converter, for config_t
  double adc_ref_v = 5.0;
  double lab_period_s = 0.020;               // the lab sketch's loop period
  std::size_t max_line_bytes = 1024;         // longer lines are discarded and counted
  std::size_t max_batch = 32;                // samples per SAMPLE message at most
  double config_interval_s = 3.0;
  double status_interval_s = 1.0;
  std::string host;                          // for config/status; empty = gethostname()
  int pid = 0;                               // for status; 0 = getpid()

  // Checks ranges; false with the reason in why.
  bool is_valid(std::string* why) const;
};

// Reads the TOML file into settings (keys it does not set keep their values). Throws
// std::runtime_error naming the file, the key and what was wrong.
void load_bridge_settings(const std::string& path, BridgeSettings& settings);

}  // namespace spindown
