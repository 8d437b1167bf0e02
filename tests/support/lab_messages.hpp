#pragma once
// Messages as the live lab publishes them, for the tests of spindown watch's table and screen, the
// fitter, the log reader and the benchmarks' logs.
#include <cstdint>
#include <string>

#include <spindown/config_t.hpp>
#include <spindown/fit_t.hpp>
#include <spindown/samples_t.hpp>

namespace spindown::test {

// A CONFIG as a bench's bridge publishes it for the lab's motor and flywheel (the lab sketch on a
// 10-bit converter at 50 Hz), with the J and K_b a test needs. Every field set: lcm-gen's structs
// leave numbers uninitialized.
inline config_t lab_config(const std::string& bench, double j = 1.12687602e-5, double kb = 1.0 / 123.569311,
                           std::int64_t utime = 1) {
  config_t c{};
  c.utime = utime;
  c.bench = bench;
  c.inertia_kg_m2 = j;
  c.inertia_source = "lab flywheel + rotor";
  c.kb_v_s_per_rad = kb;
  c.kb_source = "speed constant 1180 rpm/V";
  c.quantity = samples_t::QUANTITY_BACK_EMF_V;
  c.adc_volts_per_count = 5.0 / 1023;
  c.adc_bits = 10;
  c.firmware = "lab sketch";
  c.protocol = "lab-tsv";
  c.sample_period_s = 0.02;
  c.baud = 9600;
  c.device = "/dev/ttyACM0";
  c.host = "lab-pc-3";
  c.inertia_rel_error = 0;
  c.kb_rel_error = 0;
  return c;
}

// A combined-model fit as spindown-fitter publishes it (flat arrays; model 2 is the best).
inline fit_t fit_msg(const std::string& bench, int run, const std::string& best = "combined") {
  fit_t m{};
  m.bench = bench;
  m.run = run;
  m.residual_unit = "V";
  m.bench_source = "config";
  m.model = {"viscous", "coulomb", "combined"};
  m.nmodels = 3;
  m.rmse = {0.05, 0.02, 0.0123};
  m.r2 = {0.9, 0.99, 0.999};
  m.aic = m.bic = {1, 2, 3};
  m.t_stop_pred_s = {1e9, 8, 7.7};
  m.converged = {true, true, true};
  m.model_samples = {388, 388, 388};
  m.model_message = {"", "", ""};
  m.param_model = {0, 1, 2, 2, 2, 2};
  m.param_name = {"c1", "c2", "c3", "c4", "omega0", "A"};
  m.param_value = {1.4e-6, 1.38e-4, 1.822e-7, 1.139e-4, 450, -5.06};
  m.param_stderr = {1e-8, 1e-6, 1.1e-9, 2e-7, 0.5, 0.01};
  m.param_unit = {"N*m*s/rad", "N*m", "N*m*s/rad", "N*m", "rad/s", "V"};
  m.nparams = static_cast<std::int32_t>(m.param_name.size());
  m.best = best;
  return m;
}

}  // namespace spindown::test
