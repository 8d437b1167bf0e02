#include "spindown/effects.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>

namespace spindown {
namespace {

double zero(const RunScale&) { return 0.0; }

// --- viscous: T = c_v·ω -------------------------------------------------------------------
Effect make_viscous() {
  Effect e;
  e.name = "viscous";
  e.meaning = "drag proportional to speed (lubricant shear, eddy currents)";
  e.term = "T = c_v·ω";
  e.signature = "the decay rate stays proportional to speed: a straight-line model bends too little early on";
  e.params = {{"c_v", "N*m*s/rad", "viscous coefficient", true, zero, [](const RunScale&) { return 1e3; },
               [](const RunScale& s) { return 1.0 / s.duration_s; }}};
  e.rate = [](const double* p, double w, double* dw, double* dp) {
    if (dw) *dw = p[0];
    if (dp) dp[0] = w;
    return p[0] * w;
  };
  e.shape = [](const double*, double w) { return w; };
  return e;
}

// --- coulomb: T = c_c ----------------------------------------------------------------------
Effect make_coulomb() {
  Effect e;
  e.name = "coulomb";
  e.meaning = "dry friction independent of speed (brushes, bearing preload); it makes the shaft stop";
  e.term = "T = c_c";
  e.signature = "the speed falls linearly and reaches zero in finite time: an exponential decays too slowly "
                "at low speed and never stops";
  e.params = {{"c_c", "N*m", "Coulomb friction torque", true, zero,
               [](const RunScale& s) { return 1e3 * s.omega0 / s.duration_s; },
               [](const RunScale& s) { return s.omega0 / s.duration_s; }}};
  e.rate = [](const double* p, double, double* dw, double* dp) {
    if (dw) *dw = 0;
    if (dp) dp[0] = 1;
    return p[0];
  };
  e.shape = [](const double*, double) { return 1.0; };
  return e;
}

// --- stribeck: T += (c_s − c_c)·exp(−(ω/ω_s)²) -----------------------------------------------
Effect make_stribeck() {
  Effect e;
  e.name = "stribeck";
  e.meaning = "friction rising toward standstill as the lubricant film breaks down (boundary lubrication)";
  e.term = "T = (c_s − c_c)·exp(−(ω/ω_s)²)";
  e.signature = "the last part of the coast decelerates harder than the model: the data reach zero earlier "
                "and more abruptly, residuals negative just before the stop";
  e.params = {{"c_s_minus_c_c", "N*m", "static friction above Coulomb (c_s - c_c)", true, zero,
               [](const RunScale& s) { return 1e3 * s.omega0 / s.duration_s; },
               [](const RunScale& s) { return s.omega0 / s.duration_s; }},
              // A bump broader than 40 % of the top speed is not boundary lubrication (and would mimic
              // windage or Coulomb friction).
              {"w_s", "rad/s", "Stribeck speed", false, [](const RunScale& s) { return 0.01 * s.omega0; },
               [](const RunScale& s) { return 0.4 * s.omega0; }, [](const RunScale& s) { return 0.1 * s.omega0; }}};
  e.rate = [](const double* p, double w, double* dw, double* dp) {
    const double ws = std::max(p[1], 1e-12);
    const double x = w / ws;
    const double g = std::exp(-x * x);
    if (dw) *dw = p[0] * g * (-2 * x / ws);
    if (dp) {
      dp[0] = g;
      dp[1] = p[0] * g * (2 * x * x / ws);
    }
    return p[0] * g;
  };
  e.shape = [](const double* p, double w) {
    const double x = w / std::max(p[1], 1e-12);
    return std::exp(-x * x);
  };
  e.shape_starts = [](const RunScale& s) {
    return std::vector<double>{0.03 * s.omega0, 0.06 * s.omega0, 0.12 * s.omega0, 0.25 * s.omega0};
  };
  return e;
}

// --- windage: T = c_w·ω² -------------------------------------------------------------------
Effect make_windage() {
  Effect e;
  e.name = "windage";
  e.meaning = "aerodynamic drag of the flywheel, growing with the square of speed";
  e.term = "T = c_w·ω²";
  e.signature = "the first seconds decelerate harder than the model, fading quickly as the speed drops: "
                "residuals negative early, then positive";
  e.params = {{"c_w", "N*m*s^2/rad^2", "windage coefficient", true, zero,
               [](const RunScale& s) { return 1e3 / (s.omega0 * s.duration_s); },
               [](const RunScale& s) { return 1.0 / (s.omega0 * s.duration_s); }}};
  e.rate = [](const double* p, double w, double* dw, double* dp) {
    if (dw) *dw = 2 * p[0] * w;
    if (dp) dp[0] = w * w;
    return p[0] * w * w;
  };
  e.shape = [](const double*, double w) { return w * w; };
  return e;
}

// --- sensor_offset: reading = k·ω + offset -------------------------------------------------
Effect make_sensor_offset() {
  Effect e;
  e.name = "sensor_offset";
  e.meaning = "the sensor reads a constant offset: the reading does not return to its zero at standstill";
  e.term = "reading = k·ω + sensor offset";
  e.signature = "a constant residual where the shaft stands still (and a shifted curve while it coasts)";
  e.kind = EffectKind::sensor;
  e.params = {{"offset", "reading", "sensor offset", false,
               [](const RunScale& s) { return std::max(-0.5 * s.reading_max, s.offset_lo); },
               [](const RunScale& s) { return std::min(0.5 * s.reading_max, s.offset_hi); },
               [](const RunScale& s) { return 0.01 * s.reading_max; }}};
  e.reading = [](const double* p, double, double* dp) {
    if (dp) dp[0] = 1;
    return p[0];
  };
  return e;
}

const std::vector<Effect>& table() {
  static const std::vector<Effect> effects = {make_viscous(), make_coulomb(), make_stribeck(), make_windage(),
                                              make_sensor_offset()};
  return effects;
}

}  // namespace

std::span<const Effect> effect_library() { return table(); }

const Effect* find_effect(std::string_view name) {
  for (const auto& e : table())
    if (e.name == name) return &e;
  return nullptr;
}

std::vector<std::string> effect_names() {
  std::vector<std::string> out;
  for (const auto& e : table()) out.emplace_back(e.name);
  return out;
}

std::vector<const Effect*> parse_effect_list(std::string_view text, std::string* why) {
  std::vector<bool> chosen(table().size(), false);
  bool any = false;
  std::size_t pos = 0;
  while (pos <= text.size()) {
    const std::size_t comma = std::min(text.find(',', pos), text.size());
    std::string_view item = text.substr(pos, comma - pos);
    while (!item.empty() && item.front() == ' ') item.remove_prefix(1);
    while (!item.empty() && item.back() == ' ') item.remove_suffix(1);
    pos = comma + 1;
    if (item.empty()) continue;
    std::vector<std::string_view> names;
    if (item == "combined")
      names = {"viscous", "coulomb"};
    else
      names = {item};
    for (auto n : names) {
      const Effect* e = find_effect(n);
      if (!e) {
        if (why) {
          std::string known = "combined";
          for (const auto& k : table()) known += fmt::format(", {}", k.name);
          *why = fmt::format("unknown effect '{}' (known: {})", n, known);
        }
        return {};
      }
      chosen[static_cast<std::size_t>(e - table().data())] = true;
      any = true;
    }
  }
  if (!any) {
    if (why) *why = "no effect named";
    return {};
  }
  std::vector<const Effect*> out;
  for (std::size_t i = 0; i < table().size(); ++i)
    if (chosen[i]) out.push_back(&table()[i]);
  return out;
}

}  // namespace spindown
