#include "spindown/synthetic_run.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <optional>
#include <random>

#include "spindown/coast_simulator.hpp"

namespace spindown {

namespace {

// Single bad samples in the coast's middle 90 %, apart from each other: a dropout (the reading 0)
// or a glitch (half of it), as a loose connector or a missed pulse gives. Their own random
// stream, so the rest of the recording is the one without them.
void add_glitches(SyntheticRun& out, const SyntheticRunSpec& s) {
  const double from_ms = out.t_cut_ms + 0.05 * 1000.0 * out.t_stop_s, to_ms = out.t_cut_ms + 0.95 * 1000.0 * out.t_stop_s;
  std::vector<std::size_t> coast;
  for (std::size_t i = 0; i < out.t_ms.size(); ++i)
    if (out.t_ms[i] > from_ms && out.t_ms[i] < to_ms && out.volts[i] > 0) coast.push_back(i);
  if (coast.size() < 10u * std::size_t(s.glitches)) return;
  std::mt19937_64 rng(s.seed ^ 0x5bd1e995u);
  const std::size_t stride = coast.size() / std::size_t(s.glitches);
  for (int g = 0; g < s.glitches; ++g) {
    const std::size_t i = coast[std::size_t(g) * stride + 1 + rng() % (stride - 2)];
    const double factor = g % 2 == 0 ? 0.0 : 0.5;
    out.volts[i] = std::round(out.volts[i] * factor * 1e6) / 1e6;
    if (out.adc[i] >= 0) out.adc[i] = int(out.adc[i] * factor);
    out.glitch_index.push_back(i);
  }
}

// The floating pin of the handout's step 6, until it is connected: its level, hum and drift, and
// the connection with its bounce. Drawn from its own random stream, so the rest of the recording
// is the one another lead-in would give.
struct FloatingPin {
  double level, pickup, phase, connect_s;
  int bounce;
  double drift = 0;
  std::mt19937_64 rng;
  std::normal_distribution<double> gauss{0.0, 1.0};
  FloatingPin(const SyntheticRunSpec& s) : rng(s.seed ^ 0xf10a7196ull) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    level = std::isfinite(s.float_level_v) ? s.float_level_v : 0.5 + 2.0 * u(rng);
    pickup = std::isfinite(s.pickup_v) ? s.pickup_v : 0.05 + 0.55 * u(rng);
    phase = 2 * M_PI * u(rng);
    connect_s = std::isfinite(s.connect_s) ? s.connect_s : u(rng);
    bounce = s.bounce_samples >= 0 ? s.bounce_samples : int(rng() % 4);
  }
  // What the open pin reads at device time t_ms: the level, a slow drift (a random walk pulled back
  // over ~2 s), the hum at the sampling instant (the loop's period aliases it), noise.
  double read(double t_ms, double period_s, double mains_hz, double noise_v) {
    const double pull = std::min(1.0, period_s / 2.0);
    drift = (1.0 - pull) * drift + 0.02 * std::sqrt(period_s / 0.02) * gauss(rng);
    return level + drift + pickup * std::sin(2 * M_PI * mains_hz * t_ms / 1000.0 + phase) + noise_v * gauss(rng);
  }
  // A sample taken while the contact bounces: part way between the open pin and the motor.
  double bounced(double open, double motor) {
    return open + std::uniform_real_distribution<double>(0.0, 1.0)(rng) * (motor - open);
  }
};

}  // namespace

