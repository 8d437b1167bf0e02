#include "spindown/virtual_bench.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <random>
#include <stdexcept>
#include <utility>

#include "physics_truth.hpp"
#include "spindown/spindown_protocol.hpp"

namespace spindown {

bool VirtualBenchOptions::is_valid(std::string* why) const {
  auto fail = [&](std::string r) {
    if (why) *why = std::move(r);
    return false;
  };
  if (runs < 1 || runs > 10000) return fail(fmt::format("runs {} not in 1-10000", runs));
  if (!(idle_s >= 0 && idle_s < 3600)) return fail("idle_s not in [0, 3600)");
  if (!(spec.period_s >= 0.001 && spec.period_s <= 1.0)) return fail("period not in 1 ms - 1 s");
  if (protocol == BenchProtocol::spindown_v1 && spec.period_s > 0.020 + 1e-12)
    return fail("spindown-v1 firmware period is 1-20 ms");
  if (!(spec.jitter_s >= 0 && spec.jitter_s < spec.period_s / 2)) return fail("jitter must be below half the period");
  if (effective_baud() < 300) return fail("baud below 300");
  if (!(boot_s >= 0 && boot_s < 60)) return fail("boot_s not in [0, 60)");
  if (!(unplug_for_s >= 0 && unplug_for_s < 600)) return fail("unplug_for_s not in [0, 600)");
  if (long_line_bytes > (256u << 20)) return fail("long_line_bytes above 256 MiB");
  if (garbage_every < 0 || partial_every < 0) return fail("garbage/partial every N must be ≥ 0");
  if (protocol == BenchProtocol::spindown_v1 && spec.adc_bits <= 0) return fail("spindown-v1 needs an ADC (adc_bits > 0)");
  // The physics: a NaN or infinity never reaches the simulator (it would integrate forever),
  // and friction, noise and times cannot be negative.
  const auto& f = spec.friction;
  const std::pair<const char*, double> at_least_zero[] = {
      {"viscous", f.viscous},   {"coulomb", f.coulomb},       {"stribeck-static", f.stribeck_static},
      {"stribeck-speed", f.stribeck_speed}, {"windage", f.windage}, {"noise", spec.noise_v},
      {"ripple", spec.ripple},  {"lead-in-s", spec.lead_in_s}, {"tail-s", spec.tail_s},
      {"start-s", spec.start_s}, {"gap-s", spec.gap_s}};
  for (const auto& [name, v] : at_least_zero)
    if (!(std::isfinite(v) && v >= 0)) return fail(fmt::format("--{} {} must be a finite number ≥ 0", name, v));
  const std::pair<const char*, double> above_zero[] = {{"e0", spec.e0_v},
                                                       {"inertia", spec.bench.inertia_kg_m2},
                                                       {"kb", spec.bench.kb_v_s_per_rad},
                                                       {"max-coast-s", spec.max_coast_s},
                                                       {"adc reference", spec.adc_ref_v}};
  for (const auto& [name, v] : above_zero)
    if (!(std::isfinite(v) && v > 0)) return fail(fmt::format("--{} {} must be a finite number > 0", name, v));
  const std::pair<const char*, double> finite[] = {{"supply", spec.supply_v}, {"offset", spec.offset_v},
                                                   {"e0-step", e0_step_v}, {"unplug-at", unplug_at_s},
                                                   {"long-line-at", long_line_at_s}};
  for (const auto& [name, v] : finite)
    if (!std::isfinite(v)) return fail(fmt::format("--{} {} must be a finite number", name, v));
  for (const double r : reset_at_s)
    if (!(std::isfinite(r) && r >= 0)) return fail(fmt::format("--reset-at {} must be a finite time ≥ 0", r));
  if (f.stribeck_static > 0 && !(f.stribeck_speed > 0))
    return fail("--stribeck-static needs --stribeck-speed > 0 (the speed scale of the Stribeck dip)");
  if (!std::isfinite(spec.pulse_timeout_s))
    return fail(fmt::format("--pulse-timeout-s {} must be a finite number", spec.pulse_timeout_s));
  if (!std::isfinite(spec.gap_from_s)) return fail(fmt::format("--gap-from-s {} must be a finite number", spec.gap_from_s));
  if (spec.lead_in == LeadIn::spin_up && !(std::isfinite(spec.spin_up_s) && spec.spin_up_s > 0 && spec.spin_up_s <= spec.lead_in_s))
    return fail(fmt::format("--spin-up-s {} must be > 0 and at most --lead-in-s ({})", spec.spin_up_s, spec.lead_in_s));
  if (spec.glitches < 0 || spec.glitches > 1000) return fail(fmt::format("--glitches {} not in 0-1000", spec.glitches));
  if (spec.pulses_per_rev < 0 || spec.pulses_per_rev > 10000)
    return fail(fmt::format("--pulses-per-rev {} not in 0-10000", spec.pulses_per_rev));
  if (spec.max_coast_s > 3600) return fail(fmt::format("--max-coast-s {} above an hour", spec.max_coast_s));
  if (spec.adc_bits < 0 || spec.adc_bits > 24) return fail(fmt::format("--adc-bits {} not in 0-24", spec.adc_bits));
  if (spec.decimals > 15) return fail(fmt::format("--decimals {} above 15", spec.decimals));
  return true;
}

namespace {

// Bench time runs on; the device clock restarts at each reset (device time = since boot).
struct DeviceState {
  double boot_at_s = 0;      // bench time the sketch started
  std::int32_t epoch = 0;
  std::uint32_t seq = 0;
  double silent_until_s = 0; // bootloader, or cable out
};

// The bench's output in time order: each emission with the time its last byte leaves the wire
// (8N1 at the effective baud), the samples the device sent, and the truth of what happened.
class Schedule {
 public:
  Schedule(const VirtualBenchOptions& o, std::vector<BenchEmission>& emissions, std::vector<SentSample>& sent,
           nlohmann::json& truth)
      : o_(o),
        emissions_(emissions),
        sent_(sent),
        truth_(truth),
        byte_s_(10.0 / o.effective_baud()),
        rng_(o.seed ^ 0x9e3779b97f4a7c15ull),
        v1_(o.protocol == BenchProtocol::spindown_v1),
        resets_(o.reset_at_s),
        unplug_done_(o.unplug_at_s < 0),
        long_done_(o.long_line_at_s < 0 || o.long_line_bytes == 0) {
    banner_.firmware = o.firmware;
    banner_.version = o.version;
    banner_.adc_bits = o.spec.adc_bits;
    banner_.adc_ref_v = o.spec.adc_ref_v;
    banner_.period_us = static_cast<std::uint32_t>(std::lround(o.spec.period_s * 1e6));
    banner_.baud = o.effective_baud();
    std::sort(resets_.begin(), resets_.end());
  }

