// spindown-lcm-publish: publishes spindown traffic for tests, benchmarks and the lcm-spy check:
// samples_t (a coasting curve, consecutive seq) for one or more benches at a given rate, and
// with --all-types also config_t, run_t, fit_t, explain_t and status_t on every bench's
// channels. Prints one JSON line with what it published.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <fmt/format.h>
#include <lcm/lcm-cpp.hpp>

#include <spindown/config_t.hpp>
#include <spindown/explain_t.hpp>
#include <spindown/fit_t.hpp>
#include <spindown/run_t.hpp>
#include <spindown/samples_t.hpp>
#include <spindown/status_t.hpp>

#include "spindown/clock.hpp"
#include "spindown/host_name.hpp"
#include "lab_messages.hpp"  // tests/support: the lab's CONFIG
#include "spindown/lcm_channels.hpp"
#include "spindown/lcm_status.hpp"
#include "spindown/stop_signal.hpp"

namespace {

using spindown::wall_us;

spindown::config_t make_config(const std::string& bench, std::int64_t now) {
  spindown::config_t c = spindown::test::lab_config(bench, 1.12687602e-5, 1.0 / 123.569311, now);
  c.host = spindown::host_name();
  return c;
}

spindown::run_t make_run(const std::string& bench, std::int64_t now, std::int64_t seq) {
  spindown::run_t r{};
  r.utime = now;
  r.bench = bench;
  r.run = 1;
  r.state = spindown::run_t::STATE_STOPPED;
  r.t_cut_s = 1.25;
  r.t_stop_s = 38.5;
  r.first_seq = 0;
  r.last_seq = seq;
  r.samples = static_cast<std::int32_t>(seq);
  r.note = "demo run from spindown-lcm-publish";
  return r;
}

spindown::fit_t make_fit(const std::string& bench, std::int64_t now) {
  spindown::fit_t f{};
  f.utime = now;
  f.bench = bench;
  f.run = 1;
  f.t_cut_s = 1.25;
  f.t_stop_s = 38.5;
  f.samples = 1862;
  f.inertia_kg_m2 = 1.12687602e-5;
  f.kb_v_s_per_rad = 1.0 / 123.569311;
  f.bench_source = "config";
  f.zero_level = 0.0;
  f.residual_unit = "V";
  f.model = {"viscous", "coulomb", "combined"};
  f.nmodels = 3;
  f.rmse = {0.061, 0.034, 0.012};
  f.r2 = {0.991, 0.997, 0.9996};
  f.aic = {-9100, -11300, -15200};
  f.bic = {-9090, -11290, -15185};
  f.t_stop_pred_s = {INFINITY, 37.1, 37.3};
  f.converged = {true, true, true};
  f.param_model = {0, 1, 2, 2};
  f.param_name = {"c1", "c2", "c3", "c4"};
  f.param_value = {1.2508e-6, 1.402e-4, 1.800e-7, 1.1419e-4};
  f.param_stderr = {2e-9, 3e-7, 4e-9, 2e-7};
  f.param_unit = {"N*m*s/rad", "N*m", "N*m*s/rad", "N*m"};
  f.nparams = 4;
  f.best = "combined";
  f.best_reason = "lowest BIC by 3895";
  f.verdict = "";
  f.verdict_reason = "no reference configured";
  f.latency_s = 0.004;
  f.inertia_source = "lab default";
  f.kb_source = "speed constant 1180 rpm/V";
  f.lead_in = "zeros";
  f.noise_level = 0.011;
  f.period_s = 0.02;
  // Every per-model array must have nmodels entries or the encoder reads past the end.
  f.model_samples.assign(f.nmodels, f.samples);
  f.model_message.assign(f.nmodels, "");
  f.model_reduced_chi2.assign(f.nmodels, 1.0);
  f.first_seq = 0;
  f.last_seq = 1861;
  f.ndoubts = 0;
  f.reading_step = 0.01;
  f.ncorrelations = 1;
  f.corr_model = {2};
  f.corr_a = {"c3"};
  f.corr_b = {"c4"};
  f.corr_value = {-0.96};
  // lcm-gen's C++ structs leave numbers uninitialized: an unset count made the encoder walk a
  // garbage number of findings (a crash now and then, seen under the lcm-spy GUI test).
  f.health_reference = false;
  f.nfindings = 0;
  f.t_end_s = 38.5;
  f.end = "stopped";
  f.inertia_rel_error = 0.02;
  f.kb_rel_error = 0.05;
  f.param_bench_error = {3e-8, 9e-6, 4e-9, 6e-6};
  f.reading_noise = 0.0042;
  return f;
}

spindown::explain_t make_explain(const std::string& bench, std::int64_t now) {
  spindown::explain_t e{};
  e.utime = now;
  e.bench = bench;
  e.run = 1;
  e.base = {"viscous"};
  e.nbase = 1;
  e.rmse_base = 0.061;
  e.rmse_final = 0.012;
  e.noise_level = 0.011;
  e.step_added = {"coulomb"};
  e.step_rmse_before = {0.061};
  e.step_rmse_after = {0.012};
  e.step_why = {"the speed falls linearly near the stop"};
  e.nsteps = 1;
  e.where_step = {0};
  e.where_t_from_s = {25.0};
  e.where_t_to_s = {38.5};
  e.where_mean_residual = {0.08};
  e.nwhere = 1;
  e.final_effects = {"viscous", "coulomb"};
  e.nfinal = 2;
  e.param_name = {"c3", "c4"};
  e.param_value = {1.8e-7, 1.1419e-4};
  e.param_stderr = {4e-9, 2e-7};
  e.param_unit = {"N*m*s/rad", "N*m"};
  e.nparams = 2;
  e.story = "viscous alone misses the linear end of the coast; adding coulomb explains it";
  return e;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"spindown-lcm-publish: publish spindown test traffic on LCM"};
  std::string lcm_url;
  std::vector<std::string> benches;
  int bench_count = 0;
  long count = 100;
  double rate_hz = 50;
  int batch = 1;
  long seq_start = 0;
  double duration_s = 0;
  bool all_types = false;
  app.add_option("--lcm-url", lcm_url, "LCM URL (default: LCM_DEFAULT_URL or LCM's default)");
  app.add_option("--bench", benches, "bench id (repeatable; default bench-1)");
  app.add_option("--benches", bench_count, "publish for benches bench-1 … bench-N")->check(CLI::Range(1, 10000));
  app.add_option("--count", count, "SAMPLE messages per bench (0 = until --duration or a signal)")
      ->capture_default_str()->check(CLI::NonNegativeNumber);
  app.add_option("--rate", rate_hz, "SAMPLE messages per second per bench (0 = as fast as possible)")
      ->capture_default_str()->check(CLI::NonNegativeNumber);
  app.add_option("--batch", batch, "samples per message")->capture_default_str()->check(CLI::Range(1, 10000));
  app.add_option("--seq-start", seq_start, "first sequence number")->capture_default_str();
  app.add_option("--duration", duration_s, "stop after this many seconds (0 = no limit)")
      ->check(CLI::NonNegativeNumber);
  app.add_flag("--all-types", all_types, "also CONFIG, RUN, FIT, EXPLAIN and STATUS once a second per bench");
  CLI11_PARSE(app, argc, argv);
  for (int i = 1; i <= bench_count; ++i) benches.push_back(fmt::format("bench-{}", i));
  if (benches.empty()) benches.push_back("bench-1");
  for (const auto& b : benches) {
    std::string why;
    if (!spindown::is_valid_bench_id(b, &why)) {
      fmt::print(stderr, "spindown-lcm-publish: {}\n", why);
      return 2;
    }
  }
  if (count == 0 && duration_s == 0 && rate_hz == 0) {
    fmt::print(stderr, "spindown-lcm-publish: --count 0 needs --duration or --rate\n");
    return 2;
  }
  lcm::LCM lcm(lcm_url);
  if (!lcm.good()) {
    fmt::print(stderr, "spindown-lcm-publish: cannot start LCM{}{}\n", lcm_url.empty() ? "" : " at ", lcm_url);
    return 1;
  }
  spindown::StopSignals stop;

