#include "spindown/health_file.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fmt/format.h>
#include <set>
#include <stdexcept>
#include <toml++/toml.h>

#include "spindown/toml_file.hpp"

namespace spindown {

namespace {

struct HealthReader {
  const std::string& path;
  const toml::table& root;

  [[noreturn]] void fail(const std::string& key, const std::string& what) const {
    throw std::runtime_error(fmt::format("{}: key '{}': {}", path, key, what));
  }
  const toml::node* at(const std::string& key) const { return root.at_path(key).node(); }

  std::optional<double> number(const std::string& key) const {
    const auto* n = at(key);
    if (!n) return std::nullopt;
    auto v = n->value<double>();  // integers convert too
    if (!v) fail(key, "is not a number");
    if (!std::isfinite(*v)) fail(key, "is not finite");
    return v;
  }
  std::optional<double> positive(const std::string& key) const {
    auto v = number(key);
    if (v && !(*v > 0)) fail(key, fmt::format("must be positive (got {})", *v));
    return v;
  }
  std::optional<double> non_negative(const std::string& key) const {
    auto v = number(key);
    if (v && *v < 0) fail(key, fmt::format("must not be negative (got {})", *v));
    return v;
  }
  std::optional<std::string> text_or_date(const std::string& key) const {
    const auto* n = at(key);
    if (!n) return std::nullopt;
    if (auto s = n->value<std::string>()) return s;
    if (auto d = n->value<toml::date>()) return fmt::format("{:04}-{:02}-{:02}", d->year, d->month, d->day);
    if (auto dt = n->value<toml::date_time>())
      return fmt::format("{:04}-{:02}-{:02}T{:02}:{:02}:{:02}", dt->date.year, dt->date.month, dt->date.day,
                         dt->time.hour, dt->time.minute, dt->time.second);
    fail(key, "is not a string or date");
  }
  // A typo in these sections would silently drop a reference: unknown keys are errors.
  void only_keys(const std::string& section, const std::set<std::string>& known) const {
    const auto* n = at(section);
    if (!n) return;
    const auto* t = n->as_table();
    if (!t) fail(section, "is not a table");
    for (const auto& [key, value] : *t) {
      (void)value;
      const std::string name(key.str());
      if (!known.contains(name)) {
        std::string list;
        for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
        fail(section + "." + name, fmt::format("unknown key (known: {})", list));
      }
    }
  }
};

}  // namespace

MotorHealthConfig load_motor_health_config(const std::string& path) {
  const toml::table root = parse_toml_file(path);
  const HealthReader r{path, root};
  MotorHealthConfig cfg;
  cfg.source = path;

  r.only_keys("motor", {"speed_constant_rpm_per_v", "no_load_speed_rpm", "no_load_current_a",
                        "torque_constant_nm_per_a", "rotor_inertia_kg_m2"});
  r.only_keys("baseline", {"c_viscous_n_m_s", "c_viscous_stderr", "c_viscous_spread", "c_coulomb_n_m",
                           "c_coulomb_stderr", "c_coulomb_spread", "runs", "date", "inertia_kg_m2", "source",
                           "omega0_rad_s", "omega0_spread"});
  r.only_keys("health", {"check_ratio", "service_ratio", "significance_sigma", "max_slowdown_s",
                         "slowdown_fraction", "max_stop_s", "stop_change_fraction"});

  if (r.at("motor")) {
    MotorDatasheet ds;
    ds.speed_constant_rpm_per_v = r.positive("motor.speed_constant_rpm_per_v");
    ds.no_load_speed_rpm = r.positive("motor.no_load_speed_rpm");
    ds.no_load_current_a = r.positive("motor.no_load_current_a");
    ds.torque_constant_nm_per_a = r.positive("motor.torque_constant_nm_per_a");
    ds.rotor_inertia_kg_m2 = r.positive("motor.rotor_inertia_kg_m2");
    if (ds.no_load_current_a && !ds.torque_constant())
      r.fail("motor.no_load_current_a", "needs torque_constant_nm_per_a or speed_constant_rpm_per_v beside it");
    if (!ds.empty()) cfg.datasheet = ds;
  }

  if (r.at("baseline")) {
    HealthBaseline b;
    const auto cv = r.non_negative("baseline.c_viscous_n_m_s");
    const auto cc = r.non_negative("baseline.c_coulomb_n_m");
    if (!cv) r.fail("baseline.c_viscous_n_m_s", "missing (a baseline needs both c_viscous_n_m_s and c_coulomb_n_m)");
    if (!cc) r.fail("baseline.c_coulomb_n_m", "missing (a baseline needs both c_viscous_n_m_s and c_coulomb_n_m)");
    if (*cv == 0 && *cc == 0) r.fail("baseline.c_coulomb_n_m", "both baseline coefficients are zero");
    b.c_viscous = *cv;
    b.c_coulomb = *cc;
    b.c_viscous_stderr = r.non_negative("baseline.c_viscous_stderr").value_or(0);
    b.c_coulomb_stderr = r.non_negative("baseline.c_coulomb_stderr").value_or(0);
    b.c_viscous_spread = r.non_negative("baseline.c_viscous_spread").value_or(0);
    b.c_coulomb_spread = r.non_negative("baseline.c_coulomb_spread").value_or(0);
    b.inertia_kg_m2 = r.non_negative("baseline.inertia_kg_m2").value_or(0);
    b.omega0 = r.non_negative("baseline.omega0_rad_s").value_or(0);
    b.omega0_spread = r.non_negative("baseline.omega0_spread").value_or(0);
    if (const auto* n = r.at("baseline.runs")) {
      if (!n->is_integer() || n->value<long long>().value() < 1) r.fail("baseline.runs", "is not a positive integer");
      b.runs = static_cast<int>(std::min<long long>(n->value<long long>().value(), 1'000'000));
    }
    b.date = r.text_or_date("baseline.date").value_or("");
    if (const auto* n = r.at("baseline.source")) {
      if (!n->is_string()) r.fail("baseline.source", "is not a string");
      b.source = n->value<std::string>().value();
    }
    cfg.baseline = b;
  }

  HealthThresholds& th = cfg.thresholds;
  th.check_ratio = r.number("health.check_ratio").value_or(th.check_ratio);
  th.service_ratio = r.number("health.service_ratio").value_or(th.service_ratio);
  th.significance_sigma = r.number("health.significance_sigma").value_or(th.significance_sigma);
  th.max_slowdown_s = r.number("health.max_slowdown_s").value_or(th.max_slowdown_s);
  th.slowdown_fraction = r.number("health.slowdown_fraction").value_or(th.slowdown_fraction);
  th.max_stop_s = r.number("health.max_stop_s").value_or(th.max_stop_s);
  th.stop_change_fraction = r.number("health.stop_change_fraction").value_or(th.stop_change_fraction);
  std::string why;
  if (!th.is_valid(&why)) throw std::runtime_error(fmt::format("{}: [health]: {}", path, why));
  return cfg;
}

std::string bench_id_of_config(const std::string& path) {
  const toml::table root = parse_toml_file(path);
  if (const auto* n = root.get("bench_id")) {
    if (!n->is_string()) throw std::runtime_error(fmt::format("{}: key 'bench_id': is not a string", path));
    return n->value<std::string>().value();
  }
  return std::filesystem::path(path).stem().string();
}

}  // namespace spindown
