#pragma once
// One message of each spindown type with every field set (every string non-empty, every array
// with its own length), for the tests of the decoder, the signatures and the gate: a layout error
// shifts bytes, and every field is covered by a signature. The source fields (lab, host, session,
// sequence) are set too, unsigned.
#include <cmath>
#include <cstdint>
#include <vector>

#include <spindown/config_t.hpp>
#include <spindown/explain_t.hpp>
#include <spindown/fit_t.hpp>
#include <spindown/run_t.hpp>
#include <spindown/samples_t.hpp>
#include <spindown/status_t.hpp>

namespace spindown::test {

template <class Msg>
std::vector<std::uint8_t> encoded(const Msg& m) {
  std::vector<std::uint8_t> b(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}

// The source fields every type ends with.
template <class Msg>
void set_source(Msg& m, const char* lab = "lab-a", const char* host = "bench-pc", std::int64_t session = 0x1234abcd5678ef01,
                std::int64_t seq = 9) {
  m.lab = lab;
  m.sent_to = "239.255.76.67:7667";
  m.source_host = host;
  m.source_session = session;
  m.source_seq = seq;
  m.auth_key_id = 0;
}

// Every field non-empty, every array with distinct lengths, so a layout error shifts bytes.
inline samples_t make_samples() {
  samples_t s{};
  s.utime = 1;
  s.bench = "bench-a";
  s.seq = 7;
  s.clock_epoch = 2;
  s.quantity = samples_t::QUANTITY_RPM;
  s.n = 3;
  s.device_time_us = {1, 2, 3};
  s.host_time_us = {4, 5, 6};
  s.value = {1.5, 2.5, 3.5};
  s.raw_adc = {-1, -1, 7};
  set_source(s);
  return s;
}
inline config_t make_config() {
  config_t c{};
  c.bench = "b";
  c.inertia_kg_m2 = 1e-5;
  c.inertia_source = "lab default";
  c.kb_v_s_per_rad = 0.008;
  c.kb_source = "x";
  c.quantity = 1;
  c.adc_bits = 10;
  c.firmware = "fw";
  c.protocol = "lab-tsv";
  c.baud = 9600;
  c.device = "/dev/ttyACM0";
  c.host = "h";
  c.inertia_rel_error = 0.02;
  c.kb_rel_error = 0.05;
  set_source(c);
  return c;
}
inline run_t make_run() {
  run_t r{};
  r.bench = "b";
  r.run = 3;
  r.state = run_t::STATE_STOPPED;
  r.t_cut_s = 1;
  r.t_stop_s = NAN;
  r.samples = 9;
  r.note = "note";
  set_source(r);
  return r;
}
inline fit_t make_fit() {
  fit_t f{};
  f.bench = "bench-a";
  f.residual_unit = "V";
  f.bench_source = "config";
  f.nmodels = 2;
  f.model = {"viscous", "combined"};
  f.rmse = {1, 2};
  f.r2 = {1, 2};
  f.aic = {1, 2};
  f.bic = {1, 2};
  f.t_stop_pred_s = {INFINITY, 2};
  f.converged = {1, 0};
  f.model_samples = {10, 11};
  f.model_message = {"", "did not converge"};
  f.nparams = 3;
  f.param_model = {0, 1, 1};
  f.param_name = {"c4", "c3", "c4"};
  f.param_value = {1, 2, 3};
  f.param_stderr = {0.1, 0.2, 0.3};
  f.param_unit = {"a", "b", "c"};
  f.best = "viscous";
  f.best_reason = "r";
  f.verdict = "ok";
  f.verdict_reason = "v";
  f.inertia_source = "i";
  f.kb_source = "k";
  f.lead_in = "zeros";
  f.first_seq = 1;
  f.last_seq = 2;
  f.health_reference = 1;
  f.nfindings = 2;
  f.finding_what = {"dry friction", "time to stop"};
  f.finding_level = {"ok", "check"};
  f.finding_reason = {"r1", "r2"};
  f.finding_value = {1, 2};
  f.finding_stderr = {1, 2};
  f.finding_reference = {1, 2};
  f.finding_reference_stderr = {1, 2};
  f.finding_reference_name = {"baseline", "lab limit"};
  f.finding_ratio = {1, 2};
  f.finding_ratio_stderr = {1, 2};
  f.finding_unit = {"N*m", "s"};
  f.ndoubts = 2;
  f.doubts = {"d1", "d2"};
  f.reading_step = 0.01;
  f.model_reduced_chi2 = {1, 2};
  f.ncorrelations = 3;
  f.corr_model = {0, 1, 1};
  f.corr_a = {"omega0", "omega0", "c3"};
  f.corr_b = {"c1", "c3", "c4"};
  f.corr_value = {0.5, 0.6, -0.9};
  f.inertia_rel_error = 0.02;
  f.kb_rel_error = 0.05;
  f.param_bench_error = {0.01, 0.02, 0.03};
  f.reading_noise = 0.0042;
  set_source(f);
  return f;
}
inline explain_t make_explain() {
  explain_t e{};
  e.bench = "b";
  e.nbase = 1;
  e.base = {"viscous"};
  e.nsteps = 2;
  e.step_added = {"coulomb", "windage"};
  e.step_rmse_before = {3, 2};
  e.step_rmse_after = {2, 1};
  e.step_why = {"w1", "w2"};
  e.nwhere = 3;
  e.where_step = {0, 0, 1};
  e.where_t_from_s = {0, 1, 2};
  e.where_t_to_s = {1, 2, 3};
  e.where_mean_residual = {0.1, 0.2, 0.3};
  e.nfinal = 3;
  e.final_effects = {"viscous", "coulomb", "windage"};
  e.nparams = 4;
  e.param_name = {"c1", "c2", "c3", "c4"};
  e.param_value = {1, 2, 3, 4};
  e.param_stderr = {1, 2, 3, 4};
  e.param_unit = {"u", "u", "u", "u"};
  e.story = "story";
  set_source(e);
  return e;
}
inline status_t make_status() {
  status_t s{};
  s.service = "bridge";
  s.instance = "bench-a";
  s.host = "h";
  s.pid = 1;
  s.state = "connected";
  s.ncounters = 2;
  s.counter_name = {"lines_good", "lines_bad"};
  s.counter_value = {10, 1};
  s.ngauges = 1;
  s.gauge_name = {"rate_hz"};
  s.gauge_value = {50};
  s.last_error = "e";
  set_source(s);
  return s;
}


}  // namespace spindown::test