  void run() && {
    if (v1_) emit(BenchEmission::Kind::banner, 0.0, format_spindown_banner(banner_));
    write_setup_truth();
    double run_start_s = 0.5;  // the sketch's first samples come a little after boot
    for (int k = 0; k < o_.runs; ++k) run_start_s = schedule_run(k, run_start_s);
    write_fault_truth();
  }

 private:
  void emit(BenchEmission::Kind kind, double at_s, std::string bytes) {
    const double start = std::max(at_s, wire_free_s_);
    BenchEmission e;
    e.kind = kind;
    e.wire_s = start + double(bytes.size()) * byte_s_;
    if (kind == BenchEmission::Kind::long_line) e.wire_s = start;  // written at once, not paced
    e.bytes = std::move(bytes);
    wire_free_s_ = e.wire_s;
    emissions_.push_back(std::move(e));
  }

  void restart_device(double at_s) {
    ++dev_.epoch;
    dev_.seq = 0;
    dev_.boot_at_s = at_s + o_.boot_s;
    dev_.silent_until_s = dev_.boot_at_s;
    if (v1_) emit(BenchEmission::Kind::banner, dev_.boot_at_s, format_spindown_banner(banner_));
    truth_["resets"].push_back({{"bench_s", at_s}, {"epoch", dev_.epoch}});
  }

  void write_setup_truth() {
    const SyntheticRunSpec& spec = o_.spec;
    truth_["protocol"] = v1_ ? "spindown-v1" : "lab-tsv";
    truth_["baud"] = o_.effective_baud();
    write_physics_truth(truth_, spec.bench, spec.friction);
    truth_["offset"] = spec.offset_v;
    // What the pin reads before each cut (the runs' lead-in), and the supply it reads with "supply".
    truth_["lead_in"] = spec.lead_in == LeadIn::zeros      ? "zeros"
                        : spec.lead_in == LeadIn::floating ? "floating"
                        : spec.lead_in == LeadIn::supply   ? "supply"
                                                           : "spin-up";
    truth_["supply_v"] = spec.supply_v;
    truth_["noise_v"] = spec.noise_v;
    truth_["ripple"] = spec.ripple;
    truth_["period_s"] = spec.period_s;
    truth_["jitter_s"] = spec.jitter_s;
    truth_["runs"] = nlohmann::json::array();
    truth_["resets"] = nlohmann::json::array();
  }

