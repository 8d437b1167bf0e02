#include "spindown/explain_report.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <fmt/ranges.h>

#include "spindown/fit_report.hpp"
#include "spindown/lab_units.hpp"
#include "spindown/svg_plot.hpp"

namespace spindown {
namespace {

ExplainJson number(double x) { return std::isfinite(x) ? ExplainJson(x) : ExplainJson(nullptr); }

// As spindown fit --json gives a parameter: value, stderr, unit (ASCII), and "lab" with --lab-units.
ExplainJson params_json(const EffectFit& f, const ReportOptions& opt) {
  ExplainJson p = ExplainJson::object();
  for (const auto& q : f.params) {
    ExplainJson one{{"value", number(q.value)}, {"stderr", number(q.std_error)}, {"unit", q.unit}};
    if (opt.lab_units)
      if (auto lab = lab_unit_for(q.unit))
        one["lab"] = {{"value", number(q.value * lab->per_si)},
                      {"stderr", number(q.std_error * lab->per_si)},
                      {"unit", lab->ascii}};
    p[q.name] = std::move(one);
  }
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
  for (const auto& t : trials) {
    ExplainJson one{{"effect", t.effect},
                    {"rmse", number(t.fit.rmse)},
                    {"delta_bic", number(t.delta_bic)},
                    {"systematic_left", number(t.systematic_after)},
                    {"verdict", t.verdict}};
    if (!t.impossible.empty()) one["impossible"] = t.impossible;
    a.push_back(std::move(one));
  }
  return a;
}

std::string ratio_text(double before, double after) {
  if (!(after > 0) || !std::isfinite(before / after)) return "";
  const double r = before / after;
  return r >= 1.05 ? fmt::format("{:.3g}x smaller", r) : r > 0.95 ? "about the same" : fmt::format("{:.3g}x larger", 1 / r);
}

std::string params_text(const EffectFit& f, std::string_view indent, const ReportOptions& opt) {
  std::string out;
  for (const auto& p : f.params) out += fmt::format("{}{}\n", indent, parameter_text(p, opt.lab_units));
  return out;
}

std::string where_text(const std::vector<Disagreement>& where, const std::string& unit, std::string_view indent) {
  std::string out;
  for (const auto& d : where)
    out += fmt::format("{}{:.2f}-{:.2f} s after the cut (speed {:.0f}->{:.0f} rad/s): data {} the model by {:.3g} {} "
                       "on average (peak {:.3g} {}, {:.0f}x a bin's noise)\n",
                       indent, d.tau_from_s, d.tau_to_s, d.omega_from, d.omega_to,
                       d.mean_residual > 0 ? "above" : "below", std::abs(d.mean_residual), unit,
                       std::abs(d.peak_residual), unit, std::abs(d.z));
  return out;
}

// A bin's noise as derived from the reading noise σ: σ/√m, or how much wider the residual's own
// bin-to-bin scatter made it.
std::string bin_noise_text(const ExplainResult& r, double bin_noise) {
  const double white = r.bin_noise_white();
  const std::string& u = r.unit;
  if (!(white > 0) || bin_noise <= 1.05 * white)
    return fmt::format("a bin's noise {:.2g} {} = σ/√{}", bin_noise, u, r.bin_samples);
  return fmt::format("a bin's noise {:.2g} {}: σ/√{} = {:.2g} {}, widened {:.2g}x because the residual's bin means "
                     "scatter more than independent errors would",
                     bin_noise, u, r.bin_samples, white, u, bin_noise / white);
}

// The zero level, and what it says when it is not zero.
std::string zero_text(const ExplainResult& r) {
  const std::string& u = r.unit;
  if (r.zero_level != 0)
    return fmt::format("zero level {:.3g} {}{}: spindown fit subtracts it, explain keeps the reading's own zero and names "
                       "a reading that does not return to 0 as a sensor offset{}",
                       r.zero_level, u, r.standstill_seen ? " at standstill" : " (no standstill: the floor the coast was lost in)",
                       r.standstill_seen ? fmt::format(" (here between {:.3g} and {:.3g} {})", r.offset_lo, r.offset_hi, u)
                                         : std::string());
  return r.standstill_seen ? fmt::format("zero level 0 {} at standstill", u)
                           : std::string("no standstill in the window (the reading's zero not measured)");
}

}  // namespace

ExplainJson explain_run_json(const ExplainResult& r, std::string_view bench, const ReportOptions& opt) {
  ExplainJson j;
  j["run"] = r.run.number;
  if (!bench.empty()) j["bench"] = bench;
  j["base"] = r.base.names();
  ExplainJson steps = ExplainJson::array();
  for (const auto& s : r.steps) {
    ExplainJson step{{"added", s.added},
                     {"rmse_before", number(s.rmse_before)},
                     {"rmse_after", number(s.rmse_after)},
                     {"where", where_json(s.where)},
                     {"overall", s.overall},
                     {"why", s.why},
                     {"meaning", s.meaning},
                     {"signature", s.signature},
                     {"bin_noise", number(s.bin_noise)},
                     {"removed", s.removed},
                     {"indistinguishable_from", s.indistinguishable},
                     {"candidates", trials_json(s.trials)},
                     {"model", s.fit.fit_model()},
                     {"params", params_json(s.fit, opt)}};
    if (!s.undecided.empty()) step["undecided"] = s.undecided;
    steps.push_back(std::move(step));
  }
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
  j["zero_level"] = number(r.zero_level);
  j["standstill_seen"] = r.standstill_seen;
  j["sensor_offset_bounds"] = ExplainJson::array({number(r.offset_lo), number(r.offset_hi)});
  j["reading_noise"] = number(r.reading_noise);
  j["bin_samples"] = r.bin_samples;
  j["bin_noise_white"] = number(r.bin_noise_white());
  j["bin_noise"] = number(r.bin_noise);
  j["base_model"] = r.base.fit_model();
  j["final_model"] = r.final_fit.fit_model();
  j["base_params"] = params_json(r.base, opt);
  j["final_params"] = params_json(r.final_fit, opt);
  j["t_stop_pred_s"] = number(r.final_fit.t_stop_pred_s);
  j["remaining"] = where_json(r.remaining);
  j["rejected_last"] = trials_json(r.final_trials);
  j["conclusion"] = r.conclusion;
  j["inertia_kg_m2"] = number(r.bench.inertia_kg_m2);
  j["kb_v_s_per_rad"] = number(r.bench.kb_v_s_per_rad);
  if (opt.lab_units) j["inertia_lab"] = {{"value", number(inertia_to_g_cm2(r.bench.inertia_kg_m2))}, {"unit", "g*cm^2"}};
  return j;
}

ExplainJson explain_report_json(std::span<const FileExplain> files, const ReportOptions& opt) {
  ExplainJson out;
  ExplainJson arr = ExplainJson::array();
  for (const auto& f : files) {
    ExplainJson fj;
    fj["file"] = f.file;
    ExplainJson runs = ExplainJson::array();
    for (std::size_t i = 0; i < f.runs.size(); ++i)
      runs.push_back(explain_run_json(f.runs[i], i < f.run_bench.size() ? f.run_bench[i] : std::string_view{}, opt));
    fj["runs"] = runs;
    fj["samples"] = f.samples;
    fj["failures"] = f.failures;
    arr.push_back(fj);
  }
  out["files"] = arr;
  return out;
}

std::string format_explain(const ExplainResult& r, std::string_view bench, const ReportOptions& opt) {
  const std::string& u = r.unit;
  std::string out = fmt::format("run {}{}: cut at {:.3f} s, {} samples as spindown fit takes them (the run's window, "
                                "weighted by the run's noise)\n",
                                r.run.number, bench.empty() ? std::string() : fmt::format(" of bench {}", bench),
                                r.run.t_cut_s, r.tau.size());
  out += fmt::format("  {}; reading noise σ {:.2g} {}; residuals judged in {}-sample bins, a bin mean's noise σ/√{} = "
                     "{:.2g} {} where the readings' errors are independent\n",
                     zero_text(r), r.reading_noise, u, r.bin_samples, r.bin_samples, r.bin_noise_white(), u);
  if (opt.lab_units) out += fmt::format("  bench: J = {:.6g} g·cm²\n", inertia_to_g_cm2(r.bench.inertia_kg_m2));
  if (!r.ok) return out + fmt::format("  could not be explained: {}\n", r.message);
  const std::string fit_name = r.base.fit_model();
  out += fmt::format("  base model: {}{}   RMSE {:.4g} {}\n", r.base.title(),
                     fit_name.empty()       ? std::string()
                     : r.zero_level == 0 ? fmt::format(" - spindown fit's {} model", fit_name)
                                            : fmt::format(" - spindown fit's {} model but for its zero level", fit_name),
                     r.base.rmse, u);
  out += params_text(r.base, "    ", opt);
  int number = 0;
  for (const auto& s : r.steps) {
    ++number;
    if (s.added.empty()) {  // a term of the belief the data do not need, nothing added
      out += fmt::format("\n  step {}: {} not needed\n", number, fmt::join(s.removed, " and "));
      out += fmt::format("    why: {}\n", s.why);
      out += fmt::format("    model now: {}\n", s.fit.title());
      out += params_text(s.fit, "      ", opt);
      out += fmt::format("    gap: RMSE {:.4g} {} -> {:.4g} {}\n", s.rmse_before, u, s.rmse_after, u);
      continue;
    }
    out += fmt::format("\n  step {}: where the model and the data disagree ({})\n", number, bin_noise_text(r, s.bin_noise));
    out += where_text(s.where, u, "    ");
    if (!s.overall.empty()) out += fmt::format("    {}\n", s.overall);
    const Effect* e = find_effect(s.added);
    out += fmt::format("  missing effect: {}", s.added);
    if (e)
      out += fmt::format(" - {}\n    its term: {}\n    its signature: {}\n",
                         s.meaning.empty() ? std::string(e->meaning) : s.meaning, effect_term(*e, s.fit),
                         s.signature.empty() ? std::string(e->signature) : s.signature);
    else
      out += "\n";
    out += fmt::format("    why: {}\n", s.why);
    if (!s.undecided.empty()) out += fmt::format("    undecided: {}\n", s.undecided);
    for (const auto& t : s.trials)
      if (t.verdict != "added") out += fmt::format("    rejected {}: {}\n", t.effect, t.verdict);
    for (const auto& gone : s.removed)
      out += fmt::format("    removed {}: not needed once {} is in (the model does as well without it)\n", gone, s.added);
    out += fmt::format("    model now: {}\n", s.fit.title());
    out += params_text(s.fit, "      ", opt);
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
    out += fmt::format("  final model: {} (nothing added), RMSE {:.4g} {}\n", r.final_fit.title(), r.final_fit.rmse, u);
  else
    out += fmt::format("  final model: {}, RMSE {:.4g} {} (base {:.4g} {}: {})\n", r.final_fit.title(),
                       r.final_fit.rmse, u, r.base.rmse, u, ratio_text(r.base.rmse, r.final_fit.rmse));
  return out;
}

std::string format_file_explain(const FileExplain& file, const ReportOptions& opt) {
  std::string out = fmt::format("{}\n", file.file);
  for (std::size_t i = 0; i < file.runs.size(); ++i)
    out += format_explain(file.runs[i], i < file.run_bench.size() ? file.run_bench[i] : std::string_view{}, opt) + "\n";
  return out;
}

namespace {

using svg::Panel;
using svg::axes;
using svg::legend;
using svg::polyline;

constexpr double fig_w = 960, fig_h = 700;

// The base model and the model after each step: the gap shrinking step by step.
struct Stage {
  std::string label;
  const EffectFit* fit;
  std::string style;
  std::string change;  // what the step did and what became of it ("+ stribeck [removed at step 3]"); "" for the base
};

std::vector<Stage> stages_of(const ExplainResult& r) {
  static constexpr const char* colors[] = {"#ff7f0e", "#2ca02c", "#9467bd", "#8c564b", "#e377c2", "#17becf"};
  const std::string& u = r.unit;
  std::vector<Stage> out;
  out.push_back({fmt::format("base: {} - RMSE {:.3g} {}", r.base.title(), r.base.rmse, u), &r.base,
                 "stroke=\"#d62728\" stroke-width=\"2\" stroke-dasharray=\"7,4\"", ""});
  for (std::size_t i = 0; i < r.steps.size(); ++i) {
    const ExplainStep& s = r.steps[i];
    const bool last = i + 1 == r.steps.size();
    // What the step did: its effect added, the terms it removed; and, for an effect a later step
    // removed again, that it was (the legend keeps every step, the removed ones marked).
    std::string did = s.added.empty() ? std::string() : "+ " + s.added;
    for (const auto& gone : s.removed) did += (did.empty() ? "" : ", ") + fmt::format("- {} (removed: not needed)", gone);
    std::string later;
    for (std::size_t k = i + 1; k < r.steps.size() && !s.added.empty(); ++k)
      if (std::find(r.steps[k].removed.begin(), r.steps[k].removed.end(), s.added) != r.steps[k].removed.end())
        later = fmt::format(" [{} removed at step {}]", s.added, k + 1);
    out.push_back({fmt::format("step {}: {} -> {} - RMSE {:.3g} {}{}{}", i + 1, did, s.fit.title(), s.rmse_after, u,
                               last ? " (final)" : "", later),
                   &s.fit,
                   last ? std::string("stroke=\"#1f77b4\" stroke-width=\"2\"")
                        : fmt::format("stroke=\"{}\" stroke-width=\"1.6\" stroke-dasharray=\"4,3\"", colors[i % 6]),
                   did + later});
  }
  return out;
}

std::string run_figure(const std::string& file, std::string_view bench, const ExplainResult& r, double top) {
  const std::string& u = r.unit;
  const std::size_t n = r.tau.size();
  std::string s;
  const std::string name = file.substr(file.find_last_of('/') == std::string::npos ? 0 : file.find_last_of('/') + 1);
  const std::string title = fmt::format("{}{} - run {}: base {} (RMSE {:.3g} {}) -> {} (RMSE {:.3g} {})", name,
                                        bench.empty() ? std::string() : fmt::format(" bench {}", bench), r.run.number,
                                        r.base.title(), r.base.rmse, u, r.final_fit.title(), r.final_fit.rmse, u);
  s += fmt::format("<text x=\"{}\" y=\"{:.1f}\" text-anchor=\"middle\" font-size=\"15\" font-weight=\"bold\">{}</text>\n",
                   fig_w / 2, top + 22, svg::escape(title));
  if (n == 0 || !r.ok) return s;
  const std::vector<double>& reading = r.y;
  double ymin = 0, ymax = 0;
  for (double v : reading) ymin = std::min(ymin, v), ymax = std::max(ymax, v);
  const double tmax = r.tau.back();
  Panel top_p{80, top + 40, fig_w - 110, 330, 0, tmax, ymin, ymax + 0.05 * (ymax - ymin) + 1e-9};

  const std::vector<Stage> stages = stages_of(r);
  std::vector<std::vector<double>> bin_x(stages.size()), bin_y(stages.size());
  std::vector<double> rf(n);
  double rmax = 1e-12;
  for (std::size_t c = 0; c < stages.size(); ++c) {
    std::vector<double> res(n);
    for (std::size_t i = 0; i < n; ++i) res[i] = r.y[i] - stages[c].fit->simulated[i];
    svg::bin_means(r.tau, res, r.bin_samples, bin_x[c], bin_y[c]);
    for (double v : bin_y[c]) rmax = std::max(rmax, std::abs(v));
    if (c + 1 == stages.size()) rf = std::move(res);
  }
  for (double v : rf) rmax = std::max(rmax, std::abs(v));
  rmax *= 1.1;
  Panel bot_p{80, top + 430, fig_w - 110, 200, 0, tmax, -rmax, rmax};

  // Top: the measurement and every stage's simulation, each with its RMSE.
  s += axes(top_p, "time after the cut (s)", fmt::format("reading ({})", u));
  const std::size_t stride = std::max<std::size_t>(1, n / 2500);
  s += svg::dots(top_p, r.tau, reading, stride, 1.6, "#777");
  std::vector<std::pair<std::string, std::string>> items{
      {"measurement", "stroke=\"#777\" stroke-width=\"4\" stroke-dasharray=\"2,4\""}};
  for (std::size_t c = 0; c < stages.size(); ++c) {
    s += polyline(top_p, r.tau, stages[c].fit->simulated,
                  fmt::format("class=\"model\" data-step=\"{}\" data-rmse=\"{:.4g}\" {}", c, stages[c].fit->rmse,
                              stages[c].style));
    items.emplace_back(stages[c].label, stages[c].style);
  }
  s += legend(top_p.x + top_p.w - 550, top_p.y + 10, items, 540);

  // Bottom: every stage's residual (bin means), the final one's samples as dots.
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
  std::vector<std::pair<std::string, std::string>> res_items;
  for (std::size_t c = 0; c < stages.size(); ++c) {
    s += polyline(bot_p, bin_x[c], bin_y[c],
                  fmt::format("class=\"residual\" data-step=\"{}\" {}", c, stages[c].style));
    res_items.emplace_back(fmt::format("{}: {} ({}-sample means{})",
                                       c == 0 ? "base" : fmt::format("step {} ({})", c, stages[c].change),
                                       stages[c].fit->title(), r.bin_samples,
                                       c + 1 == stages.size() ? "; dots: samples" : ""),
                           stages[c].style);
  }
  if (!r.steps.empty())
    res_items.emplace_back("where the base model disagrees", "stroke=\"#ffbf00\" stroke-opacity=\"0.5\" stroke-width=\"10\"");
  s += legend(bot_p.x + bot_p.w - 550, bot_p.y + 8, res_items, 540);
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
