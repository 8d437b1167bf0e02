#include "spindown/bridge_settings.hpp"

#include <cmath>
#include <fmt/format.h>
#include <stdexcept>
#include <toml++/toml.h>

#include "spindown/lcm_channels.hpp"
#include "spindown/serial_port.hpp"
#include "spindown/toml_file.hpp"

namespace spindown {

bool BridgeSettings::is_valid(std::string* why) const {
  auto fail = [&](std::string reason) {
    if (why) *why = std::move(reason);
    return false;
  };
  std::string r;
  if (!is_valid_bench_id(bench, &r)) return fail(r);
  if (device.empty()) return fail("no serial device given");
  if (!is_supported_baud(baud)) return fail(fmt::format("unsupported baud rate {}", baud));
  if (!params.is_valid(&r)) return fail(r);
  if (adc_bits < 1 || adc_bits > 16) return fail(fmt::format("adc bits {} not in 1-16", adc_bits));
  if (!(adc_ref_v > 0 && adc_ref_v <= 100)) return fail(fmt::format("adc ref_v {} not in (0, 100] V", adc_ref_v));
  if (!(lab_period_s > 0 && lab_period_s <= 10)) return fail(fmt::format("lab period_s {} not in (0, 10] s", lab_period_s));
  if (max_line_bytes < 16 || max_line_bytes > (1u << 20))
    return fail(fmt::format("max_line_bytes {} not in 16-1048576", max_line_bytes));
  if (max_batch < 1 || max_batch > 1000) return fail(fmt::format("max_batch {} not in 1-1000", max_batch));
  if (!(config_interval_s >= 0.1 && config_interval_s <= 60))
    return fail(fmt::format("config_interval_s {} not in [0.1, 60]", config_interval_s));
  if (!(status_interval_s >= 0.1 && status_interval_s <= 60))
    return fail(fmt::format("status_interval_s {} not in [0.1, 60]", status_interval_s));
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

void load_bridge_settings(const std::string& path, BridgeSettings& s) {
  const toml::table root = parse_toml_file(path);
  const Reader r{path, root};
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
  // Their standard uncertainties in percent (geometry and density; the datasheet's tolerance).
  for (const auto& [key, field] : {std::pair{"bench.inertia_error_pct", &BenchParams::inertia_rel_error},
                                   std::pair{"bench.kb_error_pct", &BenchParams::kb_rel_error}}) {
    if (!r.number(key, d)) continue;
    if (!(d >= 0 && d < 100)) r.fail(key, fmt::format("{} is not a percentage in 0-100", d));
    s.params.*field = d / 100;
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
