#include "spindown/fit_view.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>

#include "spindown/fit_message.hpp"
#include "spindown/lab_units.hpp"

namespace spindown {

namespace {

std::size_t model_index(const fit_t& msg, std::string_view name) {
  const auto n = static_cast<std::size_t>(std::max(0, msg.nmodels));
  for (std::size_t i = 0; i < n && i < msg.model.size(); ++i)
    if (msg.model[i] == name) return i;
  return n;
}

// "1.805 ± 0.011 g·cm²·s⁻¹" (lab units) or "(1.805 ± 0.011)e-07 N·m·s/rad".
std::string value_text(double value, double err, std::string_view si_unit, bool lab_units) {
  std::string_view unit = pretty_unit(si_unit);
  if (lab_units)
    if (auto lab = lab_unit_for(si_unit)) {
      value *= lab->per_si;
      err *= lab->per_si;
      unit = lab->pretty;
    }
  return fmt::format("{} {}", format_value_error(value, err), unit);
}

// Parameter name of model model_name in the message: {"value","stderr","unit","text","model"} or null.
Json param_json(const fit_t& msg, std::string_view model_name, std::string_view param, bool lab_units) {
  const std::size_t i = model_index(msg, model_name);
  const auto n = static_cast<std::size_t>(std::max(0, msg.nparams));
  for (std::size_t k = 0; k < n && k < msg.param_name.size() && k < msg.param_model.size() &&
                          k < msg.param_value.size() && k < msg.param_stderr.size() && k < msg.param_unit.size();
       ++k) {
    if (msg.param_model[k] != static_cast<std::int32_t>(i) || msg.param_name[k] != param) continue;
    Json j;
    j["value"] = json_number(msg.param_value[k]);
    j["stderr"] = json_number(msg.param_stderr[k]);
    j["unit"] = msg.param_unit[k];
    j["model"] = std::string(model_name);
    // The text in the units the service was started with, and in both (the page's units toggle).
    j["text"] = value_text(msg.param_value[k], msg.param_stderr[k], msg.param_unit[k], lab_units);
    j["text_lab"] = value_text(msg.param_value[k], msg.param_stderr[k], msg.param_unit[k], true);
    j["text_si"] = value_text(msg.param_value[k], msg.param_stderr[k], msg.param_unit[k], false);
    const double bench_error = k < msg.param_bench_error.size() ? msg.param_bench_error[k] : 0.0;
    if (bench_error > 0) {
      const double total = std::hypot(msg.param_stderr[k], bench_error);
      j["total_stderr"] = json_number(total);
      j["total_text"] = value_text(msg.param_value[k], total, msg.param_unit[k], lab_units);
      j["total_text_lab"] = value_text(msg.param_value[k], total, msg.param_unit[k], true);
      j["total_text_si"] = value_text(msg.param_value[k], total, msg.param_unit[k], false);
    }
    return j;
  }
  return nullptr;
}

// The model's reading at τ seconds after the cut.
double model_reading(const RunFit& fit, const ModelFit& m, double tau) {
  return fit.run.zero_level + value_per_rad_per_s(fit.quantity, fit.bench.kb_v_s_per_rad) * m.omega_at(tau);
}

// τ from the cut to the end of what the plot shows: the fitted window, or the run's samples when
// they go on (the tail), and the predicted stops of the models that stop within twice that.
double curve_end(const RunFit& fit, const RunTrace* trace) {
  double end = fit.run.t_end_s - fit.run.t_cut_s;
  if (trace && trace->kept() > 0) end = std::max(end, trace->samples().back().t_s - fit.run.t_cut_s);
  if (!(end > 0) || !std::isfinite(end)) end = 1.0;
  return end;
}

Json curve_json(const RunFit& fit, const ModelFit& m, double tau_end, std::size_t points) {
  Json pts = Json::array();
  points = std::max<std::size_t>(points, 2);
  for (std::size_t i = 0; i < points; ++i) {
    const double tau = tau_end * double(i) / double(points - 1);
    pts.push_back(plot_point(tau, model_reading(fit, m, tau)));
  }
  return pts;
}

const ModelFit* named_model(const RunFit& fit, std::string_view name) {
  const auto kind = parse_model(name);
  return kind ? fit.model(*kind) : nullptr;
}

// v rounded to digits significant digits, the nearest double to that decimal (a division by an
// exact power of ten), so the shortest text that reads back is short too.
double round_significant(double v, int digits) {
  if (v == 0 || !std::isfinite(v)) return v;
  const int shift = digits - 1 - static_cast<int>(std::floor(std::log10(std::fabs(v))));
  if (shift <= 0 || shift > 22) return v;
  const double p = std::pow(10.0, shift);
  return std::round(v * p) / p;
}

}  // namespace

Json json_number(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }

Json plot_point(double x, double y) {
  return Json::array({std::isfinite(x) ? Json(std::round(x * 1e4) / 1e4) : Json(nullptr), json_number(round_significant(y, 7))});
}

std::string health_text(const fit_t& msg) {
  if (msg.verdict == "ok" || msg.verdict == "check" || msg.verdict == "service") return msg.verdict;
  return "not judged";
}

Json fit_summary_json(const fit_t& msg, bool lab_units) {
  Json j;
  j["run"] = msg.run;
  j["partial"] = msg.lead_in == "none";
  j["best"] = msg.best;
  j["best_reason"] = msg.best_reason;
  j["c1"] = param_json(msg, "viscous", "c1", lab_units);
  j["c2"] = param_json(msg, "coulomb", "c2", lab_units);
  j["c3"] = param_json(msg, "combined", "c3", lab_units);
  j["c4"] = param_json(msg, "combined", "c4", lab_units);
  j["health"] = health_text(msg);
  j["health_reason"] = msg.verdict_reason;
  Json doubts = Json::array();
  for (std::size_t i = 0; i < msg.doubts.size() && i < static_cast<std::size_t>(std::max(0, msg.ndoubts)); ++i)
    doubts.push_back(msg.doubts[i]);
  j["doubts"] = std::move(doubts);
  const std::size_t best = model_index(msg, msg.best);
  j["rmse"] = best < msg.rmse.size() ? json_number(msg.rmse[best]) : Json(nullptr);
  j["residual_unit"] = msg.residual_unit;
  j["t_cut_s"] = json_number(msg.t_cut_s);
  j["t_stop_s"] = json_number(msg.t_stop_s);
  j["t_end_s"] = json_number(msg.t_end_s);
  j["end"] = msg.end;
  j["bench_source"] = msg.bench_source;
  j["samples"] = msg.samples;
  // What the lab record prints: J and K_b the fit used and where they came from, and when.
  j["inertia_kg_m2"] = json_number(msg.inertia_kg_m2);
  j["kb_v_s_per_rad"] = json_number(msg.kb_v_s_per_rad);
  j["inertia_source"] = msg.inertia_source;
  j["kb_source"] = msg.kb_source;
  j["unix_ms"] = msg.utime > 0 ? Json(msg.utime / 1000) : Json(nullptr);  // the FIT's time (the fitter's clock)
  return j;
}

Json best_curve_json(const fit_t& msg, std::size_t points) {
  const auto fit = from_fit_message(msg);
  if (!fit) return Json::array();
  const ModelFit* m = named_model(*fit, fit->best);
  if (!m || !m->converged) return Json::array();
  return curve_json(*fit, *m, curve_end(*fit, nullptr), points);
}

std::optional<Json> fit_curves_json(const fit_t& msg, const RunTrace* trace, std::size_t curve_points,
                                    std::size_t max_residuals, std::string* why) {
  const auto fit = from_fit_message(msg, why);
  if (!fit) return std::nullopt;
  const double tau_end = curve_end(*fit, trace);
  Json j;
  Json models = Json::array();
  for (std::size_t i = 0; i < fit->models.size(); ++i) {
    const ModelFit& m = fit->models[i];
    Json mj;
    mj["name"] = std::string(model_name(m.kind));
    mj["converged"] = m.converged;
    mj["rmse"] = json_number(m.rmse);
    mj["t_stop_pred_s"] = json_number(m.t_stop_pred_s);
    mj["message"] = m.message;
    mj["curve"] = m.converged ? curve_json(*fit, m, tau_end, curve_points) : Json::array();
    models.push_back(std::move(mj));
  }
  j["models"] = std::move(models);
  j["residuals"] = nullptr;
  const ModelFit* best = named_model(*fit, fit->best);
  if (trace && best && best->converged) {
    // The samples of the fitted window [cut, end], thinned to at most max_residuals.
    std::vector<const TracePoint*> in;
    for (const TracePoint& p : trace->samples())
      if (p.t_s >= fit->run.t_cut_s && p.t_s <= fit->run.t_end_s) in.push_back(&p);
    const std::size_t stride = std::max<std::size_t>(1, (in.size() + max_residuals - 1) / std::max<std::size_t>(max_residuals, 1));
    Json pts = Json::array();
    for (std::size_t k = 0; k < in.size(); k += stride) {
      const double tau = in[k]->t_s - fit->run.t_cut_s;
      pts.push_back(plot_point(tau, in[k]->value - model_reading(*fit, *best, tau)));
    }
    Json r;
    r["model"] = fit->best;
    r["unit"] = msg.residual_unit;
    r["noise"] = json_number(msg.reading_noise);
    r["points"] = std::move(pts);
    j["residuals"] = std::move(r);
  }
  return j;
}

Json explain_json(const explain_t& msg, bool lab_units) {
  Json j;
  j["run"] = msg.run;
  j["base"] = msg.base;
  j["rmse_base"] = json_number(msg.rmse_base);
  j["rmse_final"] = json_number(msg.rmse_final);
  j["noise_level"] = json_number(msg.noise_level);
  Json steps = Json::array();
  const auto ns = static_cast<std::size_t>(std::max(0, msg.nsteps));
  for (std::size_t i = 0; i < ns && i < msg.step_added.size() && i < msg.step_rmse_before.size() &&
                          i < msg.step_rmse_after.size() && i < msg.step_why.size();
       ++i) {
    Json s;
    s["added"] = msg.step_added[i];
    s["why"] = msg.step_why[i];
    s["rmse_before"] = json_number(msg.step_rmse_before[i]);
    s["rmse_after"] = json_number(msg.step_rmse_after[i]);
    Json where = Json::array();
    const auto nw = static_cast<std::size_t>(std::max(0, msg.nwhere));
    for (std::size_t w = 0; w < nw && w < msg.where_step.size() && w < msg.where_t_from_s.size() &&
                            w < msg.where_t_to_s.size() && w < msg.where_mean_residual.size();
         ++w)
      if (msg.where_step[w] == static_cast<std::int32_t>(i))
        where.push_back({{"t_from_s", json_number(msg.where_t_from_s[w])},
                         {"t_to_s", json_number(msg.where_t_to_s[w])},
                         {"mean_residual", json_number(msg.where_mean_residual[w])}});
    s["where"] = std::move(where);
    steps.push_back(std::move(s));
  }
  j["steps"] = std::move(steps);
  j["final"] = msg.final_effects;
  Json params = Json::array();
  const auto np = static_cast<std::size_t>(std::max(0, msg.nparams));
  for (std::size_t k = 0; k < np && k < msg.param_name.size() && k < msg.param_value.size() &&
                          k < msg.param_stderr.size() && k < msg.param_unit.size();
       ++k)
    params.push_back({{"name", msg.param_name[k]},
                      {"value", json_number(msg.param_value[k])},
                      {"stderr", json_number(msg.param_stderr[k])},
                      {"unit", msg.param_unit[k]},
                      {"text", value_text(msg.param_value[k], msg.param_stderr[k], msg.param_unit[k], lab_units)},
                      {"text_lab", value_text(msg.param_value[k], msg.param_stderr[k], msg.param_unit[k], true)},
                      {"text_si", value_text(msg.param_value[k], msg.param_stderr[k], msg.param_unit[k], false)}});
  j["params"] = std::move(params);
  j["story"] = msg.story;
  return j;
}

}  // namespace spindown
