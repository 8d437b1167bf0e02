// The generated spindown LCM types: every type round-trips with non-trivial arrays and
// strings, reports its size, refuses truncated buffers and buffers of another type.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <spindown/config_t.hpp>
#include <spindown/explain_t.hpp>
#include <spindown/fit_t.hpp>
#include <spindown/run_t.hpp>
#include <spindown/samples_t.hpp>
#include <spindown/status_t.hpp>

using namespace spindown;

namespace {

template <class M>
std::vector<std::uint8_t> encode(const M& m) {
  std::vector<std::uint8_t> buf(static_cast<std::size_t>(m.getEncodedSize()));
  const int n = m.encode(buf.data(), 0, static_cast<int>(buf.size()));
  EXPECT_EQ(n, static_cast<int>(buf.size())) << M::getTypeName();
  return buf;
}

// Decodes, checks every byte was used, and that encoding the result gives the same bytes.
template <class M>
M round_trip(const M& m) {
  const auto bytes = encode(m);
  M back;
  EXPECT_EQ(back.decode(bytes.data(), 0, static_cast<int>(bytes.size())), static_cast<int>(bytes.size()));
  EXPECT_EQ(encode(back), bytes) << M::getTypeName() << " does not re-encode to the same bytes";
  return back;
}

template <class M>
void refuses_truncation(const M& m) {
  const auto bytes = encode(m);
  for (std::size_t len = 0; len < bytes.size(); ++len) {
    M back;
    ASSERT_LT(back.decode(bytes.data(), 0, static_cast<int>(len)), 0)
        << M::getTypeName() << " decoded from " << len << " of " << bytes.size() << " bytes";
  }
  std::vector<std::uint8_t> small(bytes.size() - 1);
  EXPECT_LT(m.encode(small.data(), 0, static_cast<int>(small.size())), 0) << "encode into a short buffer";
}

template <class As, class M>
void refuses_other_type(const M& m) {
  const auto bytes = encode(m);
  As other;
  EXPECT_LT(other.decode(bytes.data(), 0, static_cast<int>(bytes.size())), 0)
      << "a " << M::getTypeName() << " decoded as " << As::getTypeName();
}

samples_t make_samples() {
  samples_t m{};
  m.utime = 1694686893123456;
  m.bench = "lab-2_B";
  m.seq = 4242;
  m.clock_epoch = 3;
  m.quantity = samples_t::QUANTITY_RPM;
  m.n = 5;
  m.device_time_us = {5234000, 5254000, 5274000, 5295000, (std::int64_t{1} << 32) * 1000 + 1};
  m.host_time_us = {1, 2, 3, 4, std::numeric_limits<std::int64_t>::max()};
  m.value = {2.81, -0.01, 0.0, 1e-300, 3300.5};
  m.raw_adc = {575, -1, 0, 1023, 12};
  return m;
}

config_t make_config() {
  config_t m{};
  m.utime = 99;
  m.bench = "bench1";
  m.inertia_kg_m2 = 1.12687602e-5;
  m.inertia_source = "geometry r=0.02 h=0.015 ρ=2700 + rotor 10.9 g·cm²";
  m.kb_v_s_per_rad = 1.0 / 123.569311;
  m.kb_source = "speed constant 1180 rpm/V";
  m.quantity = samples_t::QUANTITY_BACK_EMF_V;
  m.adc_volts_per_count = 5.0 / 1024;
  m.adc_bits = 10;
  m.firmware = "lab sketch";
  m.protocol = "lab-tsv";
  m.sample_period_s = 0.020;
  m.baud = 9600;
  m.device = "/dev/ttyACM0";
  m.host = "lab-pc-07";
  if constexpr (requires { m.inertia_rel_error; }) {  // J's and K_b's own uncertainty
    m.inertia_rel_error = 0.02;
    m.kb_rel_error = 0.05;
  }
  return m;
}

run_t make_run() {
  run_t m{};
  m.utime = 7;
  m.bench = "b";
  m.run = 2;
  m.state = run_t::STATE_STOPPED;
  m.t_cut_s = 8.234;
  m.t_stop_s = std::numeric_limits<double>::quiet_NaN();
  m.first_seq = 10;
  m.last_seq = 1700;
  m.samples = 1691;
  m.note = "";
  return m;
}

fit_t make_fit() {
  fit_t m{};
  m.utime = 1;
  m.bench = "bench1";
  m.run = 1;
  m.t_cut_s = 8.234;
  m.t_stop_s = 35.1;
  m.samples = 1400;
  m.inertia_kg_m2 = 1.12687602e-5;
  m.kb_v_s_per_rad = 0.0081;
  m.bench_source = "config";
  m.zero_level = 0.004;
  m.residual_unit = "V";
  m.nmodels = 3;
  m.model = {"viscous", "coulomb", "combined"};
  m.rmse = {0.05, 0.03, 0.01};
  m.r2 = {0.98, 0.99, 0.999};
  m.aic = {-100, -200, -300};
  m.bic = {-90, -190, -290};
  m.t_stop_pred_s = {std::numeric_limits<double>::infinity(), 27.0, 26.9};
  m.converged = {1, 1, 0};
  m.nparams = 4;
  m.param_model = {0, 1, 2, 2};
  m.param_name = {"c1", "c2", "c3", "c4"};
  m.param_value = {1.4e-6, 1.38e-4, 1.8e-7, 1.14e-4};
  m.param_stderr = {1e-8, 1e-6, 1e-9, 1e-6};
  m.param_unit = {"N*m*s/rad", "N*m", "N*m*s/rad", "N*m"};
  m.best = "combined";
  m.best_reason = "lowest BIC";
  m.verdict = "";
  m.verdict_reason = "";
  m.latency_s = 0.0123;
  // Fields added to fit_t later: filled when this version of the type has them.
  if constexpr (requires { m.model_samples; }) m.model_samples = {1400, 1400, 1399};
  if constexpr (requires { m.model_message; }) m.model_message = {"", "", "did not converge: max evaluations"};
  if constexpr (requires { m.nfindings; }) {  // motor health: one finding with its numbers
    m.verdict = "service";
    m.verdict_reason = "dry friction 2.5× the baseline: check bearings and alignment";
    m.health_reference = true;
    m.nfindings = 1;
    m.finding_what = {"dry friction"};
    m.finding_level = {"service"};
    m.finding_reason = {m.verdict_reason};
    m.finding_value = {2.85e-4};
    m.finding_stderr = {1e-6};
    m.finding_reference = {1.14e-4};
    m.finding_reference_stderr = {4e-7};
    m.finding_reference_name = {"baseline"};
    m.finding_ratio = {2.5};
    m.finding_ratio_stderr = {0.012};
    m.finding_unit = {"N*m"};
  }
  if constexpr (requires { m.ndoubts; }) {  // what the numbers cannot say by themselves
    m.ndoubts = 1;
    m.doubts = {"the combined model misses"};
    m.reading_step = 0.01;
    m.model_reduced_chi2 = {2200, 106, std::numeric_limits<double>::quiet_NaN()};
    m.ncorrelations = 2;
    m.corr_model = {0, 1};
    m.corr_a = {"omega0", "omega0"};
    m.corr_b = {"c1", "c2"};
    m.corr_value = {0.74, 0.88};
  }
  if constexpr (requires { m.param_bench_error; }) {  // J's and K_b's uncertainty in each parameter
    m.inertia_rel_error = 0.02;
    m.kb_rel_error = 0.05;
    m.param_bench_error = {2.8e-8, 7e-6, 3.6e-9, 6.6e-6};
  }
  if constexpr (requires { m.reading_noise; }) m.reading_noise = 0.0042;  // the reading noise σ
  return m;
}

explain_t make_explain() {
  explain_t m{};
  m.utime = 5;
  m.bench = "b";
  m.run = 1;
  m.nbase = 1;
  m.base = {"viscous"};
  m.rmse_base = 0.2;
  m.rmse_final = 0.01;
  m.noise_level = 0.009;
  m.nsteps = 2;
  m.step_added = {"coulomb", "stribeck"};
  m.step_rmse_before = {0.2, 0.03};
  m.step_rmse_after = {0.03, 0.01};
  m.step_why = {"residual bends late", "friction rises near the stop"};
  m.nwhere = 3;
  m.where_step = {0, 0, 1};
  m.where_t_from_s = {0, 10, 25};
  m.where_t_to_s = {5, 20, 27};
  m.where_mean_residual = {0.1, -0.05, 0.02};
  m.nfinal = 3;
  m.final_effects = {"viscous", "coulomb", "stribeck"};
  m.nparams = 2;
  m.param_name = {"c1", "c_s"};
  m.param_value = {1e-7, 2e-4};
  m.param_stderr = {1e-9, 1e-5};
  m.param_unit = {"N*m*s/rad", "N*m"};
  m.story = "The viscous model alone leaves a systematic residual.\nCoulomb friction explains it.";
  return m;
}

status_t make_status() {
  status_t m{};
  m.utime = 11;
  m.service = "bridge";
  m.instance = "bench1";
  m.host = "lab-pc";
  m.pid = 4321;
  m.state = "connected";
  m.uptime_s = 12.5;
  m.ncounters = 3;
  m.counter_name = {"lines_good", "lines_bad", "seq_gaps"};
  m.counter_value = {1665, 3, 0};
  m.ngauges = 1;
  m.gauge_name = {"rate_hz"};
  m.gauge_value = {49.8};
  m.last_error = "line 47: \"6\": missing value";
  m.last_error_utime = 10;
  return m;
}

}  // namespace