  // Run k from bench time run_start_s: its samples as the device prints them, its truth; returns
  // when the next run starts.
  double schedule_run(int k, double run_start_s) {
    SyntheticRunSpec spec = o_.spec;
    spec.seed = o_.spec.seed + std::uint64_t(k) * 7919;
    spec.e0_v = o_.spec.e0_v + k * o_.e0_step_v;
    spec.t0_ms = 0;
    const SyntheticRun run = make_synthetic_run(spec);
    nlohmann::json rt = run_truth(k, spec, run, run_start_s);
    std::int64_t first_sent = -1;
    for (std::size_t i = 0; i < run.t_ms.size(); ++i) {
      const double t = run_start_s + run.t_ms[i] / 1000.0;  // bench time of this sample
      faults_due(t);
      if (t < dev_.silent_until_s) continue;  // booting or unplugged: nothing printed
      const std::size_t before = sent_.size();
      send_sample(run, i, spec, t, rt);
      if (first_sent < 0 && sent_.size() > before) first_sent = std::int64_t(before);
    }
    rt["first_sample"] = first_sent;
    rt["last_sample"] = std::int64_t(sent_.size()) - 1;
    truth_["runs"].push_back(rt);
    return run_start_s + (run.t_ms.empty() ? 0.0 : run.t_ms.back() / 1000.0 + spec.period_s + o_.idle_s);
  }

  static nlohmann::json run_truth(int k, const SyntheticRunSpec& spec, const SyntheticRun& run, double run_start_s) {
    nlohmann::json rt{{"run", k + 1},        {"e0", spec.e0_v},       {"w0", run.omega0},
                      {"t_stop_s", run.t_stop_s}, {"stopped", run.stopped}, {"cut_bench_s", run_start_s + run.t_cut_ms / 1000.0}};
    if (spec.start_s > 0) rt["starts_mid_coast_s"] = spec.start_s;
    // The handout's floating pin: the coast is in the readings from the pin's connection on.
    if (run.t_connect_ms != run.t_cut_ms) rt["connect_bench_s"] = run_start_s + run.t_connect_ms / 1000.0;
    if (!run.bounce_index.empty()) {
      auto& b = rt["bounce_bench_s"] = nlohmann::json::array();
      for (std::size_t i : run.bounce_index) b.push_back(run_start_s + run.t_ms[i] / 1000.0);
    }
    if (spec.gap_s > 0) rt["gap_bench_s"] = {run_start_s + run.t_cut_ms / 1000.0 + spec.gap_from_s, spec.gap_s};
    if (run.t_signal_lost_ms >= 0) rt["signal_lost_bench_s"] = run_start_s + run.t_signal_lost_ms / 1000.0;
    if (!run.glitch_index.empty()) {
      auto& g = rt["glitch_bench_s"] = nlohmann::json::array();
      for (std::size_t i : run.glitch_index) g.push_back(run_start_s + run.t_ms[i] / 1000.0);
    }
    return rt;
  }

  // The faults due by bench time t: resets, the unplug (the board boots when USB power returns),
  // the long line.
  void faults_due(double t) {
    while (next_reset_ < resets_.size() && resets_[next_reset_] <= t) restart_device(resets_[next_reset_++]);
    if (!unplug_done_ && o_.unplug_at_s <= t) {
      unplug_done_ = true;
      BenchEmission e;
      e.kind = BenchEmission::Kind::unplug;
      e.wire_s = std::max(o_.unplug_at_s, wire_free_s_);
      e.unplug_for_s = o_.unplug_for_s;
      emissions_.push_back(e);
      wire_free_s_ = e.wire_s + o_.unplug_for_s;
      truth_["unplug"] = {{"bench_s", e.wire_s}, {"for_s", o_.unplug_for_s}};
      restart_device(e.wire_s + o_.unplug_for_s);
    }
    if (!long_done_ && o_.long_line_at_s <= t) {
      long_done_ = true;
      std::string junk(o_.long_line_bytes, 'x');
      for (std::size_t j = 0; j < junk.size(); j += 97) junk[j] = char('A' + j % 26);
      junk += "\r\n";
      emit(BenchEmission::Kind::long_line, t, std::move(junk));
    }
  }

