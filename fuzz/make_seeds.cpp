// Writes the binary part of the seed corpus: one or more encoded messages of each LCM type
// (fuzz/corpus/fuzz_<type>/) and small LCM logs, sound and damaged (fuzz/corpus/fuzz_lcm_log/).
// The text seeds are plain files kept by hand. Usage: fuzz_make_seeds CORPUS_DIR
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <string>
#include <vector>

#include <spindown/config_t.hpp>
#include <spindown/explain_t.hpp>
#include <spindown/fit_t.hpp>
#include <spindown/run_t.hpp>
#include <spindown/samples_t.hpp>
#include <spindown/status_t.hpp>

#include "lab_messages.hpp"  // tests/support
#include "spindown/lab_key.hpp"
#include "spindown/message_stamp.hpp"

namespace fs = std::filesystem;
using namespace spindown;

namespace {

constexpr std::int64_t t0_us = 1'694'686'893'000'000;  // 2023-09-14 10:21:33

// Every seed names its source, as the lab's programs send them (lab, host, session, count).
MessageStamp& stamp() {
  static MessageStamp s(SourceIdentity{"lab", "239.255.76.67:7667", "lab-pc-3", 0x3f9a0c1d5e7b2a48, t0_us});
  return s;
}

template <class Msg>
std::vector<std::uint8_t> encode(Msg m) {
  stamp().stamp(m);
  std::vector<std::uint8_t> b(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}

// The same message signed with a fixed test key on channel.
template <class Msg>
std::vector<std::uint8_t> signed_bytes(const std::string& channel, const Msg& m) {
  std::array<unsigned char, lab_key_bytes> key{};
  key.fill(0x42);
  MessageStamp signer(SourceIdentity{"lab", "239.255.76.67:7667", "lab-pc-3", 0x3f9a0c1d5e7b2a48, t0_us}, lab_key_from_bytes(key));
  const auto b = signer.encode(channel, m);
  return {b.begin(), b.end()};
}

// The encoding spindown wrote before the source and signature fields (samples_t's older
// fingerprint; a log recorded then holds these).
std::vector<std::uint8_t> legacy_samples(samples_t m) {
  m.lab.clear();
  m.sent_to.clear();
  m.source_host.clear();
  m.source_session = m.source_seq = 0;
  m.auth_key_id = 0;
  std::vector<std::uint8_t> b(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  b.resize(b.size() - (5 + 5 + 5 + 8 + 8 + 4 + 32));
  const std::uint64_t old = 0x6366464c24ab26e1ull;
  for (int k = 0; k < 8; ++k) b[static_cast<std::size_t>(k)] = static_cast<std::uint8_t>(old >> (56 - 8 * k));
  return b;
}

void write(const fs::path& path, const std::vector<std::uint8_t>& bytes) {
  fs::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()),
                                              static_cast<std::streamsize>(bytes.size()));
}

// A lab-like coast: 20 samples powered at 3 V, the cut, an exponential-linear decay to a stop
// over about 2 s, then zeros; 20 ms cadence, 2-decimal volts.
samples_t coast_samples(std::int64_t seq, int first, int count) {
  samples_t s{};
  s.utime = t0_us + seq * 20'000;
  s.bench = "bench-a";
  s.seq = seq;
  s.clock_epoch = 0;
  s.quantity = samples_t::QUANTITY_BACK_EMF_V;
  for (int i = first; i < first + count; ++i) {
    const double t = (i - 20) * 0.02;
    double v = 3.0;
    if (t > 0) v = std::max(0.0, 3.4 * std::exp(-t / 1.5) - 0.4 - 0.2 * t);
    s.device_time_us.push_back(5'234'000 + std::int64_t(i) * 20'000);
    s.host_time_us.push_back(t0_us + std::int64_t(i) * 20'000);
    s.value.push_back(std::round(v * 100) / 100);
    s.raw_adc.push_back(static_cast<std::int32_t>(std::lround(v / 5.0 * 1023)));
  }
  s.n = static_cast<std::int32_t>(s.value.size());
  return s;
}

config_t bench_config() {
  config_t c = test::lab_config("bench-a", 1.2e-5, 0.0081, t0_us);
  c.inertia_rel_error = 0.02;
  c.kb_rel_error = 0.05;
  return c;
}

run_t run_message(std::int8_t state) {
  run_t r{};
  r.utime = t0_us + 3'000'000;
  r.bench = "bench-a";
  r.run = 1;
  r.state = state;
  r.t_cut_s = 5.634;
  r.t_stop_s = state == run_t::STATE_STOPPED ? 7.41 : NAN;
  r.first_seq = 20;
  r.last_seq = 140;
  r.samples = 120;
  r.note = state == run_t::STATE_ABANDONED ? "power came back before the stop" : "";
  return r;
}

fit_t fit_message() {
  fit_t f{};
  f.utime = t0_us + 4'000'000;
  f.bench = "bench-a";
  f.run = 1;
  f.t_cut_s = 5.634;
  f.t_stop_s = 7.41;
  f.samples = 89;
  f.inertia_kg_m2 = 1.2e-5;
  f.kb_v_s_per_rad = 0.0081;
  f.bench_source = "config";
  f.zero_level = 0.0;
  f.residual_unit = "V";
  f.model = {"viscous", "coulomb", "combined"};
  f.nmodels = 3;
  f.rmse = {0.031, 0.044, 0.012};
  f.r2 = {0.998, 0.996, 0.9997};
  f.aic = {-610, -550, -780};
  f.bic = {-605, -545, -772};
  f.t_stop_pred_s = {INFINITY, 1.9, 1.78};
  f.converged = {1, 1, 1};
  f.model_samples = {89, 89, 89};
  f.model_message = {"", "", ""};
  f.param_model = {0, 1, 2, 2};
  f.param_name = {"c4", "c3", "c3", "c4"};
  f.param_value = {2.1e-6, 9.6e-6, 6.2e-6, 1.1e-6};
  f.param_stderr = {4e-8, 2e-7, 1e-7, 5e-8};
  f.param_unit = {"kg·m²·s⁻¹", "N·m", "N·m", "kg·m²·s⁻¹"};
  f.nparams = 4;
  f.best = "combined";
  f.best_reason = "lowest BIC";
  f.verdict = "";
  f.verdict_reason = "";
  f.latency_s = 0.004;
  f.inertia_source = "lab default";
  f.kb_source = "lab default";
  f.lead_in = "powered";
  f.noise_level = 0.006;
  f.period_s = 0.02;
  f.first_seq = 20;
  f.last_seq = 140;
  f.ndoubts = 0;
  f.reading_step = 0.01;
  f.model_reduced_chi2.assign(static_cast<std::size_t>(f.nmodels), 1.0);
  f.ncorrelations = 0;
  f.inertia_rel_error = 0.02;
  f.kb_rel_error = 0.05;
  f.param_bench_error = {8e-9, 1e-5, 9e-6, 2e-9};
  f.reading_noise = 0.0042;
  return f;
}

explain_t explain_message() {
  explain_t e{};
  e.utime = t0_us + 4'100'000;
  e.bench = "bench-a";
  e.run = 1;
  e.base = {"viscous", "coulomb"};
  e.nbase = 2;
  e.rmse_base = 0.012;
  e.rmse_final = 0.006;
  e.noise_level = 0.006;
  e.step_added = {"windage"};
  e.step_rmse_before = {0.012};
  e.step_rmse_after = {0.006};
  e.step_why = {"residuals curved at high speed"};
  e.nsteps = 1;
  e.where_step = {0};
  e.where_t_from_s = {0.0};
  e.where_t_to_s = {0.4};
  e.where_mean_residual = {0.02};
  e.nwhere = 1;
  e.final_effects = {"viscous", "coulomb", "windage"};
  e.nfinal = 3;
  e.param_name = {"c3", "c4", "c5"};
  e.param_value = {6.2e-6, 1.1e-6, 3e-9};
  e.param_stderr = {1e-7, 5e-8, 1e-10};
  e.param_unit = {"N·m", "kg·m²·s⁻¹", "kg·m²"};
  e.nparams = 3;
  e.story = "The combined model left curved residuals early in the coast; windage explains them.";
  return e;
}

status_t status_message() {
  status_t s{};
  s.utime = t0_us + 1'000'000;
  s.service = "bridge";
  s.instance = "bench-a";
  s.host = "lab-pc-3";
  s.pid = 4242;
  s.state = "connected";
  s.uptime_s = 12.5;
  s.counter_name = {"lines_good", "lines_bad", "samples", "seq_gaps"};
  s.counter_value = {620, 1, 620, 0};
  s.ncounters = 4;
  s.gauge_name = {"rate_hz"};
  s.gauge_value = {50.0};
  s.ngauges = 1;
  s.last_error = "line 3: garbled \"52\\x00\"";
  s.last_error_utime = t0_us + 400'000;
  return s;
}

template <class Msg>
void log_event(lcm::LogFile& log, std::int64_t& number, const std::string& channel, const Msg& m) {
  const auto bytes = encode(m);
  lcm::LogEvent ev{};
  ev.eventnum = number++;
  ev.timestamp = m.utime;
  ev.channel = channel;
  ev.datalen = static_cast<std::int32_t>(bytes.size());
  ev.data = const_cast<std::uint8_t*>(bytes.data());
  log.writeEvent(&ev);
}

std::vector<std::uint8_t> read_all(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: fuzz_make_seeds CORPUS_DIR\n");
    return 2;
  }
  const fs::path dir = argv[1];

  write(dir / "fuzz_samples_t/coast", encode(coast_samples(0, 0, 150)));
  write(dir / "fuzz_samples_t/empty", encode(coast_samples(7, 0, 0)));
  samples_t rpm = coast_samples(3, 30, 4);
  rpm.quantity = samples_t::QUANTITY_RPM;
  write(dir / "fuzz_samples_t/rpm", encode(rpm));
  write(dir / "fuzz_config_t/lab", encode(bench_config()));
  write(dir / "fuzz_run_t/coasting", encode(run_message(run_t::STATE_COASTING)));
  write(dir / "fuzz_run_t/stopped", encode(run_message(run_t::STATE_STOPPED)));
  write(dir / "fuzz_run_t/abandoned", encode(run_message(run_t::STATE_ABANDONED)));
  write(dir / "fuzz_fit_t/combined", encode(fit_message()));
  write(dir / "fuzz_explain_t/windage", encode(explain_message()));
  write(dir / "fuzz_status_t/bridge", encode(status_message()));
  write(dir / "fuzz_samples_t/signed", signed_bytes("SPINDOWN.fz.SAMPLE", coast_samples(150, 150, 3)));
  write(dir / "fuzz_samples_t/legacy", legacy_samples(coast_samples(0, 0, 20)));
  write(dir / "fuzz_fit_t/signed", signed_bytes("SPINDOWN.fz.FIT", fit_message()));

  // A small sound log: config, a coast in three messages, a heartbeat, a foreign channel.
  const fs::path logs = dir / "fuzz_lcm_log";
  fs::create_directories(logs);
  const fs::path sound = logs / "sound.lcmlog";
  {
    lcm::LogFile log(sound.string(), "w");
    std::int64_t number = 0;
    log_event(log, number, "SPINDOWN.bench-a.CONFIG", bench_config());
    log_event(log, number, "SPINDOWN.bench-a.SAMPLE", coast_samples(0, 0, 50));
    log_event(log, number, "SPINDOWN.bench-a.STATUS", status_message());
    log_event(log, number, "SPINDOWN.bench-a.SAMPLE", coast_samples(50, 50, 50));
    log_event(log, number, "SPINDOWN.bench-a.SAMPLE", coast_samples(100, 100, 50));
    log_event(log, number, "OTHER.CHANNEL", run_message(run_t::STATE_STOPPED));
  }
  const auto bytes = read_all(sound);
  // Truncated in the middle of the last sample message.
  write(logs / "truncated.lcmlog", {bytes.begin(), bytes.end() - 700});
  // Garbage between events and a samples_t whose fingerprint is wrong.
  {
    lcm::LogFile log((logs / "damaged.lcmlog").string(), "w");
    std::int64_t number = 0;
    log_event(log, number, "SPINDOWN.bench-b.CONFIG", bench_config());
    log_event(log, number, "SPINDOWN.bench-b.SAMPLE", bench_config());  // wrong type on SAMPLE
    log_event(log, number, "SPINDOWN.bench-b.SAMPLE", coast_samples(0, 0, 30));
  }
  auto damaged = read_all(logs / "damaged.lcmlog");
  damaged.insert(damaged.begin() + 200, {'g', 'a', 'r', 'b', 'a', 'g', 'e', 0, 0, 0});
  write(logs / "damaged.lcmlog", damaged);
  std::printf("seeds written to %s\n", dir.c_str());
  return 0;
}