TEST(LcmTypes, SamplesRoundTrip) {
  const samples_t m = make_samples();
  // Fixed part 8 (hash) + 8 + (4 + 7 + 1) + 8 + 4 + 1 + 4, then 28 bytes per sample, then the
  // source fields: three empty strings (5 bytes each), session, seq, key id and auth[32].
  EXPECT_EQ(m.getEncodedSize(), 8 + 8 + 12 + 8 + 4 + 1 + 4 + 5 * 28 + 3 * 5 + 8 + 8 + 4 + 32);
  const samples_t b = round_trip(m);
  EXPECT_EQ(b.bench, m.bench);
  EXPECT_EQ(b.seq, m.seq);
  EXPECT_EQ(b.clock_epoch, 3);
  EXPECT_EQ(int(b.quantity), int(samples_t::QUANTITY_RPM));  // int(): no ODR-use of the constant
  EXPECT_EQ(b.device_time_us, m.device_time_us);
  EXPECT_EQ(b.host_time_us, m.host_time_us);
  EXPECT_EQ(b.value, m.value);
  EXPECT_EQ(b.raw_adc, m.raw_adc);
}

TEST(LcmTypes, EmptySamplesBatch) {
  samples_t m = make_samples();
  m.n = 0;
  m.device_time_us.clear();
  m.host_time_us.clear();
  m.value.clear();
  m.raw_adc.clear();
  const samples_t b = round_trip(m);
  EXPECT_EQ(b.n, 0);
  EXPECT_TRUE(b.value.empty());
}

