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
#include <vector>

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
  // What the file says that is usable but doubtful, one sentence each naming the file and keys
  // (kb_disagreement): every program that reads the file prints them.
  std::vector<std::string> warnings;

  // Checks ranges; false with the reason in why.
  bool is_valid(std::string* why) const;
};

// A back-EMF constant and a motor's datasheet constant that disagree beyond what either is known
// to: [bench] K_b (kb_v_s_per_rad or speed_constant_rpm_per_v) against [motor]
// speed_constant_rpm_per_v and torque_constant_nm_per_a (k_M in N·m/A equals K_b in V·s/rad for a
// DC motor). A datasheet gives both constants of one motor to 3–4 digits, so a K_b derived from it
// agrees to 0.1 %; one measured on the bench lies within the motor's tolerance, which the file
// states as kb_error_pct (a standard uncertainty). Beyond max(kb_disagreement_floor, 2 ×
// kb_error_pct) the two describe different motors or one was copied wrong.
inline constexpr double kb_disagreement_floor = 0.02;
// The warning for file path ("" when they agree or the file gives only one of them): the values,
// by how much they disagree, which one spindown uses and why.
std::string kb_disagreement(const std::string& path, double bench_kb_v_s_per_rad, const std::string& bench_kb_key,
                            double kb_rel_error, double motor_constant, const std::string& motor_key);

// Reads the TOML file into settings (keys it does not set keep their values). Throws
// std::runtime_error naming the file, the key and what was wrong.
void load_bridge_settings(const std::string& path, BridgeSettings& settings);

}  // namespace spindown