  const auto start = std::chrono::steady_clock::now();
  const std::int64_t start_us = wall_us();
  std::vector<std::string> sample_channels;
  for (const auto& b : benches) sample_channels.push_back(spindown::channel_name(b, spindown::ChannelKind::sample));
  spindown::samples_t msg{};
  msg.quantity = spindown::samples_t::QUANTITY_BACK_EMF_V;
  msg.n = batch;
  msg.device_time_us.resize(batch);
  msg.host_time_us.resize(batch);
  msg.value.resize(batch);
  msg.raw_adc.resize(batch);
  long published = 0, failures = 0, extras = 0;
  std::int64_t first_utime = 0, last_utime = 0;
  auto next_extras = start;
  for (long k = 0; !stop.requested() && (count == 0 || k < count); ++k) {
    const auto now_steady = std::chrono::steady_clock::now();
    if (duration_s > 0 && now_steady - start >= std::chrono::duration<double>(duration_s)) break;
    if (all_types && now_steady >= next_extras) {
      const std::int64_t now = wall_us();
      for (const auto& b : benches) {
        using K = spindown::ChannelKind;
        const auto c = make_config(b, now);
        const auto r = make_run(b, now, seq_start + k * batch);
        const auto f = make_fit(b, now);
        const auto e = make_explain(b, now);
        spindown::StatusHeartbeat hb("bridge", b, start_us);
        hb.set_state("connected");
        hb.set_counter("samples", k * batch);
        hb.set_counter("lines_bad", 0);
        hb.set_gauge("rate_hz", rate_hz * batch);
        const auto s = hb.message(now);
        failures += lcm.publish(spindown::channel_name(b, K::config), &c) != 0;
        failures += lcm.publish(spindown::channel_name(b, K::run), &r) != 0;
        failures += lcm.publish(spindown::channel_name(b, K::fit), &f) != 0;
        failures += lcm.publish(spindown::channel_name(b, K::explain), &e) != 0;
        failures += lcm.publish(spindown::channel_name(b, K::status), &s) != 0;
        extras += 5;
      }
      next_extras += std::chrono::seconds(1);
    }
    for (std::size_t bi = 0; bi < benches.size(); ++bi) {
      const std::int64_t now = wall_us();
      msg.utime = now;
      msg.bench = benches[bi];
      msg.seq = seq_start + k * batch;
      msg.clock_epoch = 0;
      for (int i = 0; i < batch; ++i) {
        const double t = double(msg.seq + i) * 0.02;
        msg.device_time_us[i] = static_cast<std::int64_t>(t * 1e6);
        msg.host_time_us[i] = now;
        msg.value[i] = std::round(100 * std::max(0.0, 3.0 - 0.1 * std::fmod(t, 40.0))) / 100;
        msg.raw_adc[i] = static_cast<std::int32_t>(msg.value[i] / 5.0 * 1024);
      }
      if (lcm.publish(sample_channels[bi], &msg) != 0) ++failures;
      else ++published;
      if (first_utime == 0) first_utime = now;
      last_utime = now;
    }
    if (rate_hz > 0)
      stop.sleep_until(start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                   std::chrono::duration<double>(double(k + 1) / rate_hz)));
  }
  fmt::print("{{\"sample_messages\":{},\"other_messages\":{},\"failures\":{},\"first_utime\":{},\"last_utime\":{}}}\n",
             published, extras, failures, first_utime, last_utime);
  return failures > 0 ? 1 : 0;
}