SyntheticRun make_synthetic_run(const SyntheticRunSpec& s) {
  SyntheticRun out;
  std::mt19937_64 rng(s.seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);

  out.omega0 = s.e0_v / s.bench.kb_v_s_per_rad;
  // A recording that starts mid-coast has no lead-in: its first sample is start_s after the cut.
  const bool mid_coast = s.start_s > 0;
  out.t_cut_ms = mid_coast ? s.t0_ms - s.start_s * 1000.0 : s.t0_ms + s.lead_in_s * 1000.0;
  CoastSimulator sim(s.friction, s.bench.inertia_kg_m2, out.omega0);
  const double gap_from_ms = out.t_cut_ms + s.gap_from_s * 1000.0, gap_to_ms = gap_from_ms + s.gap_s * 1000.0;
  // A per-revolution sensor: the speed measured from the last two pulses, held in between.
  const double pulse_angle = s.pulses_per_rev > 0 ? 2.0 * M_PI / s.pulses_per_rev : 0.0;
  double prev_angle = 0, prev_tau = 0, last_pulse = 0, held_omega = out.omega0, frozen_omega = 0;
  bool lost = false;

  const int adc_max = s.adc_bits > 0 ? (1 << s.adc_bits) - 1 : 0;
  const double p10 = s.decimals >= 0 ? std::pow(10.0, s.decimals) : 0.0;
  std::optional<FloatingPin> pin;
  if (s.lead_in == LeadIn::floating && !mid_coast) pin.emplace(s);
  out.t_connect_ms = pin ? out.t_cut_ms + 1000.0 * pin->connect_s : out.t_cut_ms;
  int bounces_left = pin ? pin->bounce : 0;
  double t_real_ms = s.t0_ms;
  for (std::size_t guard = 0; guard < 50'000'000; ++guard) {
    if (s.gap_s > 0 && t_real_ms >= gap_from_ms && t_real_ms < gap_to_ms) {  // the logger paused
      t_real_ms += 1000.0 * (s.period_s + s.jitter_s * unit(rng));
      continue;
    }
    double v = 0.0;
    if (t_real_ms < out.t_cut_ms) {
      switch (s.lead_in) {
        case LeadIn::spin_up: {
          // At rest, then a concave rise (a motor's ramp, a hand's push) that still climbs at the cut.
          const double u = 1.0 - (out.t_cut_ms - t_real_ms) / (1000.0 * s.spin_up_s);
          v = u > 0 ? s.e0_v * (1.0 - std::exp(-3.0 * u)) / (1.0 - std::exp(-3.0)) : 0.0;
          v += s.noise_v * gauss(rng);
          break;
        }
        case LeadIn::zeros: v = 0.0; break;
        case LeadIn::supply: v = s.supply_v + s.noise_v * gauss(rng); break;
        case LeadIn::floating: v = pin ? pin->read(t_real_ms, s.period_s, s.mains_hz, s.noise_v) : 0.0; break;
      }
    } else if (pin && t_real_ms < out.t_connect_ms) {
      v = pin->read(t_real_ms, s.period_s, s.mains_hz, s.noise_v);  // the motor coasts, the pin is still open
      const double tau = (t_real_ms - out.t_cut_ms) / 1000.0;
      if (tau > sim.time()) sim.advance(tau - sim.time());
    } else {
      const double tau = (t_real_ms - out.t_cut_ms) / 1000.0;
      if (tau > sim.time()) sim.advance(tau - sim.time());
      double w = sim.omega();
      if (pulse_angle > 0) {
        // Pulses where the angle crossed a multiple of pulse_angle since the last sample (the angle
        // taken as linear in between); the speed is one pulse angle over the last pulse interval.
        const double a = sim.angle();
        for (double next = (std::floor(prev_angle / pulse_angle) + 1) * pulse_angle; next <= a; next += pulse_angle) {
          const double t_pulse = prev_tau + (tau - prev_tau) * (next - prev_angle) / (a - prev_angle);
          if (t_pulse > last_pulse) held_omega = pulse_angle / (t_pulse - last_pulse);
          last_pulse = t_pulse;
        }
        prev_angle = a, prev_tau = tau;
        // Past the timeout the sensor gives up for good (a display's lowest speed): it reads 0, or
        // (a negative timeout) freezes on its last value, as some rpm counters do.
        if (s.pulse_timeout_s != 0 && !lost && tau - last_pulse > std::abs(s.pulse_timeout_s)) {
          out.t_signal_lost_ms = out.t_cut_ms + 1000.0 * last_pulse;
          lost = true;
          frozen_omega = held_omega;
        }
        w = lost ? (s.pulse_timeout_s < 0 ? frozen_omega : 0.0) : held_omega;
      }
      const double ripple = s.ripple * std::sin(s.ripple_per_rev * sim.angle());
      // A per-revolution sensor's reading is a count, not an analog voltage: no noise on it.
      v = s.bench.kb_v_s_per_rad * w * (1.0 + ripple) + s.offset_v + (pulse_angle > 0 ? 0.0 : s.noise_v * gauss(rng));
      if (bounces_left > 0) {  // the contact bounces: the pin reads part way between open and the motor
        --bounces_left;
        const double motor = v;
        v = pin->bounced(pin->read(t_real_ms, s.period_s, s.mains_hz, s.noise_v), motor);
        // Truth: a bounce that reads what the motor reads (within its noise, or 3 %) is no bad sample.
        if (std::abs(v - motor) > std::max(0.03 * std::abs(motor), 4.0 * s.noise_v)) out.bounce_index.push_back(out.t_ms.size());
      }
      const bool done_stopped = sim.stopped() && tau > sim.stop_time() + s.tail_s;
      const bool done_coast = !sim.stopped() && tau > s.max_coast_s;
      if (done_stopped || done_coast) break;
    }
    int counts = -1;
    if (s.adc_bits > 0) {
      // analogRead: v/Vref·2^bits to an integer count, clipped to the converter's range.
      const double x = v / s.adc_ref_v * (adc_max + 1);
      counts = static_cast<int>(std::clamp(s.adc_floor ? std::floor(x) : std::round(x), 0.0, double(adc_max)));
      // Vref/2^bits per count; the lab sketch's analogRead(A0) * 5.0 / 1023 reads 0.1 % high.
      v = counts * s.adc_ref_v / (s.sketch_gain ? adc_max : adc_max + 1);
    }
    if (s.decimals >= 0) v = std::round(v * p10) / p10;
    out.t_ms.push_back(std::floor(t_real_ms));
    out.volts.push_back(v);
    out.adc.push_back(counts);
    t_real_ms += 1000.0 * (s.period_s + s.jitter_s * unit(rng));
  }
  out.stopped = sim.stopped();
  out.t_stop_s = sim.stopped() ? sim.stop_time() : s.max_coast_s;
  if (s.glitches > 0) add_glitches(out, s);
  return out;
}

std::string to_arduino_text(const SyntheticRun& run, int decimals, bool putty_header) {
  std::string text;
  text.reserve(run.t_ms.size() * 14 + 100);
  if (putty_header) text += putty_log_header;
  for (std::size_t i = 0; i < run.t_ms.size(); ++i)
    text += fmt::format("{:.0f}\t{}\r\n", run.t_ms[i], printed_value(run.volts[i], decimals));
  return text;
}

std::string printed_value(double v, int decimals) {
  return decimals >= 0 ? fmt::format("{:.{}f}", v, decimals) : fmt::format("{}", v);
}

}  // namespace spindown
