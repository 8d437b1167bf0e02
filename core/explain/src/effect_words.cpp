// The words the workflow's story uses for an effect: its torque term, its meaning and its
// signature in the residual, as fitted on this run.
#include "spindown/explain.hpp"

#include <cmath>
#include <fmt/format.h>

namespace spindown {

std::string effect_term(const Effect& effect, const EffectFit& fit) {
  const auto has = [&](std::string_view name) { return fit.param(name) != nullptr; };
  const std::string coulomb = has("c4") ? "c4" : has("c2") ? "c2" : "";
  if (effect.name == "viscous") return fmt::format("T = {}·ω", has("c3") ? "c3" : "c1");
  if (effect.name == "coulomb") return fmt::format("T = {}", coulomb.empty() ? "c2" : coulomb);
  if (effect.name == "stribeck")
    return coulomb.empty() ? "T = c_s·exp(−(ω/ω_s)²)" : fmt::format("T = (c_s − {})·exp(−(ω/ω_s)²)", coulomb);
  return std::string(effect.term);
}

namespace {

// Stribeck friction whose speed scale is a third of the top speed or more.
bool broad_stribeck(const Effect& effect, const EffectFit& fit, double top_speed) {
  const Parameter* ws = fit.param("w_s");
  return effect.name == "stribeck" && ws && std::isfinite(ws->value) && top_speed > 0 && ws->value >= top_speed / 3;
}

}  // namespace

std::string effect_meaning(const Effect& effect, const EffectFit& fit, double top_speed) {
  const Parameter* ws = fit.param("w_s");
  if (broad_stribeck(effect, fit, top_speed)) {
    // exp(−(ω/ω_s)²) halves at ω_s·√ln 2.
    const double half = ws->value * std::sqrt(std::log(2.0));
    return fmt::format("friction that falls with speed over much of the coast, not only near standstill: the extra "
                       "friction above Coulomb's halves by {:.3g} rad/s, {:.0f} % of the top speed {:.3g} rad/s "
                       "(ω_s = {:.3g} rad/s) - far wider than a lubricant film breaking down near standstill",
                       half, 100 * half / top_speed, top_speed, ws->value);
  }
  if (effect.name == "stribeck" && ws && std::isfinite(ws->value) && top_speed > 0)
    return fmt::format("{} (ω_s = {:.3g} rad/s, {:.0f} % of the top speed {:.3g} rad/s)", effect.meaning, ws->value,
                       100 * ws->value / top_speed, top_speed);
  return std::string(effect.meaning);
}

std::string effect_signature(const Effect& effect, const EffectFit& fit, double top_speed) {
  if (broad_stribeck(effect, fit, top_speed))
    return "the coast decelerates harder as it slows over much of its length, more than viscous and Coulomb friction "
           "allow: residuals of one sign early and late, of the other in between";
  return std::string(effect.signature);
}

}  // namespace spindown
