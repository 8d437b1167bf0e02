#include "spindown/bridge_settings.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <fmt/format.h>
#include <stdexcept>
#include <toml++/toml.h>

#include "spindown/fail_why.hpp"
#include "spindown/lcm_channels.hpp"
#include "spindown/serial_port.hpp"
#include "spindown/toml_file.hpp"

namespace spindown {

bool BridgeSettings::is_valid(std::string* why) const {
  std::string r;
  if (!is_valid_bench_id(bench, &r)) return fail_why(why, r);
  if (device.empty()) return fail_why(why, "no serial device given");
  if (!is_supported_baud(baud)) return fail_why(why, fmt::format("unsupported baud rate {}", baud));
  if (!params.is_valid(&r)) return fail_why(why, r);
  if (adc_bits < 1 || adc_bits > 16) return fail_why(why, fmt::format("adc bits {} not in 1-16", adc_bits));
  if (!(adc_ref_v > 0 && adc_ref_v <= 100)) return fail_why(why, fmt::format("adc ref_v {} not in (0, 100] V", adc_ref_v));
  if (!(lab_period_s > 0 && lab_period_s <= 10)) return fail_why(why, fmt::format("lab period_s {} not in (0, 10] s", lab_period_s));
  if (max_line_bytes < 16 || max_line_bytes > (1u << 20))
    return fail_why(why, fmt::format("max_line_bytes {} not in 16-1048576", max_line_bytes));
  if (max_batch < 1 || max_batch > 1000) return fail_why(why, fmt::format("max_batch {} not in 1-1000", max_batch));
  if (!(config_interval_s >= 0.1 && config_interval_s <= 60))
    return fail_why(why, fmt::format("config_interval_s {} not in [0.1, 60]", config_interval_s));
  if (!(status_interval_s >= 0.1 && status_interval_s <= 60))
    return fail_why(why, fmt::format("status_interval_s {} not in [0.1, 60]", status_interval_s));
  return true;
}

namespace {

struct Reader {
  const std::string& path;
  const toml::table& root;

  [[noreturn]] void fail(const std::string& key, const std::string& what) const {
    throw std::runtime_error(fmt::format("{}: key '{}': {}", path, key, what));
  }
  const toml::node* at(const std::string& key) const { return root.at_path(key).node(); }

