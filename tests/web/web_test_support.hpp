#pragma once
// What the web tests share: one simulated run of the lab's bench as the bridge publishes it
// (samples_t batches) and as the fitter describes it (run_t at the cut and the stop, the fit_t of
// spindown's own fit of those samples), fed to a WebLab as LCM's thread would.
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "spindown/fit.hpp"
#include "spindown/fit_message.hpp"
#include "spindown/runs.hpp"
#include "spindown/synthetic_run.hpp"
#include "spindown/web_lab.hpp"

namespace spindown::test {

inline constexpr std::int64_t t0_us = 1'700'000'000'000'000;  // host time of the first sample
inline constexpr std::int64_t sec_us = 1'000'000;

struct SimulatedRun {
  std::vector<std::int64_t> t_us;  // device time
  std::vector<double> v;
  double t_cut_s = 0, t_stop_s = 0;
  fit_t fit;                       // spindown's fit of the samples, as the fitter publishes it
};

inline SimulatedRun simulated_run(std::uint64_t seed = 7, std::int32_t number = 1, const std::string& bench = "b1") {
  SyntheticRunSpec spec;
  spec.seed = seed;
  const SyntheticRun s = make_synthetic_run(spec);
  SimulatedRun out;
  Recording rec;
  for (std::size_t i = 0; i < s.t_ms.size(); ++i) {
    out.t_us.push_back(std::llround(s.t_ms[i] * 1000));
    out.v.push_back(s.volts[i]);
    rec.push(static_cast<double>(out.t_us.back()) / 1e6, s.volts[i]);
  }
  Run run = find_runs(rec).runs.at(0);
  run.number = number;
  out.t_cut_s = run.t_cut_s;
  out.t_stop_s = run.t_stop_s;
  const RunFit fit = fit_run(rec, run, FitOptions{});
  out.fit = to_fit_message(fit, FitProvenance{bench, "config", 0, 0, 0.001, std::nullopt, "", 0}, t0_us);
  return out;
}

inline samples_t one_sample(const std::string& bench, std::int64_t seq, std::int64_t t_us, double v,
                            std::int8_t quantity = samples_t::QUANTITY_BACK_EMF_V) {
  samples_t m{};
  m.bench = bench;
  m.seq = seq;
  m.quantity = quantity;
  m.n = 1;
  m.device_time_us = {t_us};
  m.host_time_us = {t0_us};
  m.value = {v};
  m.raw_adc = {-1};
  return m;
}

inline run_t run_message(const std::string& bench, std::int32_t number, std::int8_t state, double t_cut_s,
                         double t_stop_s, const std::string& lead_in = "zeros") {
  run_t m{};
  m.bench = bench;
  m.run = number;
  m.state = state;
  m.t_cut_s = t_cut_s;
  m.t_stop_s = t_stop_s;
  m.lead_in = lead_in;
  m.note = "test";
  return m;
}

inline status_t bridge_status(const std::string& bench, const std::string& state, std::int64_t reconnects) {
  status_t m{};
  m.service = "bridge";
  m.instance = bench;
  m.state = state;
  m.counter_name = {"lines_good", "lines_bad", "reconnects"};
  m.counter_value = {100, 0, reconnects};
  m.ncounters = 3;
  m.gauge_name = {"rate_hz"};
  m.gauge_value = {50};
  m.ngauges = 1;
  return m;
}

// The value of parameter name of model model in a fit message.
inline double fit_param(const fit_t& m, const std::string& model, const std::string& name) {
  std::int32_t index = -1;
  for (std::size_t i = 0; i < m.model.size(); ++i)
    if (m.model[i] == model) index = static_cast<std::int32_t>(i);
  for (std::size_t k = 0; k < m.param_name.size(); ++k)
    if (m.param_model[k] == index && m.param_name[k] == name) return m.param_value[k];
  return std::nan("");
}

// Feeds the run to lab as it happens live: samples at 50 Hz of host time (one per message), the
// RUN when the cut and the stop are seen (a few samples late, as the fitter sees them), the FIT
// after the tail. Returns the host time after the last message.
inline std::int64_t feed_run(WebLab& lab, const SimulatedRun& r, const std::string& bench = "b1",
                             std::int32_t number = 1, std::int64_t seq0 = 0, std::int64_t host0 = t0_us) {
  std::int64_t now = host0;
  bool cut_sent = false, stop_sent = false;
  for (std::size_t i = 0; i < r.t_us.size(); ++i) {
    now = host0 + static_cast<std::int64_t>(i) * 20000;
    lab.on_samples(bench, one_sample(bench, seq0 + static_cast<std::int64_t>(i), r.t_us[i], r.v[i]), now);
    const double t = static_cast<double>(r.t_us[i]) / 1e6;
    if (!cut_sent && t > r.t_cut_s + 0.1) {
      lab.on_run(bench, run_message(bench, number, run_t::STATE_COASTING, r.t_cut_s, std::nan("")), now);
      cut_sent = true;
    }
    if (!stop_sent && std::isfinite(r.t_stop_s) && t > r.t_stop_s + 0.5) {
      lab.on_run(bench, run_message(bench, number, run_t::STATE_STOPPED, r.t_cut_s, r.t_stop_s), now);
      stop_sent = true;
    }
  }
  fit_t fit = r.fit;
  fit.run = number;
  lab.on_fit(bench, fit, now);
  return now;
}

}  // namespace spindown::test