  // Sample i as the sketch prints it (or a line cut short, or one followed by garbage).
  void send_sample(const SyntheticRun& run, std::size_t i, const SyntheticRunSpec& spec, double t, nlohmann::json& rt) {
    const double dev_s = t - dev_.boot_at_s;
    const auto millis = static_cast<std::uint64_t>(std::floor(dev_s * 1000.0 + 1e-9));
    const std::uint32_t seq = dev_.seq++;
    std::string line;
    SentSample s;
    s.epoch = dev_.epoch;
    s.device_time_us = std::int64_t(millis) * 1000;
    if (v1_) {
      // micros() of the sample: the simulation's millisecond grid (wraps at 2^32 µs).
      const auto micros = static_cast<std::uint32_t>(millis * 1000 % (1ull << 32));
      const int adc = std::max(run.adc[i], 0);
      line = format_spindown_sample(seq, micros, adc);
      s.value = adc * banner_.volts_per_count();
      s.raw_adc = adc;
      s.device_seq = seq;
    } else {
      line = fmt::format("{}\t{}\r\n", millis, printed_value(run.volts[i], spec.decimals));
      s.value = std::stod(line.substr(line.find('\t') + 1));
    }
    ++sample_lines_;
    if (o_.partial_every > 0 && sample_lines_ % o_.partial_every == 0) {
      // A line cut short (bytes lost): only the start of the time field, then the newline.
      const auto cut = std::max<std::size_t>(1, std::min<std::size_t>(line.find_first_of("\t,"), 3) - 1);
      emit(BenchEmission::Kind::partial, t, line.substr(0, cut) + "\r\n");
      return;
    }
    emit(BenchEmission::Kind::sample, t, std::move(line));
    sent_.push_back(s);
    const bool last = i + 1 >= run.t_ms.size();
    if (!last && run.t_ms[i] <= run.t_cut_ms && run.t_ms[i + 1] > run.t_cut_ms) {
      rt["cut_epoch"] = dev_.epoch;
      rt["cut_device_us"] = s.device_time_us + std::int64_t(std::llround((run.t_cut_ms - run.t_ms[i]) * 1000.0));
    }
    // The floating pin's connection: where the coast enters the readings (the cut as a reader of
    // the readings can see it; the power was cut earlier, unseen).
    if (run.t_connect_ms != run.t_cut_ms && !last && run.t_ms[i] <= run.t_connect_ms &&
        run.t_ms[i + 1] > run.t_connect_ms)
      rt["connect_device_us"] = s.device_time_us + std::int64_t(std::llround((run.t_connect_ms - run.t_ms[i]) * 1000.0));
    if (o_.garbage_every > 0 && sample_lines_ % o_.garbage_every == 0) {
      std::string junk;
      const int n = 3 + int(rng_() % 20);
      for (int j = 0; j < n; ++j) junk += char(0x80 + rng_() % 0x7f);  // never '\n', never a number
      emit(BenchEmission::Kind::garbage, t, junk + "\r\n");
    }
  }

  void write_fault_truth() {
    truth_["samples"] = sent_.size();
    std::size_t garbage = 0, partial = 0, long_lines = 0;
    for (const auto& e : emissions_) {
      garbage += e.kind == BenchEmission::Kind::garbage;
      partial += e.kind == BenchEmission::Kind::partial;
      long_lines += e.kind == BenchEmission::Kind::long_line;
    }
    truth_["faults"] = {{"garbage_lines", garbage}, {"partial_lines", partial}, {"long_lines", long_lines},
                        {"resets", o_.reset_at_s.size()}, {"unplugs", o_.unplug_at_s >= 0 ? 1 : 0}};
  }

  const VirtualBenchOptions& o_;
  std::vector<BenchEmission>& emissions_;
  std::vector<SentSample>& sent_;
  nlohmann::json& truth_;
  const double byte_s_;  // one byte on the wire, 8N1
  std::mt19937_64 rng_;
  const bool v1_;
  SpindownBanner banner_;
  DeviceState dev_;
  double wire_free_s_ = 0;  // when the UART has sent everything queued so far
  std::vector<double> resets_;
  std::size_t next_reset_ = 0;
  bool unplug_done_, long_done_;
  long sample_lines_ = 0;
};

}  // namespace

VirtualBench::VirtualBench(VirtualBenchOptions options) : o_(std::move(options)) {
  std::string why;
  if (!o_.is_valid(&why)) throw std::invalid_argument("virtual bench: " + why);
  Schedule(o_, emissions_, sent_, truth_).run();
  truth_["duration_s"] = duration_s();
}

std::string garble_for_baud(std::string_view bytes, int sender_baud, int reader_baud, std::uint64_t& state) {
  // A reader slower than the sender sees fewer, framing-broken bytes; a faster one sees many.
  const double ratio = std::clamp(double(reader_baud) / std::max(sender_baud, 1), 0.05, 16.0);
  static constexpr unsigned char patterns[] = {0x00, 0x80, 0xF8, 0xFE, 0xE0, 0xC0, 0xF0, 0x9E, 0xFC, 0x86};
  std::string out;
  double acc = 0;
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    acc += ratio;
    for (; acc >= 1.0; acc -= 1.0) {
      state = state * 6364136223846793005ull + 1442695040888963407ull;
      const auto r = static_cast<unsigned>(state >> 33);
      out += (r % 61 == 0) ? '\n' : static_cast<char>(patterns[r % sizeof patterns]);
    }
  }
  return out;
}

}  // namespace spindown
