#pragma once
// Synthetic spin-down recordings as a real bench produces them: lead-in before the cut
// (zeros, a floating pin or the supply voltage), the coast from the simulator, sensor
// offset, commutator ripple, white noise, 10-bit ADC, 2-decimal printing, loop period with
// jitter. Used by the virtual bench, by tests and by benchmarks.
#include <cmath>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "spindown/bench.hpp"
#include "spindown/friction.hpp"

namespace spindown {

// zeros, supply: what the pin reads while the motor is powered, the reading jumping to the
// back-EMF at the cut (the lab's rig). floating: the handout's own procedure (step 6: "immediately
// after the motor is switched off, connect the analog pin to the motor"): until the pin is
// connected, a moment after the cut, A0 floats — a high-impedance input whose jumper picks up the
// mains (a level anywhere in 0.5–2.5 V, the 50 Hz hum aliased by the sketch's ~20 ms loop into a
// slow beat, a slow drift) — then a few samples of contact bounce, then the back-EMF of a coast
// already under way. spin_up: a speed sensor (tachometer, encoder) on a rig spun up by a motor ramp
// or by hand: at rest, then over the last spin_up_s of the lead-in the reading rises to e0 and the
// supply is cut at the peak, with no steady plateau.
enum class LeadIn { zeros, floating, supply, spin_up };

struct SyntheticRunSpec {
  BenchParams bench;
  FrictionTerms friction{1.822e-7, 1.1389e-4};
  double e0_v = 2.8;           // back-EMF at the cut
  double supply_v = 3.0;       // what the pin reads before the cut with LeadIn::supply
  // LeadIn::floating, each drawn from the run's seed (its own random stream) when NaN or negative:
  double float_level_v = NAN;  // the floating pin's mean level (drawn in 0.5–2.5 V)
  double pickup_v = NAN;       // amplitude of the mains hum it picks up (drawn in 0.05–0.6 V)
  double mains_hz = 50.0;      // the mains frequency (60 in the Americas)
  double connect_s = NAN;      // the pin is connected this long after the cut (drawn in 0–1 s)
  int bounce_samples = -1;     // samples of contact bounce at the connection (drawn 0–3)
  LeadIn lead_in = LeadIn::zeros;
  double lead_in_s = 3.0;      // recorded time before the cut
  double tail_s = 3.0;         // recorded time after the stop (or after max_coast_s)
  double max_coast_s = 120.0;  // stop recording a coast that does not stop by then
  double period_s = 0.020;     // loop period
  double jitter_s = 0.0005;    // uniform ± jitter on each period
  double noise_v = 0.003;      // white noise on the reading (V, before the ADC)
  double ripple = 0.0;         // relative commutator ripple
  int ripple_per_rev = 6;      // ripple cycles per revolution
  double offset_v = 0.0;       // sensor offset after the cut
  int adc_bits = 10;           // 0 = no ADC quantization
  bool adc_floor = false;      // true: truncating converter (−½ LSB bias); false: rounds to nearest
  double adc_ref_v = 5.0;
  bool sketch_gain = false;    // true: volts = counts·Vref/1023 as the lab sketch prints (+0.1 % gain)
  int decimals = 2;            // printing; negative = full precision
  double t0_ms = 5234;         // device time of the first sample
  std::uint64_t seed = 1;
  // What other rigs' recordings hold (all off by default; each leaves the random stream of the
  // others untouched when off).
  double spin_up_s = 3.0;      // LeadIn::spin_up: seconds of the rise (0.3: by hand; lead_in_s: a ramp)
  double start_s = 0.0;        // > 0: the recording starts this long after the cut (mid-coast, no lead-in)
  double gap_from_s = 0.0;     // no samples in [cut + gap_from_s, cut + gap_from_s + gap_s): the logger paused
  double gap_s = 0.0;
  int glitches = 0;            // coasting samples replaced by a dropout (0) or a glitch (half the value)
  int pulses_per_rev = 0;      // > 0: a per-revolution sensor: the speed is measured once per pulse and held
  double pulse_timeout_s = 0;  // per-revolution sensor: reads 0 after this long without a pulse; negative:
                               // freezes on its last value after -pulse_timeout_s (0: holds between pulses)
};

struct SyntheticRun {
  std::vector<double> t_ms;   // device time of each sample (integer ms as the sketch prints)
  std::vector<double> volts;  // the printed value
  std::vector<int> adc;       // raw ADC counts (−1 when not quantized)
  double t_cut_ms = 0;        // device time of the power cut
  // Device time the coast begins in the readings: the cut, or with LeadIn::floating the moment the
  // pin was connected to the motor after it (the cut itself is not in the readings then).
  double t_connect_ms = 0;
  double t_stop_s = 0;        // seconds from the cut to the stop (or max_coast_s)
  double omega0 = 0;          // rad/s at the cut
  bool stopped = false;
  // Truth for run finding, in the recording's own samples.
  std::vector<std::size_t> glitch_index;  // samples replaced by a dropout or glitch
  std::vector<std::size_t> bounce_index;  // LeadIn::floating: samples read while the contact bounced, off
                                          // what the motor reads (by over 3 % or 4 noise sd)
  double t_signal_lost_ms = -1;  // per-revolution sensor: device time of its last pulse before it gave up
                                 // (read 0) or froze on its last value (-1: never)
};

SyntheticRun make_synthetic_run(const SyntheticRunSpec& spec);

// The Arduino sketch's text: "millis\tvolts\r\n" per sample, optionally after a PuTTY header.
std::string to_arduino_text(const SyntheticRun& run, int decimals = 2, bool putty_header = false);

// The header line a PuTTY log starts with (as the lab's logs do), CR LF included.
inline constexpr std::string_view putty_log_header =
    "=~=~=~=~=~=~=~=~=~=~=~= PuTTY log 2023.09.14 10:21:33 =~=~=~=~=~=~=~=~=~=~=~=\r\n";

// A reading as printed: `decimals` places, or with a negative count every digit needed to read
// the same double back (SyntheticRunSpec::decimals: "negative = full precision").
std::string printed_value(double v, int decimals);

}  // namespace spindown
