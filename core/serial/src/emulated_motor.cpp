#include "spindown/emulated_motor.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <stdexcept>
#include <utility>

#include "physics_truth.hpp"

namespace spindown {

bool EmulatedMotorOptions::is_valid(std::string* why) const {
  auto fail = [&](std::string r) {
    if (why) *why = std::move(r);
    return false;
  };
  if (runs < 1 || runs > 1000) return fail(fmt::format("runs {} not in 1-1000", runs));
  const std::pair<const char*, double> at_least_zero[] = {
      {"first-run-s", first_run_s}, {"lead-in-s", lead_in_s}, {"tail-s", tail_s},
      {"idle", idle_s},             {"noise", noise_v},       {"viscous", friction.viscous},
      {"coulomb", friction.coulomb}, {"stribeck-static", friction.stribeck_static},
      {"stribeck-speed", friction.stribeck_speed}, {"windage", friction.windage}};
  for (const auto& [name, v] : at_least_zero)
    if (!(std::isfinite(v) && v >= 0 && v < 1e6)) return fail(fmt::format("--{} {} must be a finite number ≥ 0", name, v));
  const std::pair<const char*, double> above_zero[] = {{"e0", e0_v},
                                                       {"inertia", bench.inertia_kg_m2},
                                                       {"kb", bench.kb_v_s_per_rad},
                                                       {"max-coast-s", max_coast_s},
                                                       {"adc reference", adc_ref_v}};
  for (const auto& [name, v] : above_zero)
    if (!(std::isfinite(v) && v > 0)) return fail(fmt::format("--{} {} must be a finite number > 0", name, v));
  if (!std::isfinite(e0_step_v) || !std::isfinite(supply_v)) return fail("--e0-step and --supply must be finite");
  if (max_coast_s > 3600) return fail(fmt::format("--max-coast-s {} above an hour", max_coast_s));
  if (adc_bits < 1 || adc_bits > 16) return fail(fmt::format("adc bits {} not in 1-16", adc_bits));
  if (friction.stribeck_static > 0 && !(friction.stribeck_speed > 0))
    return fail("--stribeck-static needs --stribeck-speed > 0");
  for (int k = 0; k < runs; ++k)
    if (!(e0_v + k * e0_step_v > 0)) return fail(fmt::format("run {} would start at e0 ≤ 0", k + 1));
  return true;
}

EmulatedMotor::EmulatedMotor(EmulatedMotorOptions options) : o_(std::move(options)), rng_(o_.seed ^ 0x5bd1e995u) {
  std::string why;
  if (!o_.is_valid(&why)) throw std::invalid_argument("emulated motor: " + why);
  double t = o_.first_run_s;
  for (int k = 0; k < o_.runs; ++k) {
    RunTimes r{};
    r.lead_in_s = t;
    r.cut_s = t + o_.lead_in_s;
    r.e0 = o_.e0_v + k * o_.e0_step_v;
    r.omega0 = r.e0 / o_.bench.kb_v_s_per_rad;
    CoastSimulator probe(o_.friction, o_.bench.inertia_kg_m2, r.omega0);
    probe.advance(o_.max_coast_s);
    r.stopped = probe.stopped();
    r.stop_s = r.cut_s + (r.stopped ? probe.stop_time() : o_.max_coast_s);
    r.end_s = r.stop_s + o_.tail_s;
    runs_.push_back(r);
    t = r.end_s + o_.idle_s;
  }
  end_s_ = runs_.back().end_s;
}

double EmulatedMotor::volts_at(double t_s) {
  t_s = std::max(t_s, last_t_);  // time never goes back (a caller's rounding aside)
  last_t_ = t_s;
  while (run_ < runs_.size() && t_s >= runs_[run_].end_s) {
    ++run_;
    coast_.reset();
  }
  double v = 0.0;
  if (run_ < runs_.size()) {
    const RunTimes& r = runs_[run_];
    if (t_s < r.lead_in_s) {
      v = 0.0;  // at rest before the run
    } else if (t_s < r.cut_s) {
      v = o_.lead_in_supply ? o_.supply_v : 0.0;  // powered: the pin reads the supply side
    } else if (t_s < r.stop_s) {
      if (!coast_) coast_ = std::make_unique<CoastSimulator>(o_.friction, o_.bench.inertia_kg_m2, r.omega0);
      const double dt = (t_s - r.cut_s) - coast_->time();
      const double omega = coast_->advance(std::max(dt, 0.0));
      v = o_.bench.kb_v_s_per_rad * omega;
    }
  }
  if (o_.noise_v > 0) v += o_.noise_v * noise_(rng_);
  return v;
}

int EmulatedMotor::counts_for(double volts) const {
  const double full = std::ldexp(1.0, o_.adc_bits);
  const double c = std::floor(volts / o_.adc_ref_v * full + 0.5);
  return static_cast<int>(std::clamp(c, 0.0, full - 1.0));
}

int EmulatedMotor::convert(double t_s) {
  ++conversions_;
  return counts_for(volts_at(t_s));
}

nlohmann::json EmulatedMotor::truth_json(const std::vector<double>& boots_s, const nlohmann::json& extra) const {
  nlohmann::json t;
  write_physics_truth(t, o_.bench, o_.friction);
  t["offset"] = 0.0;
  t["lead_in"] = o_.lead_in_supply ? "supply" : "zeros";
  t["supply_v"] = o_.supply_v;
  t["noise_v"] = o_.noise_v;
  t["ripple"] = 0.0;
  t["adc_bits"] = o_.adc_bits;
  t["adc_ref_v"] = o_.adc_ref_v;
  t["runs"] = nlohmann::json::array();
  t["resets"] = nlohmann::json::array();
  for (std::size_t e = 1; e < boots_s.size(); ++e) t["resets"].push_back({{"bench_s", boots_s[e]}, {"epoch", e}});
  for (std::size_t k = 0; k < runs_.size(); ++k) {
    const RunTimes& r = runs_[k];
    nlohmann::json rt{{"run", k + 1},          {"e0", r.e0},          {"w0", r.omega0},
                      {"t_stop_s", r.stop_s - r.cut_s}, {"stopped", r.stopped}, {"cut_bench_s", r.cut_s},
                      {"stop_bench_s", r.stop_s}};
    // The boot before the cut names the epoch and the device clock's zero.
    std::size_t epoch = 0;
    bool booted = false;
    for (std::size_t e = 0; e < boots_s.size(); ++e)
      if (boots_s[e] <= r.cut_s) {
        epoch = e;
        booted = true;
      }
    if (booted) {
      rt["cut_epoch"] = epoch;
      rt["cut_device_us"] = std::llround((r.cut_s - boots_s[epoch]) * 1e6);
      // A reset between the cut and the stop breaks the run: the device clock restarts mid-coast.
      bool whole = true;
      for (std::size_t e = epoch + 1; e < boots_s.size(); ++e)
        if (boots_s[e] < r.stop_s) whole = false;
      rt["reset_mid_coast"] = !whole;
    }
    t["runs"].push_back(rt);
  }
  t["conversions"] = conversions_;
  t["duration_s"] = end_s_;
  for (const auto& [key, value] : extra.items()) t[key] = value;
  return t;
}

}  // namespace spindown
