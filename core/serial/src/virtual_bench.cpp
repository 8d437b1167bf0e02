#include "spindown/virtual_bench.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <random>
#include <stdexcept>
#include <utility>

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

}  // namespace

VirtualBench::VirtualBench(VirtualBenchOptions options) : o_(std::move(options)) {
  std::string why;
  if (!o_.is_valid(&why)) throw std::invalid_argument("virtual bench: " + why);
  const double byte_s = 10.0 / o_.effective_baud();  // 8N1
  std::mt19937_64 rng(o_.seed ^ 0x9e3779b97f4a7c15ull);
  const bool v1 = o_.protocol == BenchProtocol::spindown_v1;

  SpindownBanner banner;
  banner.firmware = o_.firmware;
  banner.version = o_.version;
  banner.adc_bits = o_.spec.adc_bits;
  banner.adc_ref_v = o_.spec.adc_ref_v;
  banner.period_us = static_cast<std::uint32_t>(std::lround(o_.spec.period_s * 1e6));
  banner.baud = o_.effective_baud();
  const double vpc = banner.volts_per_count();

  DeviceState dev;
  dev.boot_at_s = 0;
  double wire_free_s = 0;  // when the UART has sent everything queued so far
  auto emit = [&](BenchEmission::Kind kind, double at_s, std::string bytes) {
    const double start = std::max(at_s, wire_free_s);
    BenchEmission e;
    e.kind = kind;
    e.wire_s = start + double(bytes.size()) * byte_s;
    if (kind == BenchEmission::Kind::long_line) e.wire_s = start;  // written at once, not paced
    e.bytes = std::move(bytes);
    wire_free_s = e.wire_s;
    emissions_.push_back(std::move(e));
  };
  if (v1) emit(BenchEmission::Kind::banner, 0.0, format_spindown_banner(banner));

  std::vector<double> resets = o_.reset_at_s;
  std::sort(resets.begin(), resets.end());
  std::size_t next_reset = 0;
  bool unplug_done = o_.unplug_at_s < 0;
  bool long_done = o_.long_line_at_s < 0 || o_.long_line_bytes == 0;
  long sample_lines = 0;

  auto restart_device = [&](double at_s) {
    ++dev.epoch;
    dev.seq = 0;
    dev.boot_at_s = at_s + o_.boot_s;
    dev.silent_until_s = dev.boot_at_s;
    if (v1) emit(BenchEmission::Kind::banner, dev.boot_at_s, format_spindown_banner(banner));
    truth_["resets"].push_back({{"bench_s", at_s}, {"epoch", dev.epoch}});
  };

  truth_["protocol"] = v1 ? "spindown-v1" : "lab-tsv";
  truth_["baud"] = o_.effective_baud();
  truth_["inertia_kg_m2"] = o_.spec.bench.inertia_kg_m2;
  truth_["kb_v_s_per_rad"] = o_.spec.bench.kb_v_s_per_rad;
  truth_["c_v"] = o_.spec.friction.viscous;
  truth_["c_c"] = o_.spec.friction.coulomb;
  truth_["c_s"] = o_.spec.friction.stribeck_static;
  truth_["w_s"] = o_.spec.friction.stribeck_speed;
  truth_["c_w"] = o_.spec.friction.windage;
  truth_["offset"] = o_.spec.offset_v;
  // What the pin reads before each cut (the runs' lead-in), and the supply it reads with "supply".
  truth_["lead_in"] = o_.spec.lead_in == LeadIn::zeros      ? "zeros"
                      : o_.spec.lead_in == LeadIn::floating ? "floating"
                      : o_.spec.lead_in == LeadIn::supply   ? "supply"
                                                            : "spin-up";
  truth_["supply_v"] = o_.spec.supply_v;
  truth_["noise_v"] = o_.spec.noise_v;
  truth_["ripple"] = o_.spec.ripple;
  truth_["period_s"] = o_.spec.period_s;
  truth_["jitter_s"] = o_.spec.jitter_s;
  truth_["runs"] = nlohmann::json::array();
  truth_["resets"] = nlohmann::json::array();

  double run_start_s = 0.5;  // the sketch's first samples come a little after boot
  for (int k = 0; k < o_.runs; ++k) {
    SyntheticRunSpec spec = o_.spec;
    spec.seed = o_.spec.seed + std::uint64_t(k) * 7919;
    spec.e0_v = o_.spec.e0_v + k * o_.e0_step_v;
    spec.t0_ms = 0;
    const SyntheticRun run = make_synthetic_run(spec);
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
    std::int64_t first_sent = -1;
    for (std::size_t i = 0; i < run.t_ms.size(); ++i) {
      const double t = run_start_s + run.t_ms[i] / 1000.0;  // bench time of this sample
      while (next_reset < resets.size() && resets[next_reset] <= t) restart_device(resets[next_reset++]);
      if (!unplug_done && o_.unplug_at_s <= t) {
        unplug_done = true;
        BenchEmission e;
        e.kind = BenchEmission::Kind::unplug;
        e.wire_s = std::max(o_.unplug_at_s, wire_free_s);
        e.unplug_for_s = o_.unplug_for_s;
        emissions_.push_back(e);
        wire_free_s = e.wire_s + o_.unplug_for_s;
        truth_["unplug"] = {{"bench_s", e.wire_s}, {"for_s", o_.unplug_for_s}};
        restart_device(e.wire_s + o_.unplug_for_s);  // USB power returns: the board boots
      }
      if (!long_done && o_.long_line_at_s <= t) {
        long_done = true;
        std::string junk(o_.long_line_bytes, 'x');
        for (std::size_t j = 0; j < junk.size(); j += 97) junk[j] = char('A' + j % 26);
        junk += "\r\n";
        emit(BenchEmission::Kind::long_line, t, std::move(junk));
      }
      if (t < dev.silent_until_s) continue;  // booting or unplugged: nothing printed
      const double dev_s = t - dev.boot_at_s;
      const auto millis = static_cast<std::uint64_t>(std::floor(dev_s * 1000.0 + 1e-9));
      const std::uint32_t seq = dev.seq++;
      std::string line;
      SentSample s;
      s.epoch = dev.epoch;
      if (v1) {
        // micros() of the sample: the simulation's millisecond grid (wraps at 2^32 µs).
        const auto micros = static_cast<std::uint32_t>(millis * 1000 % (1ull << 32));
        const int adc = std::max(run.adc[i], 0);
        line = format_spindown_sample(seq, micros, adc);
        s.device_time_us = std::int64_t(millis) * 1000;
        s.value = adc * vpc;
        s.raw_adc = adc;
        s.device_seq = seq;
      } else {
        line = fmt::format("{}\t{}\r\n", millis, printed_value(run.volts[i], spec.decimals));
        s.device_time_us = std::int64_t(millis) * 1000;
        s.value = std::stod(line.substr(line.find('\t') + 1));
      }
      ++sample_lines;
      if (o_.partial_every > 0 && sample_lines % o_.partial_every == 0) {
        // A line cut short (bytes lost): only the start of the time field, then the newline.
        const auto cut = std::max<std::size_t>(1, std::min<std::size_t>(line.find_first_of("\t,") , 3) - 1);
        emit(BenchEmission::Kind::partial, t, line.substr(0, cut) + "\r\n");
        continue;
      }
      emit(BenchEmission::Kind::sample, t, std::move(line));
      if (first_sent < 0) first_sent = std::int64_t(sent_.size());
      sent_.push_back(s);
      if (i + 1 < run.t_ms.size() && run.t_ms[i] <= run.t_cut_ms && run.t_ms[i + 1] > run.t_cut_ms) {
        rt["cut_epoch"] = dev.epoch;
        rt["cut_device_us"] = s.device_time_us + std::int64_t(std::llround((run.t_cut_ms - run.t_ms[i]) * 1000.0));
      }
      // The floating pin's connection: where the coast enters the readings (the cut as a reader of
      // the readings can see it; the power was cut earlier, unseen).
      if (run.t_connect_ms != run.t_cut_ms && i + 1 < run.t_ms.size() && run.t_ms[i] <= run.t_connect_ms &&
          run.t_ms[i + 1] > run.t_connect_ms)
        rt["connect_device_us"] = s.device_time_us + std::int64_t(std::llround((run.t_connect_ms - run.t_ms[i]) * 1000.0));
      if (o_.garbage_every > 0 && sample_lines % o_.garbage_every == 0) {
        std::string junk;
        const int n = 3 + int(rng() % 20);
        for (int j = 0; j < n; ++j) junk += char(0x80 + rng() % 0x7f);  // never '\n', never a number
        emit(BenchEmission::Kind::garbage, t, junk + "\r\n");
      }
    }
    rt["first_sample"] = first_sent;
    rt["last_sample"] = std::int64_t(sent_.size()) - 1;
    truth_["runs"].push_back(rt);
    run_start_s += run.t_ms.empty() ? 0.0 : run.t_ms.back() / 1000.0 + spec.period_s + o_.idle_s;
  }
  truth_["samples"] = sent_.size();
  std::size_t garbage = 0, partial = 0, long_lines = 0;
  for (const auto& e : emissions_) {
    garbage += e.kind == BenchEmission::Kind::garbage;
    partial += e.kind == BenchEmission::Kind::partial;
    long_lines += e.kind == BenchEmission::Kind::long_line;
  }
  truth_["faults"] = {{"garbage_lines", garbage}, {"partial_lines", partial}, {"long_lines", long_lines},
                      {"resets", o_.reset_at_s.size()}, {"unplugs", o_.unplug_at_s >= 0 ? 1 : 0}};
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