  bool number(const std::string& key, double& out) const {
    const auto* n = at(key);
    if (!n) return false;
    if (auto v = n->value<double>()) {  // integers convert too
      if (!std::isfinite(*v)) fail(key, "is not finite");
      out = *v;
      return true;
    }
    fail(key, "is not a number");
  }
  bool integer(const std::string& key, long long& out) const {
    const auto* n = at(key);
    if (!n) return false;
    if (!n->is_integer()) fail(key, "is not an integer");
    out = n->value<long long>().value();
    return true;
  }
  bool text(const std::string& key, std::string& out) const {
    const auto* n = at(key);
    if (!n) return false;
    if (!n->is_string()) fail(key, "is not a string");
    out = n->value<std::string>().value();
    return true;
  }
};

}  // namespace

std::string kb_disagreement(const std::string& path, double bench_kb, const std::string& bench_kb_key, double kb_rel_error,
                            double motor_constant, const std::string& motor_key) {
  if (!(bench_kb > 0) || !(motor_constant > 0)) return {};
  const double apart = std::max(bench_kb / motor_constant, motor_constant / bench_kb) - 1;
  const double allowed = std::max(kb_disagreement_floor, 2 * kb_rel_error);
  if (!(apart > allowed)) return {};
  return fmt::format(
      "{}: warning: {} and {} disagree by {:.0f} % (one motor's constants agree within {:.0f} %{}): the fits use "
      "[bench]'s K_b (c2, c4 and ω0 scale with 1/K_b; a bridge reading this file puts it in its CONFIG), [motor]'s "
      "only for the datasheet's expected friction in the health verdict; check which belongs to this bench's motor",
      path, bench_kb_key, motor_key, 100 * apart, 100 * allowed,
      allowed > kb_disagreement_floor ? ", twice the file's kb_error_pct" : "");
}

void load_bridge_settings(const std::string& path, BridgeSettings& s) {
  const toml::table root = parse_toml_file(path);
  const Reader r{path, root};
  s.warnings.clear();  // this file's
  long long i = 0;
  double d = 0;
  std::string t;

  r.text("bench_id", s.bench);
  r.text("serial.device", s.device);
  if (r.integer("serial.baud", i)) s.baud = int(i);
  if (r.integer("serial.max_line_bytes", i)) {
    if (i < 16 || i > (1 << 20)) r.fail("serial.max_line_bytes", "not in 16-1048576");
    s.max_line_bytes = std::size_t(i);
  }

  if (r.number("bench.inertia_kg_m2", d)) {
    s.params.inertia_kg_m2 = d;
    s.params.inertia_source = "config file";
  } else if (r.at("bench.flywheel_radius_m")) {
    double radius = 0, height = 0, density = 0, rotor = 0;
    if (!r.number("bench.flywheel_radius_m", radius) || !r.number("bench.flywheel_height_m", height) ||
        !r.number("bench.flywheel_density_kg_m3", density))
      r.fail("bench.flywheel_*", "flywheel needs radius_m, height_m and density_kg_m3");
    r.number("bench.rotor_inertia_kg_m2", rotor);
    s.params.inertia_kg_m2 = cylinder_inertia(radius, height, density) + rotor;
    s.params.inertia_source = fmt::format("geometry r={} m h={} m rho={} kg/m3 + rotor {} kg*m2", radius,
                                          height, density, rotor);
  }
  r.text("bench.inertia_source", s.params.inertia_source);
  if (r.number("bench.kb_v_s_per_rad", d)) {
    s.params.kb_v_s_per_rad = d;
    s.params.kb_source = "config file";
  } else if (r.number("bench.speed_constant_rpm_per_v", d)) {
    if (!(d > 0)) r.fail("bench.speed_constant_rpm_per_v", "must be positive");
    s.params.kb_v_s_per_rad = kb_from_speed_constant(d);
    s.params.kb_source = fmt::format("speed constant {} rpm/V", d);
  }
  r.text("bench.kb_source", s.params.kb_source);
  std::string bench_kb_key;
  if (r.at("bench.kb_v_s_per_rad"))
    bench_kb_key = fmt::format("[bench] kb_v_s_per_rad = {:.6g} V·s/rad", s.params.kb_v_s_per_rad);
  else if (r.at("bench.speed_constant_rpm_per_v"))
    bench_kb_key = fmt::format("[bench] speed_constant_rpm_per_v = {:.6g} rpm/V (K_b {:.6g} V·s/rad)",
                               r.at("bench.speed_constant_rpm_per_v")->value<double>().value_or(0),
                               s.params.kb_v_s_per_rad);
  // Their standard uncertainties in percent (geometry and density; the datasheet's tolerance).
  for (const auto& [key, field] : {std::pair{"bench.inertia_error_pct", &BenchParams::inertia_rel_error},
                                   std::pair{"bench.kb_error_pct", &BenchParams::kb_rel_error}}) {
    if (!r.number(key, d)) continue;
    if (!(d >= 0 && d < 100)) r.fail(key, fmt::format("{} is not a percentage in 0-100", d));
    s.params.*field = d / 100;
  }
  // [bench] K_b beside the datasheet's [motor] constants (that section is the health file's: only
  // numbers are looked at here, its own checks are load_motor_health_config's).
  if (!bench_kb_key.empty()) {
    const auto motor_number = [&](const char* key) {
      const toml::node* n = r.at(key);
      const std::optional<double> v = n ? n->value<double>() : std::nullopt;
      return v && std::isfinite(*v) && *v > 0 ? *v : 0.0;
    };
    if (const double kn = motor_number("motor.speed_constant_rpm_per_v"); kn > 0) {
      std::string w = kb_disagreement(path, s.params.kb_v_s_per_rad, bench_kb_key, s.params.kb_rel_error,
                                      kb_from_speed_constant(kn),
                                      fmt::format("[motor] speed_constant_rpm_per_v = {:.6g} rpm/V (K_b {:.6g} V·s/rad)",
                                                  kn, kb_from_speed_constant(kn)));
      if (!w.empty()) s.warnings.push_back(std::move(w));
    }
    if (const double km = motor_number("motor.torque_constant_nm_per_a"); km > 0) {
      std::string w = kb_disagreement(path, s.params.kb_v_s_per_rad, bench_kb_key, s.params.kb_rel_error, km,
                                      fmt::format("[motor] torque_constant_nm_per_a = {:.6g} N·m/A (the same as K_b in "
                                                  "V·s/rad)",
                                                  km));
      if (!w.empty()) s.warnings.push_back(std::move(w));
    }
  }
  if (r.text("bench.quantity", t)) {
    const auto q = parse_quantity(t);
    if (!q) r.fail("bench.quantity", fmt::format("unknown quantity '{}' (want V, rpm or rad/s)", t));
    s.quantity = *q;
  }

  if (r.integer("adc.bits", i)) s.adc_bits = int(i);
  r.number("adc.ref_v", s.adc_ref_v);
  r.number("lab.period_s", s.lab_period_s);
  if (r.integer("publish.max_batch", i)) {
    if (i < 1 || i > 1000) r.fail("publish.max_batch", "not in 1-1000");
    s.max_batch = std::size_t(i);
  }
  r.number("publish.config_interval_s", s.config_interval_s);
  r.number("publish.status_interval_s", s.status_interval_s);

  std::string why;
  BridgeSettings check = s;
  if (check.bench.empty()) check.bench = "x";      // the CLI may still supply these
  if (check.device.empty()) check.device = "/dev/null";
  if (!check.is_valid(&why)) throw std::runtime_error(fmt::format("{}: {}", path, why));
}

}  // namespace spindown