TEST(LcmTypes, ConfigRoundTrip) {
  const config_t m = make_config();
  const config_t b = round_trip(m);
  EXPECT_EQ(b.inertia_source, m.inertia_source);  // UTF-8 survives
  EXPECT_DOUBLE_EQ(b.kb_v_s_per_rad, m.kb_v_s_per_rad);
  EXPECT_EQ(b.baud, 9600);
  EXPECT_EQ(b.device, "/dev/ttyACM0");
}

TEST(LcmTypes, RunRoundTrip) {
  const run_t b = round_trip(make_run());
  EXPECT_EQ(int(b.state), int(run_t::STATE_STOPPED));
  EXPECT_TRUE(std::isnan(b.t_stop_s));
  EXPECT_EQ(b.last_seq, 1700);
  EXPECT_EQ(b.note, "");
}

TEST(LcmTypes, FitRoundTrip) {
  const fit_t m = make_fit();
  const fit_t b = round_trip(m);
  EXPECT_EQ(b.model, m.model);
  EXPECT_EQ(b.converged, m.converged);
  EXPECT_TRUE(std::isinf(b.t_stop_pred_s[0]));
  EXPECT_EQ(b.param_name, m.param_name);
  EXPECT_EQ(b.param_value, m.param_value);
  EXPECT_EQ(b.param_unit, m.param_unit);
  EXPECT_EQ(b.best, "combined");
  EXPECT_EQ(b.verdict, "service");
  EXPECT_TRUE(b.health_reference);
  EXPECT_EQ(b.nfindings, 1);
  EXPECT_EQ(b.finding_what, m.finding_what);
  EXPECT_EQ(b.finding_reason, m.finding_reason);  // UTF-8 (×) survives
  EXPECT_EQ(b.finding_ratio, m.finding_ratio);
  EXPECT_EQ(b.finding_reference_name, m.finding_reference_name);
}

