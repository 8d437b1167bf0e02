#pragma once
// The simulated bench's command-line options, shared by spindown-virtual-bench (to a pseudo-
// terminal) and `spindown simulate` (to a file), so both take the same names for the same
// physics (spindown-avr-bench takes add_motor_options). Header-only: only programs that parse a command line include it (and link CLI11).
#include <CLI/CLI.hpp>
#include <string>

#include "spindown/virtual_bench.hpp"

namespace spindown {

// What the options hold before they become VirtualBenchOptions (names and milliseconds).
struct VirtualBenchCli {
  std::string protocol = "lab", lead_in = "zeros";
  double period_ms = 20, jitter_ms = 0.5;
};

// The motor's physics: J, K_b and the friction terms. Shared with spindown-avr-bench, whose motor
// drives an emulated Arduino's A0, so that every simulated bench names the physics alike.
inline void add_motor_options(CLI::App& app, BenchParams& bench, FrictionTerms& friction) {
  app.add_option("--inertia", bench.inertia_kg_m2, "J (kg*m^2)");
  app.add_option("--kb", bench.kb_v_s_per_rad, "K_b (V*s/rad)");
  app.add_option("--viscous", friction.viscous, "c_v (N*m*s/rad)");
  app.add_option("--coulomb", friction.coulomb, "c_c (N*m)");
  app.add_option("--stribeck-static", friction.stribeck_static, "c_s (N*m)");
  app.add_option("--stribeck-speed", friction.stribeck_speed, "w_s (rad/s)");
  app.add_option("--windage", friction.windage, "c_w (N*m*s^2/rad^2)");
}

// The runs, the bench, friction, the reading and the faults (not the wire: baud, speed, pty).
inline void add_virtual_bench_options(CLI::App& app, VirtualBenchOptions& o, VirtualBenchCli& cli) {
  auto& sp = o.spec;
  app.add_option("--protocol", cli.protocol, "lab (millis<TAB>volts) or spindown-v1")
      ->check(CLI::IsMember({"lab", "spindown-v1"}));
  app.add_option("--runs", o.runs, "runs: spin up, steady, cut, coast, stop, tail");
  app.add_option("--idle", o.idle_s, "seconds at rest between runs");
  app.add_option("--period-ms", cli.period_ms, "loop period (ms)");
  app.add_option("--jitter-ms", cli.jitter_ms, "uniform ± jitter of the period (ms)");
  app.add_option("--e0", sp.e0_v, "back-EMF at the cut (V)");
  app.add_option("--e0-step", o.e0_step_v, "added to e0 at each further run (V)");
  app.add_option("--supply", sp.supply_v, "pin reading before the cut with --lead-in supply (V)");
  app.add_option("--lead-in", cli.lead_in,
                 "what the pin reads before the cut (floating: the handout's step 6, A0 open until it is connected "
                 "after the cut; spin-up: a speed sensor's rise to the peak, cut there)")
      ->check(CLI::IsMember({"zeros", "floating", "supply", "spin-up"}));
  app.add_option("--float-level", sp.float_level_v, "--lead-in floating: the open pin's level (V; default drawn in 0.5-2.5)");
  app.add_option("--pickup", sp.pickup_v, "--lead-in floating: amplitude of the mains hum on the open pin (V; default drawn in 0.05-0.6)");
  app.add_option("--mains-hz", sp.mains_hz, "--lead-in floating: mains frequency (Hz)");
  app.add_option("--connect-s", sp.connect_s, "--lead-in floating: seconds from the cut to the pin's connection (default drawn in 0-1)");
  app.add_option("--bounce", sp.bounce_samples, "--lead-in floating: samples of contact bounce at the connection (default drawn 0-3)");
  app.add_option("--spin-up-s", sp.spin_up_s, "--lead-in spin-up: seconds of the rise (0.3: by hand)");
  app.add_option("--start-s", sp.start_s, "the recording starts this long after the cut (mid-coast)");
  app.add_option("--gap-from-s", sp.gap_from_s, "a pause in the recording from this long after the cut (< 0: before)");
  app.add_option("--gap-s", sp.gap_s, "seconds the recording pauses (no samples)");
  app.add_option("--glitches", sp.glitches, "single bad coasting samples: dropouts (0) and glitches (half)");
  app.add_option("--pulses-per-rev", sp.pulses_per_rev, "a per-revolution speed sensor: pulses per turn (0: none)");
  app.add_option("--pulse-timeout-s", sp.pulse_timeout_s, "per-revolution sensor: reads 0 after this long without a pulse (< 0: freezes on its last value)");
  app.add_option("--lead-in-s", sp.lead_in_s, "seconds recorded before the cut");
  app.add_option("--tail-s", sp.tail_s, "seconds recorded after the stop");
  app.add_option("--max-coast-s", sp.max_coast_s, "longest coast simulated");
  add_motor_options(app, sp.bench, sp.friction);
  app.add_option("--offset", sp.offset_v, "sensor offset after the cut (V)");
  app.add_option("--noise", sp.noise_v, "white noise (V)");
  app.add_option("--ripple", sp.ripple, "relative commutator ripple");
  app.add_option("--adc-bits", sp.adc_bits, "ADC bits (0 = no quantization)");
  app.add_option("--decimals", sp.decimals, "decimals the lab sketch prints");
  app.add_option("--seed", sp.seed, "random seed");
  app.add_option("--firmware", o.firmware, "firmware name in the spindown-v1 banner");
  app.add_option("--reset-at", o.reset_at_s, "bench seconds at which the Arduino resets (repeatable)");
  app.add_option("--unplug-at", o.unplug_at_s, "bench seconds at which the cable is pulled");
  app.add_option("--unplug-for", o.unplug_for_s, "seconds the cable stays out");
  app.add_option("--garbage-every", o.garbage_every, "a garbage line after every N-th sample line");
  app.add_option("--partial-every", o.partial_every, "every N-th sample line cut short");
  app.add_option("--long-line-at", o.long_line_at_s, "bench seconds at which an over-long line is sent");
  app.add_option("--long-line-bytes", o.long_line_bytes, "bytes of that line (no newline until its end)");
}

// After parsing: the names and milliseconds into o.
inline void apply_virtual_bench_cli(const VirtualBenchCli& cli, VirtualBenchOptions& o) {
  o.protocol = cli.protocol == "lab" ? BenchProtocol::lab : BenchProtocol::spindown_v1;
  o.spec.lead_in = cli.lead_in == "zeros"     ? LeadIn::zeros
                   : cli.lead_in == "supply"  ? LeadIn::supply
                   : cli.lead_in == "spin-up" ? LeadIn::spin_up
                                              : LeadIn::floating;
  o.spec.period_s = cli.period_ms / 1000.0;
  o.spec.jitter_s = cli.jitter_ms / 1000.0;
  o.seed = o.spec.seed;
}

}  // namespace spindown
