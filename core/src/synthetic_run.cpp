#include "spindown/synthetic_run.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <random>

#include "spindown/coast_simulator.hpp"

namespace spindown {

SyntheticRun make_synthetic_run(const SyntheticRunSpec& s) {
  SyntheticRun out;
  std::mt19937_64 rng(s.seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);

  out.omega0 = s.e0_v / s.bench.kb_v_s_per_rad;
  out.t_cut_ms = s.t0_ms + s.lead_in_s * 1000.0;
  CoastSimulator sim(s.friction, s.bench.inertia_kg_m2, out.omega0);

  const int adc_max = s.adc_bits > 0 ? (1 << s.adc_bits) - 1 : 0;
  const double p10 = s.decimals >= 0 ? std::pow(10.0, s.decimals) : 0.0;
  double floating = 0.2;  // a floating pin wanders slowly between rails' noise and ~0.6 V
  double t_real_ms = s.t0_ms;
  for (std::size_t guard = 0; guard < 50'000'000; ++guard) {
    double v = 0.0;
    if (t_real_ms < out.t_cut_ms) {
      switch (s.lead_in) {
        case LeadIn::zeros: v = 0.0; break;
        case LeadIn::supply: v = s.supply_v + s.noise_v * gauss(rng); break;
        case LeadIn::floating:
          floating = std::clamp(0.85 * floating + 0.15 * 0.25 + 0.12 * gauss(rng), 0.0, 0.7);
          v = floating;
          break;
      }
    } else {
      const double tau = (t_real_ms - out.t_cut_ms) / 1000.0;
      if (tau > sim.time()) sim.advance(tau - sim.time());
      const double w = sim.omega();
      const double ripple = s.ripple * std::sin(s.ripple_per_rev * sim.angle());
      v = s.bench.kb_v_s_per_rad * w * (1.0 + ripple) + s.offset_v + s.noise_v * gauss(rng);
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
