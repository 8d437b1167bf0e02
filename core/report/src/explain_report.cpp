#include "spindown/explain_report.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>

#include "spindown/fit_report.hpp"
#include "spindown/svg_plot.hpp"

namespace spindown {
namespace {

ExplainJson number(double x) { return std::isfinite(x) ? ExplainJson(x) : ExplainJson(nullptr); }

ExplainJson params_json(const EffectFit& f) {
  ExplainJson p = ExplainJson::object();
  for (const auto& q : f.params)
    p[q.name] = ExplainJson{{"value", number(q.value)}, {"stderr", number(q.std_error)}, {"unit", q.unit}};
  return p;
}

ExplainJson where_json(const std::vector<Disagreement>& where) {
  ExplainJson a = ExplainJson::array();
  for (const auto& d : where)
    a.push_back({{"t_from_s", number(d.t_from_s)},
                 {"t_to_s", number(d.t_to_s)},
                 {"mean_residual", number(d.mean_residual)},
                 {"tau_from_s", number(d.tau_from_s)},
                 {"tau_to_s", number(d.tau_to_s)},
                 {"omega_from_rad_s", number(d.omega_from)},
                 {"omega_to_rad_s", number(d.omega_to)},
                 {"peak_residual", number(d.peak_residual)},
                 {"z", number(d.z)}});
  return a;
}

ExplainJson trials_json(const std::vector<CandidateTrial>& trials) {
  ExplainJson a = ExplainJson::array();
  for (const auto& t : trials)
    a.push_back({{"effect", t.effect},
                 {"rmse", number(t.fit.rmse)},
                 {"delta_bic", number(t.delta_bic)},
                 {"systematic_left", number(t.systematic_after)},
                 {"verdict", t.verdict}});
  return a;
}

std::string ratio_text(double before, double after) {
  if (!(after > 0) || !std::isfinite(before / after)) return "";
  const double r = before / after;
  return r >= 1.05 ? fmt::format("{:.3g}x smaller", r) : r > 0.95 ? "about the same" : fmt::format("{:.3g}x larger", 1 / r);
}

std::string with_unit(const std::string& v, const std::string& unit) { return unit.empty() ? v : v + " " + unit; }

std::string params_text(const EffectFit& f, std::string_view indent) {
  std::string out;
  for (const auto& p : f.params)
    out += fmt::format("{}{} = {}\n", indent, p.name, with_unit(format_value_error(p.value, p.std_error), p.unit));
  return out;
}

std::string where_text(const std::vector<Disagreement>& where, const std::string& unit, std::string_view indent) {
  std::string out;
  for (const auto& d : where)
    out += fmt::format("{}{:.2f}-{:.2f} s after the cut (speed {:.0f}->{:.0f} rad/s): data {} the model by {:.3g} {} "
                       "on average (peak {:.3g} {}, {:.0f}x the noise of a bin)\n",
                       indent, d.tau_from_s, d.tau_to_s, d.omega_from, d.omega_to,
                       d.mean_residual > 0 ? "above" : "below", std::abs(d.mean_residual), unit,
                       std::abs(d.peak_residual), unit, std::abs(d.z));
  return out;
}

}  // namespace

ExplainJson explain_run_json(const ExplainResult& r, std::string_view bench) {
  ExplainJson j;
  j["run"] = r.run.number;
  if (!bench.empty()) j["bench"] = bench;
  j["base"] = r.base.names();
  ExplainJson steps = ExplainJson::array();
  for (const auto& s : r.steps)
    steps.push_back({{"added", s.added},
                     {"rmse_before", number(s.rmse_before)},
                     {"rmse_after", number(s.rmse_after)},
                     {"where", where_json(s.where)},
                     {"why", s.why},
                     {"removed", s.removed},
                     {"candidates", trials_json(s.trials)},
                     {"params", params_json(s.fit)}});
  j["steps"] = steps;
  j["final"] = r.final_fit.names();
  j["rmse_base"] = number(r.rmse_base());
  j["rmse_final"] = number(r.rmse_final());
  // Extras (the contract allows more fields, never fewer).
  j["ok"] = r.ok;
  if (!r.message.empty()) j["message"] = r.message;
  j["residual_unit"] = r.unit;
  j["t_cut_s"] = number(r.run.t_cut_s);
  j["t_stop_s"] = number(r.run.t_stop_s);
  j["samples"] = r.tau.size();
  j["noise_level"] = number(r.noise_level);
  j["bin_noise"] = number(r.bin_noise);
  j["base_params"] = params_json(r.base);
  j["final_params"] = params_json(r.final_fit);
  j["t_stop_pred_s"] = number(r.final_fit.t_stop_pred_s);
  j["remaining"] = where_json(r.remaining);
  j["rejected_last"] = trials_json(r.final_trials);
  j["conclusion"] = r.conclusion;
  j["inertia_kg_m2"] = number(r.bench.inertia_kg_m2);
  j["kb_v_s_per_rad"] = number(r.bench.kb_v_s_per_rad);
  return j;
}

ExplainJson explain_report_json(std::span<const FileExplain> files) {
  ExplainJson out;
  ExplainJson arr = ExplainJson::array();
  for (const auto& f : files) {
    ExplainJson fj;
    fj["file"] = f.file;
    ExplainJson runs = ExplainJson::array();
    for (std::size_t i = 0; i < f.runs.size(); ++i)
      runs.push_back(explain_run_json(f.runs[i], i < f.run_bench.size() ? f.run_bench[i] : std::string_view{}));
    fj["runs"] = runs;
    fj["samples"] = f.samples;
    fj["failures"] = f.failures;
    arr.push_back(fj);
  }
  out["files"] = arr;
  return out;
}

std::string format_explain(const ExplainResult& r, std::string_view bench) {
  const std::string& u = r.unit;
  std::string out = fmt::format("run {}{}: cut at {:.3f} s, {} samples, noise {:.2g} {} per reading ({:.2g} {} per "
                                "{}-sample bin)\n",
                                r.run.number, bench.empty() ? std::string() : fmt::format(" of bench {}", bench),
                                r.run.t_cut_s, r.tau.size(), r.noise_level, u, r.bin_noise, u,
                                r.bin_samples);
  if (!r.ok) return out + fmt::format("  could not be explained: {}\n", r.message);
  out += fmt::format("  base model: {}   RMSE {:.4g} {}\n", r.base.label(), r.base.rmse, u);
  out += params_text(r.base, "    ");
  int number = 0;
  for (const auto& s : r.steps) {
    ++number;
    out += fmt::format("\n  step {}: where the model and the data disagree\n", number);
    out += where_text(s.where, u, "    ");
    const Effect* e = find_effect(s.added);
    out += fmt::format("  missing effect: {}", s.added);
    if (e) out += fmt::format(" - {} ({})\n    its signature: {}\n", e->meaning, e->term, e->signature);
    else out += "\n";
    out += fmt::format("    why: {}\n", s.why);
    for (const auto& t : s.trials)
      if (t.verdict != "added") out += fmt::format("    rejected {}: {}\n", t.effect, t.verdict);
    out += fmt::format("    model now: {}\n", s.fit.label());
    out += params_text(s.fit, "      ");
    out += fmt::format("    gap: RMSE {:.4g} {} -> {:.4g} {} ({})\n", s.rmse_before, u, s.rmse_after, u,
                       ratio_text(s.rmse_before, s.rmse_after));
  }
  out += fmt::format("\n  {}\n", r.conclusion.empty() ? "done" : r.conclusion);
  if (!r.final_trials.empty()) {
    for (const auto& t : r.final_trials) out += fmt::format("    {}: {}\n", t.effect, t.verdict);
    if (!r.remaining.empty()) {
      out += "    still visible:\n";
      out += where_text(r.remaining, u, "      ");
    }
  }
  if (r.steps.empty())
    out += fmt::format("  final model: {} (nothing added), RMSE {:.4g} {}\n", r.final_fit.label(), r.final_fit.rmse, u);
  else
    out += fmt::format("  final model: {}, RMSE {:.4g} {} (base {:.4g} {}: {})\n", r.final_fit.label(),
                       r.final_fit.rmse, u, r.base.rmse, u, ratio_text(r.base.rmse, r.final_fit.rmse));
  return out;
}

std::string format_file_explain(const FileExplain& file) {
  std::string out = fmt::format("{}\n", file.file);
  for (std::size_t i = 0; i < file.runs.size(); ++i)
    out += format_explain(file.runs[i], i < file.run_bench.size() ? file.run_bench[i] : std::string_view{}) + "\n";
  return out;
}

namespace {

using svg::Panel;
using svg::axes;
using svg::legend;
using svg::polyline;

constexpr double fig_w = 960, fig_h = 700;

std::string run_figure(const std::string& file, std::string_view bench, const ExplainResult& r, double top) {
  const std::string& u = r.unit;
  const std::size_t n = r.tau.size();
  std::string s;
  const std::string name = file.substr(file.find_last_of('/') == std::string::npos ? 0 : file.find_last_of('/') + 1);
  const std::string title = fmt::format("{}{} - run {}: base {} (RMSE {:.3g} {}) -> {} (RMSE {:.3g} {})", name,
                                        bench.empty() ? std::string() : fmt::format(" bench {}", bench), r.run.number, r.base.label(), r.base.rmse, u, r.final_fit.label(),
                                        r.final_fit.rmse, u);
  s += fmt::format("<text x=\"{}\" y=\"{:.1f}\" text-anchor=\"middle\" font-size=\"15\" font-weight=\"bold\">{}</text>\n",
                   fig_w / 2, top + 22, svg::escape(title));
  if (n == 0 || !r.ok) return s;
  double ymin = 0, ymax = 0;
  for (double v : r.y) ymin = std::min(ymin, v), ymax = std::max(ymax, v);
  const double tmax = r.tau.back();
  Panel top_p{80, top + 40, fig_w - 110, 330, 0, tmax, ymin, ymax + 0.05 * (ymax - ymin) + 1e-9};
  std::vector<double> rb(n), rf(n);
  double rmax = 1e-12;
  for (std::size_t i = 0; i < n; ++i) {
    rb[i] = r.y[i] - r.base.simulated[i];
    rf[i] = r.y[i] - r.final_fit.simulated[i];
  }
  std::vector<double> bx, bb, fx, fb;
  svg::bin_means(r.tau, rb, r.bin_samples, bx, bb);
  svg::bin_means(r.tau, rf, r.bin_samples, fx, fb);
  for (double v : bb) rmax = std::max(rmax, std::abs(v));
  for (double v : rf) rmax = std::max(rmax, std::abs(v));
  rmax *= 1.1;
  Panel bot_p{80, top + 430, fig_w - 110, 200, 0, tmax, -rmax, rmax};

  // Top: measurement, base and final simulations.
  s += axes(top_p, "time after the cut (s)", fmt::format("reading ({})", u));
  const std::size_t stride = std::max<std::size_t>(1, n / 2500);
  s += svg::dots(top_p, r.tau, r.y, stride, 1.6, "#777");
  const char* base_style = "stroke=\"#d62728\" stroke-width=\"2\" stroke-dasharray=\"7,4\"";
  const char* final_style = "stroke=\"#1f77b4\" stroke-width=\"2\"";
  s += polyline(top_p, r.tau, r.base.simulated, base_style);
  s += polyline(top_p, r.tau, r.final_fit.simulated, final_style);
  s += legend(top_p.x + top_p.w - 380, top_p.y + 10,
              {{"measurement", "stroke=\"#777\" stroke-width=\"4\" stroke-dasharray=\"2,4\""},
               {fmt::format("base model: {}", r.base.label()), base_style},
               {fmt::format("final model: {}", r.final_fit.label()), final_style}});

  // Bottom: residuals before (binned) and after (every sample, then binned).
  for (const auto& step : r.steps)
    for (const auto& d : step.where) {
      if (&step != &r.steps.front()) break;
      s += fmt::format("<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"{:.1f}\" height=\"{:.1f}\" fill=\"#ffbf00\" "
                       "fill-opacity=\"0.18\"/>\n",
                       bot_p.px(d.tau_from_s), bot_p.y, std::max(1.0, bot_p.px(d.tau_to_s) - bot_p.px(d.tau_from_s)),
                       bot_p.h);
    }
  s += axes(bot_p, "time after the cut (s)", fmt::format("measurement - model ({})", u));
  s += svg::dots(bot_p, r.tau, rf, stride, 1.2, "#9ecae1");
  s += polyline(bot_p, bx, bb, "stroke=\"#d62728\" stroke-width=\"2\"");
  s += polyline(bot_p, fx, fb, "stroke=\"#1f77b4\" stroke-width=\"2\"");
  s += legend(bot_p.x + bot_p.w - 380, bot_p.y + 8,
              {{fmt::format("before: {} ({}-sample means)", r.base.label(), r.bin_samples),
                "stroke=\"#d62728\" stroke-width=\"2\""},
               {fmt::format("after: {} (means; dots: samples)", r.final_fit.label()),
                "stroke=\"#1f77b4\" stroke-width=\"2\""},
               {"where the base model disagrees", "stroke=\"#ffbf00\" stroke-opacity=\"0.5\" stroke-width=\"10\""}});
  return s;
}

}  // namespace

std::string explain_svg(std::span<const FileExplain> files) {
  std::size_t runs = 0;
  for (const auto& f : files) runs += f.runs.size();
  const double height = fig_h * static_cast<double>(std::max<std::size_t>(runs, 1));
  std::string s = fmt::format("<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{}\" height=\"{}\" viewBox=\"0 0 {} {}\" "
                              "font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" "
                              "fill=\"white\"/>\n",
                              fig_w, height, fig_w, height);
  double top = 0;
  for (const auto& f : files)
    for (std::size_t i = 0; i < f.runs.size(); ++i) {
      s += run_figure(f.file, i < f.run_bench.size() ? f.run_bench[i] : std::string_view{}, f.runs[i], top);
      top += fig_h;
    }
  s += "</svg>\n";
  return s;
}

}  // namespace spindown