TEST(LcmTypes, ExplainRoundTrip) {
  const explain_t m = make_explain();
  const explain_t b = round_trip(m);
  EXPECT_EQ(b.step_why, m.step_why);
  EXPECT_EQ(b.where_step, m.where_step);
  EXPECT_EQ(b.final_effects, m.final_effects);
  EXPECT_EQ(b.story, m.story);
}

TEST(LcmTypes, StatusRoundTrip) {
  const status_t m = make_status();
  const status_t b = round_trip(m);
  EXPECT_EQ(b.counter_name, m.counter_name);
  EXPECT_EQ(b.counter_value, m.counter_value);
  EXPECT_EQ(b.gauge_value, m.gauge_value);
  EXPECT_EQ(b.last_error, m.last_error);
}

TEST(LcmTypes, TruncatedBuffersDoNotDecode) {
  refuses_truncation(make_samples());
  refuses_truncation(make_config());
  refuses_truncation(make_run());
  refuses_truncation(make_fit());
  refuses_truncation(make_explain());
  refuses_truncation(make_status());
}

TEST(LcmTypes, AnotherTypesBytesDoNotDecode) {
  refuses_other_type<config_t>(make_samples());
  refuses_other_type<fit_t>(make_samples());
  refuses_other_type<samples_t>(make_config());
  refuses_other_type<status_t>(make_run());
  refuses_other_type<explain_t>(make_fit());
  refuses_other_type<fit_t>(make_explain());
  refuses_other_type<samples_t>(make_status());
}

TEST(LcmTypes, FingerprintsAreDistinct) {
  const std::vector<std::int64_t> hashes{samples_t::getHash(), config_t::getHash(),  run_t::getHash(),
                                         fit_t::getHash(),     explain_t::getHash(), status_t::getHash()};
  for (std::size_t i = 0; i < hashes.size(); ++i)
    for (std::size_t j = i + 1; j < hashes.size(); ++j) EXPECT_NE(hashes[i], hashes[j]) << i << " " << j;
}

TEST(LcmTypes, DecodingAtAnOffset) {
  const auto bytes = encode(make_samples());
  std::vector<std::uint8_t> padded(13 + bytes.size(), 0xAB);
  std::copy(bytes.begin(), bytes.end(), padded.begin() + 13);
  samples_t b{};
  EXPECT_EQ(b.decode(padded.data(), 13, static_cast<int>(bytes.size())), static_cast<int>(bytes.size()));
  EXPECT_EQ(b.value, make_samples().value);
}
