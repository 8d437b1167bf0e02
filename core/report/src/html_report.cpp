#include "spindown/html_report.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fmt/format.h>
#include <utility>
#include <vector>

#include "spindown/effects.hpp"
#include "spindown/explain_report.hpp"
#include "spindown/fit_report.hpp"
#include "spindown/lab_units.hpp"
#include "spindown/quantity.hpp"
#include "spindown/recorded_at.hpp"
#include "spindown/svg_plot.hpp"
#include "spindown/utf8_text.hpp"

namespace spindown {

namespace {

using svg::Panel;

// Inline CSS only: the page must stand alone (no fonts, scripts or images from elsewhere).
constexpr std::string_view page_css = R"css(
body{font-family:system-ui,-apple-system,"Segoe UI",Roboto,"DejaVu Sans",sans-serif;color:#222;margin:0;background:#f4f5f7}
main{max-width:1040px;margin:0 auto;padding:16px 24px 48px;background:#fff}
h1{margin:8px 0 4px;font-size:26px}
h2{margin:32px 0 8px;padding-bottom:4px;border-bottom:2px solid #1f77b4;font-size:21px}
h3{margin:24px 0 6px;font-size:17px}
h4{margin:14px 0 4px;font-size:14px;color:#444}
p.meta{color:#555;margin:2px 0 8px;font-size:13px}
nav{font-size:13px;margin:8px 0}
nav a{margin-right:12px}
table{border-collapse:collapse;margin:6px 0 10px;font-size:13px}
th,td{border:1px solid #ccc;padding:3px 7px;text-align:left;vertical-align:top}
th{background:#eef2f7}
td.num{text-align:right;font-variant-numeric:tabular-nums;white-space:nowrap}
tr.best td{background:#f3f8ee}
tr.model-first td{border-top:2px solid #999}
.badge{display:inline-block;padding:1px 8px;border-radius:10px;font-weight:bold;font-size:12px;color:#fff}
.badge.not_judged{background:#757575}.badge.ok{background:#2e7d32}.badge.check{background:#e0a100;color:#222}.badge.service{background:#c62828}
.badge.none{background:#888}
.verdict{border-left:6px solid #888;background:#fafafa;padding:6px 10px;margin:8px 0}
.verdict.not_judged{border-color:#757575}.verdict.ok{border-color:#2e7d32}.verdict.check{border-color:#e0a100}.verdict.service{border-color:#c62828}
.noref{color:#666;font-style:italic}
.drift{color:#c62828;font-weight:bold}
.steady{color:#2e7d32}
article.run{border-top:1px solid #ddd;margin-top:18px}
figure{margin:6px 0}
svg{max-width:100%;height:auto}
pre{background:#f6f8fa;padding:8px;overflow-x:auto;font-size:12px;white-space:pre-wrap}
details{margin:6px 0}
summary{cursor:pointer;color:#1f4e79}
ol.story li{margin:4px 0}
.fail{color:#c62828}
ul.diag{font-size:12px;font-family:monospace}
.print-only{display:none}
table.runs td{white-space:nowrap}
table.runs td.why{white-space:normal;font-size:12px}
/* On paper: the summary, the trends, every run in one line of the runs table and the files with
   problems; each run's figure, coefficients and story stay on the screen. A semester prints on a
   few pages instead of one page per run. */
@media print{
@page{size:A4;margin:12mm}
body{background:#fff;font-size:9pt}
main{max-width:none;padding:0}
h1{font-size:16pt}h2{font-size:13pt;margin:14px 0 6px;break-after:avoid}h4{break-after:avoid}
nav,details,section.bench,.screen-only{display:none!important}
.print-only{display:block}
table{font-size:8pt;margin:4px 0}th,td{padding:1px 4px}tr{break-inside:avoid}
table.runs td.why{font-size:7pt}
#files tr.clean{display:none}
figure{margin:2px 0;break-inside:avoid}
svg.trend-plot{width:100%;height:auto;max-height:55mm}
svg.run-plot{display:none}
a{color:inherit;text-decoration:none}
.badge{color:#000!important;background:none!important;border:1px solid #000;padding:0 4px}
}
)css";

std::string esc(std::string_view s) { return html_escape(s); }

// An id usable in href="#…" built only from safe characters.
std::string anchor(std::string_view prefix, std::string_view text) {
  std::string out(prefix);
  for (char c : text) out += std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' ? c : '_';
  return out;
}

std::string level_badge(HealthLevel level) {
  const std::string_view name = health_level_name(level);
  std::string upper(name);
  for (char& c : upper) c = c == '_' ? ' ' : static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return fmt::format("<span class=\"badge {}\">{}</span>", name, upper);
}

std::string value_unit(double value, double se, std::string_view ascii_unit) {
  // Without an uncertainty (a limit, a measured time) four digits say enough.
  std::string v = se > 0 && std::isfinite(se) ? format_value_error(value, se) : fmt::format("{:.4g}", value);
  if (!ascii_unit.empty()) v += fmt::format(" {}", pretty_unit(ascii_unit));
  return v;
}

std::string number_text(double x, const char* fmt_spec = "{:.4g}") {
  return std::isfinite(x) ? fmt::format(fmt::runtime(fmt_spec), x) : std::string(std::isinf(x) ? "never" : "–");
}

// --- figures ---------------------------------------------------------------------------

struct ModelStyle {
  ModelKind kind;
  const char* color;
  const char* dash;
};
constexpr ModelStyle model_styles[] = {
    {ModelKind::viscous, "#d62728", "stroke-dasharray=\"8,4\""},
    {ModelKind::coulomb, "#2ca02c", "stroke-dasharray=\"3,3\""},
    {ModelKind::combined, "#1f77b4", ""},
};

const ModelStyle& style_of(ModelKind k) {
  for (const auto& s : model_styles)
    if (s.kind == k) return s;
  return model_styles[2];
}

std::string line_style(const ModelFit& m, bool best) {
  const ModelStyle& s = style_of(m.kind);
  return fmt::format("stroke=\"{}\" stroke-width=\"{}\" {}", s.color, best ? 3 : 2, s.dash);
}

// The model's reading at each τ: zero level + (reading per rad/s)·ω(τ).
std::vector<double> model_curve(const ReportRun& r, const ModelFit& m) {
  const double k = value_per_rad_per_s(r.fit.quantity, r.fit.bench.kb_v_s_per_rad);
  std::vector<double> out(r.tau.size());
  for (std::size_t i = 0; i < r.tau.size(); ++i) out[i] = r.fit.run.zero_level + k * m.omega_at(r.tau[i]);
  return out;
}

std::size_t samples_per_half_second(const ReportRun& r) {
  if (r.explained && r.explain.bin_samples > 0) return r.explain.bin_samples;
  double period = r.fit.run.period_s;
  if (!(period > 0) && r.tau.size() > 1) period = (r.tau.back() - r.tau.front()) / static_cast<double>(r.tau.size() - 1);
  return period > 0 ? std::max<std::size_t>(1, static_cast<std::size_t>(std::lround(0.5 / period))) : 1;
}

constexpr double run_w = 960, run_h = 640;

}  // namespace


std::string html_escape(std::string_view in) {
  std::string out;
  out.reserve(in.size());
  for (std::size_t i = 0; i < in.size();) {
    const char c = in[i];
    const std::size_t n = text::utf8_sequence_length(in, i);
    if (n == 0) {  // not UTF-8 (a Latin-1 file name): the replacement character, never broken text
      out += "\xEF\xBF\xBD";
      ++i;
      continue;
    }
    if (c == '\'')
      out += "&#39;";
    else if (c == '&' || c == '<' || c == '>' || c == '"')
      out += svg::escape(std::string_view(&c, 1));
    else if (n == 1 && static_cast<unsigned char>(c) < 0x20 && c != '\n' && c != '\t' && c != '\r')
      out += "\xEF\xBF\xBD";  // control characters are not allowed in HTML text
    else
      out.append(in.substr(i, n));
    i += n;
  }
  return out;
}

std::string run_figure_svg(const ReportRun& r) {
  const std::string unit(quantity_unit(r.fit.quantity));
  const std::string title = fmt::format("bench {} - run {} ({})", r.bench, r.fit.run.number, r.source);
  std::string s = fmt::format(
      "<svg class=\"run-plot\" width=\"{0}\" height=\"{1}\" viewBox=\"0 0 {0} {1}\" "
      "font-family=\"sans-serif\" font-size=\"12\" role=\"img\" aria-label=\"{2}\">\n<title>{2}</title>\n"
      "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n",
      run_w, run_h, html_escape(title));
  const std::size_t n = std::min(r.tau.size(), r.y.size());
  if (n < 2) {
    s += "<text x=\"480\" y=\"60\" text-anchor=\"middle\">no samples to plot</text>\n</svg>\n";
    return s;
  }
  std::vector<std::pair<const ModelFit*, std::vector<double>>> curves;
  for (const auto& m : r.fit.models)
    if (m.converged || !m.params.empty()) curves.emplace_back(&m, model_curve(r, m));

  // The top panel shows the recording around the run (its context) with the fitted window shaded,
  // so that what came before the cut is seen; the residuals are the fitted window's.
  const std::size_t nc = std::min(r.context_tau.size(), r.context_y.size());
  double ymin = 0, ymax = 0;
  for (std::size_t i = 0; i < n; ++i)
    if (std::isfinite(r.y[i])) ymin = std::min(ymin, r.y[i]), ymax = std::max(ymax, r.y[i]);
  for (std::size_t i = 0; i < nc; ++i)
    if (std::isfinite(r.context_y[i])) ymin = std::min(ymin, r.context_y[i]), ymax = std::max(ymax, r.context_y[i]);
  const double tmin = std::min(0.0, r.tau.front()), tmax = std::max(r.tau[n - 1], tmin + 1e-3);
  const double cmin = nc ? std::min(tmin, r.context_tau.front()) : tmin, cmax = nc ? std::max(tmax, r.context_tau[nc - 1]) : tmax;
  Panel top{80, 46, run_w - 110, 300, cmin, cmax, ymin, ymax + 0.05 * (ymax - ymin) + 1e-9};

  // Residuals: bin means for every model, every sample for the best one.
  const std::size_t m = samples_per_half_second(r);
  std::vector<std::vector<double>> bin_x(curves.size()), bin_y(curves.size());
  std::vector<double> best_res;
  double rmax = 1e-12;
  for (std::size_t c = 0; c < curves.size(); ++c) {
    std::vector<double> res(n);
    for (std::size_t i = 0; i < n; ++i) res[i] = r.y[i] - curves[c].second[i];
    svg::bin_means(std::span<const double>(r.tau.data(), n), res, m, bin_x[c], bin_y[c]);
    for (double v : bin_y[c])
      if (std::isfinite(v)) rmax = std::max(rmax, std::abs(v));
    if (model_name(curves[c].first->kind) == r.fit.best) best_res = std::move(res);
  }
  for (double v : best_res)
    if (std::isfinite(v)) rmax = std::max(rmax, std::abs(v));
  rmax *= 1.1;
  Panel bot{80, 416, run_w - 110, 170, tmin, tmax, -rmax, rmax};

  s += fmt::format("<text x=\"{}\" y=\"24\" text-anchor=\"middle\" font-size=\"15\" font-weight=\"bold\">{}</text>\n",
                   run_w / 2, html_escape(title));
  // The fitted window, shaded (behind everything), and the cut.
  s += fmt::format("<rect class=\"fitted-window\" x=\"{:.1f}\" y=\"{:.1f}\" width=\"{:.1f}\" height=\"{:.1f}\" "
                   "fill=\"#1f77b4\" fill-opacity=\"0.10\" data-t-from=\"{:.6g}\" data-t-to=\"{:.6g}\"/>\n",
                   top.px(r.tau.front()), top.y, std::max(1.0, top.px(r.tau[n - 1]) - top.px(r.tau.front())), top.h,
                   r.tau.front(), r.tau[n - 1]);
  s += svg::axes(top, nc ? "time after the cut (s): the recording around the run, the fitted window shaded"
                         : "time after the cut (s)",
                 fmt::format("reading ({})", unit));
  s += fmt::format("<line class=\"cut\" x1=\"{0:.1f}\" y1=\"{1:.1f}\" x2=\"{0:.1f}\" y2=\"{2:.1f}\" stroke=\"#444\" "
                   "stroke-width=\"1\" stroke-dasharray=\"5,3\"/>\n<text x=\"{3:.1f}\" y=\"{4:.1f}\" font-size=\"11\">cut</text>\n",
                   top.px(0), top.y, top.y + top.h, top.px(0) + 3, top.y + 12);
  const std::size_t stride = std::max<std::size_t>(1, n / 2500);
  std::vector<std::pair<std::string, std::string>> items;
  if (nc) {
    s += svg::dots(top, r.context_tau, r.context_y, std::max<std::size_t>(1, nc / 4000), 1.2, "#bbb");
    items.push_back({"recording outside the fitted window", "stroke=\"#bbb\" stroke-width=\"4\" stroke-dasharray=\"2,4\""});
  }
  s += svg::dots(top, r.tau, r.y, stride, 1.6, "#777");
  items.push_back({"measurement (fitted)", "stroke=\"#777\" stroke-width=\"4\" stroke-dasharray=\"2,4\""});
  items.push_back({fmt::format("fitted window: {:.2f} s to {:.2f} s after the cut", r.tau.front(), r.tau[n - 1]),
                   "stroke=\"#1f77b4\" stroke-opacity=\"0.2\" stroke-width=\"10\""});
  for (const auto& [model, curve] : curves) {
    const bool best = model_name(model->kind) == r.fit.best;
    s += svg::polyline(top, r.tau, curve, line_style(*model, best));
    items.emplace_back(fmt::format("{}{}: RMSE {:.3g} {}", model_name(model->kind), best ? " (best)" : "", model->rmse,
                                   unit),
                       line_style(*model, best));
  }
  s += svg::legend(top.x + top.w - 300, top.y + 10, items, 290);

  s += svg::axes(bot, "time after the cut (s): the fitted window", fmt::format("measurement - model ({})", unit));
  if (!best_res.empty()) s += svg::dots(bot, r.tau, best_res, stride, 1.2, "#9ecae1");
  std::vector<std::pair<std::string, std::string>> res_items;
  for (std::size_t c = 0; c < curves.size(); ++c) {
    const bool best = model_name(curves[c].first->kind) == r.fit.best;
    s += svg::polyline(bot, bin_x[c], bin_y[c], line_style(*curves[c].first, best));
    res_items.emplace_back(fmt::format("{} ({}-sample means{})", model_name(curves[c].first->kind), m,
                                       best ? "; dots: samples" : ""),
                           line_style(*curves[c].first, best));
  }
  const double zero = bot.py(0);
  s += fmt::format("<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"#444\" stroke-width=\"0.8\"/>\n",
                   bot.x, zero, bot.x + bot.w, zero);
  s += svg::legend(bot.x + bot.w - 300, bot.y + 8, res_items, 290);
  s += "</svg>\n";
  return s;
}

std::string trend_figure_svg(const BenchSummary& b) {
  constexpr double w = 960, h = 250;
  std::string s = fmt::format(
      "<svg class=\"trend-plot\" width=\"{0}\" height=\"{1}\" viewBox=\"0 0 {0} {1}\" "
      "font-family=\"sans-serif\" font-size=\"12\" role=\"img\" aria-label=\"friction over the runs of bench {2}\">\n"
      "<title>friction over the runs of bench {2}</title>\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n",
      w, h, html_escape(b.bench));
  const CoefficientTrend* trends[] = {&b.viscous, &b.coulomb};
  for (int k = 0; k < 2; ++k) {
    const CoefficientTrend& t = *trends[k];
    const auto lab = lab_unit_for(t.unit);
    const double scale = lab ? lab->per_si : 1.0;
    const std::string unit(lab ? lab->pretty : pretty_unit(t.unit));
    const std::size_t n = std::min({t.x.size(), t.value.size(), t.std_error.size()});
    const double left = 90 + k * (w / 2);
    if (n == 0) {
      s += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\">{}: no combined fit</text>\n", left, h / 2,
                       svg::escape(t.name));
      continue;
    }
    double x0 = t.x[0], x1 = t.x[0], y0 = 1e300, y1 = -1e300;
    for (std::size_t i = 0; i < n; ++i) {
      x0 = std::min(x0, t.x[i]), x1 = std::max(x1, t.x[i]);
      const double se = std::isfinite(t.std_error[i]) ? t.std_error[i] : 0;
      y0 = std::min(y0, (t.value[i] - se) * scale), y1 = std::max(y1, (t.value[i] + se) * scale);
    }
    const double pad_x = x1 > x0 ? 0.05 * (x1 - x0) : 1, pad_y = y1 > y0 ? 0.1 * (y1 - y0) : std::abs(y0) * 0.1 + 1e-12;
    Panel p{left, 30, w / 2 - 120, h - 90, x0 - pad_x, x1 + pad_x, y0 - pad_y, y1 + pad_y};
    s += fmt::format("<text x=\"{:.1f}\" y=\"18\" font-weight=\"bold\">{} ({})</text>\n", p.x,
                     t.name == "c3" ? "viscous c3" : "dry friction c4", svg::escape(unit));
    s += svg::axes(p, t.x_unit == "day" ? "days since the first run" : "run (time order)", unit);
    if (t.enough) {
      const double ya = (t.intercept + t.slope * p.x0) * scale, yb = (t.intercept + t.slope * p.x1) * scale;
      const double xs[] = {p.x0, p.x1}, ys[] = {ya, yb};
      s += svg::polyline(p, xs, ys,
                         t.drifting ? "stroke=\"#c62828\" stroke-width=\"2\" stroke-dasharray=\"6,3\""
                                    : "stroke=\"#888\" stroke-width=\"1.5\" stroke-dasharray=\"6,3\"");
    }
    for (std::size_t i = 0; i < n; ++i) {
      const double se = std::isfinite(t.std_error[i]) ? t.std_error[i] : 0;
      const double cx = p.px(t.x[i]);
      s += fmt::format("<line x1=\"{0:.1f}\" y1=\"{1:.1f}\" x2=\"{0:.1f}\" y2=\"{2:.1f}\" stroke=\"#1f77b4\"/>\n", cx,
                       p.py(std::clamp((t.value[i] - se) * scale, p.y0, p.y1)),
                       p.py(std::clamp((t.value[i] + se) * scale, p.y0, p.y1)));
      s += fmt::format("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"3.5\" fill=\"#1f77b4\"/>\n", cx,
                       p.py(t.value[i] * scale));
    }
  }
  s += "</svg>\n";
  return s;
}

namespace {

// --- page sections -----------------------------------------------------------------------

std::string trend_cell(const CoefficientTrend& t) {
  const auto lab = lab_unit_for(t.unit);
  std::string out;
  if (!t.value.empty())
    out += fmt::format("mean {}", lab ? fmt::format("{} {}", format_value_error(t.mean * lab->per_si, t.mean_stderr * lab->per_si), lab->pretty)
                                      : value_unit(t.mean, t.mean_stderr, t.unit));
  if (t.enough)
    out += fmt::format("<br>trend {} per {}",
                       lab ? fmt::format("{} {}", format_value_error(t.slope * lab->per_si, t.slope_stderr * lab->per_si),
                                         lab->pretty)
                           : value_unit(t.slope, t.slope_stderr, t.unit),
                       esc(t.x_unit));
  out += fmt::format("<br><span class=\"{}\">{}</span>", t.drifting || t.stepped ? "drift" : t.enough ? "steady" : "noref",
                     esc(t.words));
  return out;
}

// Every run in one line: what a printed page keeps of each (the figures and stories stay on screen).
std::string runs_table(const SessionReport& report) {
  std::string s = fmt::format(
      "<h3>Every run</h3>\n<p class=\"print-only meta\">On paper: one line per run; each run's figure, "
      "coefficients and explain story are in this page on screen.</p>\n<table class=\"runs\">\n<tr><th>bench</th>"
      "<th>run</th><th>recorded</th><th>file</th><th>best model</th><th>viscous c3</th><th>dry friction c4</th>"
      "<th>health</th><th>why</th></tr>\n");
  for (const auto& b : report.benches)
    for (std::size_t i : b.runs) {
      const ReportRun& r = report.runs[i];
      const ReportFile* file = r.file_index < report.files.size() ? &report.files[r.file_index] : nullptr;
      std::string who = file ? esc(std::filesystem::path(file->file).filename().string()) : esc(r.source);
      if (file && !file->student.empty()) who += " (" + esc(file->student) + ")";
      const auto f = combined_friction(r.fit);
      s += fmt::format("<tr><td>{}</td><td class=\"num\"><a href=\"#{}\">{}</a></td><td>{}</td><td>{}</td><td>{}</td>"
                       "<td class=\"num\">{}</td><td class=\"num\">{}</td><td>{}</td><td class=\"why\">{}</td></tr>\n",
                       esc(r.bench), anchor("run-", fmt::format("{}-{}", r.bench, r.order)), r.order,
                       r.cut_unix_s ? esc(recorded_at_text({*r.cut_unix_s, r.cut_local})) : "–", who,
                       esc(r.fit.best.empty() ? "none converged" : r.fit.best) +
                           (r.fit.doubts.empty() ? "" : " <span class=\"fail\">(doubtful)</span>"),
                       f ? esc(value_unit(f->c_viscous, f->c_viscous_stderr, "N*m*s/rad")) : "–",
                       f ? esc(value_unit(f->c_coulomb, f->c_coulomb_stderr, "N*m")) : "–", level_badge(r.health.level),
                       esc(r.health.reason));
    }
  return s + "</table>\n";
}

std::string summary_section(const SessionReport& report) {
  std::string s = "<section id=\"summary\">\n<h2>Summary across benches and runs</h2>\n";
  std::size_t drifting = 0;
  for (const auto& b : report.benches) drifting += b.viscous.drifting || b.coulomb.drifting;
  s += fmt::format("<p>{} run{} on {} bench{}; friction drifts on {} bench{}. Friction c3 (viscous) and c4 "
                   "(dry, Coulomb) come from the combined model; a trend is a weighted straight line through the runs in "
                   "time order, its error widened by the run-to-run scatter; it is called a drift when it is more "
                   "than 3 standard errors from flat and changes the coefficient by 10 % or more, and a step when "
                   "the runs before and after one session agree on two levels far better than with any line.</p>\n",
                   report.runs.size(), report.runs.size() == 1 ? "" : "s", report.benches.size(),
                   report.benches.size() == 1 ? "" : "es", drifting, drifting == 1 ? "" : "es");
  s += "<table class=\"summary\">\n<tr><th>bench</th><th>runs</th><th>health (worst run)</th><th>reference</th>"
       "<th>viscous c3</th><th>dry friction c4</th></tr>\n";
  for (const auto& b : report.benches) {
    s += fmt::format("<tr><td><a href=\"#{}\">{}</a></td><td class=\"num\">{}</td><td>{}</td><td>{}</td><td>{}</td>"
                     "<td>{}</td></tr>\n",
                     anchor("bench-", b.bench), esc(b.bench), b.runs.size(), level_badge(b.worst),
                     b.has_reference ? esc(b.reference_file) : "<span class=\"noref\">no reference configured</span>",
                     trend_cell(b.viscous), trend_cell(b.coulomb));
  }
  s += "</table>\n";
  s += runs_table(report);
  for (const auto& b : report.benches)
    if (b.runs.size() >= 2) {
      s += fmt::format("<h4>Bench {}: friction over its runs</h4>\n<figure>\n{}</figure>\n", esc(b.bench),
                       trend_figure_svg(b));
    }
  for (const auto& note : report.notes) s += fmt::format("<p class=\"noref\">{}</p>\n", esc(note));
  s += "</section>\n";
  return s;
}

std::string files_section(const SessionReport& report) {
  // A class's files (a roster or --bench-pattern named their students): whose each file is.
  const bool students =
      std::any_of(report.files.begin(), report.files.end(), [](const ReportFile& f) { return !f.student.empty(); });
  std::string s = fmt::format("<section id=\"files\">\n<h2>Files</h2>\n<table>\n<tr><th>file</th>{}<th>format</th>"
                              "<th>benches</th><th>samples</th><th>recorded</th><th>problems</th></tr>\n",
                              students ? "<th>student</th>" : "");
  for (const auto& f : report.files) {
    std::string benches;
    for (const auto& b : f.benches) benches += (benches.empty() ? "" : ", ") + esc(b);
    std::size_t warnings = 0;
    for (const auto& d : f.diagnostics) warnings += d.severity != Diagnostic::Severity::note;
    std::string problems = fmt::format("{} warning{}", warnings, warnings == 1 ? "" : "s");
    for (const auto& why : f.failures) problems += fmt::format("<br><span class=\"fail\">not used: {}</span>", esc(why));
    s += fmt::format("<tr{}><td>{}</td>{}<td>{}</td><td>{}</td><td class=\"num\">{}</td><td>{}</td><td>{}</td></tr>\n",
                     warnings == 0 && f.failures.empty() ? " class=\"clean\"" : "",
                     esc(f.file), students ? fmt::format("<td>{}</td>", esc(f.student)) : "",
                     esc(f.format), benches, f.samples,
                     f.start_unix_s ? recorded_at_text({*f.start_unix_s, f.start_local}) : "–", problems);
  }
  s += "</table>\n";
  for (const auto& f : report.files) {
    if (f.diagnostics.empty()) continue;
    s += fmt::format("<details><summary>{}: {} message{}{}</summary>\n<ul class=\"diag\">\n", esc(f.file),
                     f.diagnostics.size() + f.diagnostics_dropped,
                     f.diagnostics.size() + f.diagnostics_dropped == 1 ? "" : "s",
                     f.diagnostics_dropped ? fmt::format(" ({} not listed)", f.diagnostics_dropped) : "");
    for (const auto& d : f.diagnostics) s += fmt::format("<li>{}</li>\n", esc(d.to_string()));
    s += "</ul>\n</details>\n";
  }
  s += "</section>\n";
  return s;
}

std::string verdict_block(const ReportRun& r) {
  const HealthVerdict& v = r.health;
  std::string s = fmt::format("<div class=\"verdict {}\">\n<p><strong>Health:</strong> {} {}</p>\n",
                              health_level_name(v.level), level_badge(v.level), esc(v.reason));
  if (!v.has_reference)
    s += "<p class=\"noref\">no reference configured (give this bench's TOML file with --bench-config): only the "
         "lab's time rules were checked.</p>\n";
  else
    s += fmt::format("<p class=\"meta\">reference: {}</p>\n", esc(r.health_config));
  if (!v.findings.empty()) {
    s += "<table class=\"findings\">\n<tr><th>what</th><th>level</th><th>this run</th><th>reference</th><th>ratio</th>"
         "<th>in words</th></tr>\n";
    for (const auto& f : v.findings) {
      const std::string ref = f.reference_name.empty() && f.reference == 0
                                  ? "–"
                                  : fmt::format("{}{}", value_unit(f.reference, f.reference_std_error, f.unit),
                                                f.reference_name.empty() ? "" : " (" + f.reference_name + ")");
      s += fmt::format("<tr><td>{}</td><td>{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td><td class=\"num\">{}"
                       "</td><td>{}</td></tr>\n",
                       esc(f.what), level_badge(f.level),
                       std::isfinite(f.value) ? esc(value_unit(f.value, f.std_error, f.unit)) : "never", esc(ref),
                       f.ratio != 0 ? esc(format_value_error(f.ratio, f.ratio_std_error)) : "–", esc(f.reason));
    }
    s += "</table>\n";
  }
  s += "</div>\n";
  return s;
}

std::string coefficient_table(const RunFit& fit) {
  const std::string unit(quantity_unit(fit.quantity));
  // A doubt stands before the numbers it doubts.
  std::string s;
  for (const auto& d : fit.doubts) s += fmt::format("<p class=\"fail\">doubtful: {}</p>\n", esc(d));
  s += "<table class=\"coef\">\n<tr><th>model</th><th>parameter</th><th>value ± standard error (SI)</th>"
                  "<th>lab units</th><th>RMSE</th><th>R²</th><th>BIC</th><th>stop predicted</th></tr>\n";
  for (const auto& m : fit.models) {
    const bool best = model_name(m.kind) == fit.best;
    const std::size_t rows = std::max<std::size_t>(m.params.size(), 1);
    const std::string model_cell =
        fmt::format("<td rowspan=\"{}\">{}{}{}</td>", rows, model_name(m.kind), best ? " <strong>★ best</strong>" : "",
                    m.converged ? "" : fmt::format("<br><span class=\"fail\">not converged: {}</span>", esc(m.message)));
    const std::string stats = fmt::format(
        "<td rowspan=\"{0}\" class=\"num\">{1} {2}</td><td rowspan=\"{0}\" class=\"num\">{3}</td>"
        "<td rowspan=\"{0}\" class=\"num\">{4}</td><td rowspan=\"{0}\" class=\"num\">{5}</td>",
        rows, number_text(m.rmse), esc(unit), number_text(m.r2, "{:.5f}"), number_text(m.bic, "{:.1f}"),
        std::isfinite(m.t_stop_pred_s) ? fmt::format("{:.2f} s after the cut", m.t_stop_pred_s) : "never");
    if (m.params.empty()) {
      s += fmt::format("<tr class=\"model-first{}\">{}<td>–</td><td>–</td><td>–</td>{}</tr>\n", best ? " best" : "",
                       model_cell, stats);
      continue;
    }
    for (std::size_t i = 0; i < m.params.size(); ++i) {
      const Parameter& p = m.params[i];
      const auto lab = lab_unit_for(p.unit);
      const std::string lab_text =
          lab ? fmt::format("{} {}", format_value_error(p.value * lab->per_si, p.std_error * lab->per_si), lab->pretty)
              : "–";
      s += fmt::format("<tr class=\"{}{}\">{}<td>{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td>{}</tr>\n",
                       i == 0 ? "model-first" : "", best ? " best" : "", i == 0 ? model_cell : "", esc(parameter_display_name(p.name)),
                       esc(value_unit(p.value, p.std_error, p.unit)), esc(lab_text), i == 0 ? stats : "");
    }
  }
  s += "</table>\n";
  if (!fit.best_reason.empty()) s += fmt::format("<p class=\"meta\">best: {}</p>\n", esc(fit.best_reason));
  return s;
}

// fit's names and spellings (fit_report.hpp), the lab's units beside SI as the coefficient table gives them.
std::string params_inline(const EffectFit& f) {
  std::string out;
  for (const auto& p : f.params) out += (out.empty() ? "" : ", ") + parameter_text(p, true);
  return out;
}

std::string explain_block(const ReportRun& r) {
  std::string s = "<h4>What the data say (explain)</h4>\n";
  if (!r.explained) return s + "<p class=\"noref\">not explained</p>\n";
  const ExplainResult& e = r.explain;
  if (!e.ok) return s + fmt::format("<p class=\"fail\">could not be explained: {}</p>\n", esc(e.message));
  // The belief is the fit's model of the same name (the same samples and weights), but for the zero
  // level, which the fit subtracts and explain names as a sensor offset.
  const std::string fit_name = e.base.fit_model();
  s += fmt::format("<p>Starting from the belief <strong>{}</strong>{}: {} (RMSE {:.3g} {}; reading noise σ {:.2g} {}):</p>\n"
                   "<ol class=\"story\">\n",
                   esc(e.base.title()),
                   fit_name.empty()     ? std::string()
                   : e.zero_level == 0 ? esc(" — the fit's " + fit_name + " model above")
                                       : esc(" — the fit's " + fit_name + " model above but for its zero level"),
                   esc(params_inline(e.base)), e.base.rmse, esc(e.unit), e.reading_noise, esc(e.unit));
  for (const auto& step : e.steps) {
    std::string removed;
    for (const auto& gone : step.removed) removed += (removed.empty() ? "" : ", ") + gone;
    if (step.added.empty()) {  // a term of the belief the data do not need
      s += fmt::format("<li>Not needed: <strong>{}</strong>. {}. RMSE {:.3g} → {:.3g} {}.<br><span class=\"meta\">{}: "
                       "{}</span></li>\n",
                       esc(removed), esc(step.why), step.rmse_before, step.rmse_after, esc(e.unit), esc(step.fit.title()),
                       esc(params_inline(step.fit)));
      continue;
    }
    const Effect* effect = find_effect(step.added);
    std::string where;
    for (const auto& d : step.where)
      where += fmt::format("{}{:.1f}–{:.1f} s (data {} the model by {:.3g} {})", where.empty() ? "" : "; ", d.tau_from_s,
                           d.tau_to_s, d.mean_residual > 0 ? "above" : "below", std::abs(d.mean_residual), e.unit);
    s += fmt::format("<li>Disagreement at {}. Missing effect: <strong>{}</strong>{}. Gap: RMSE {:.3g} → {:.3g} {}.{} "
                     "<br><span class=\"meta\">{}: {}</span></li>\n",
                     esc(where.empty() ? "—" : where), esc(step.added),
                     effect ? esc(" — " + (step.meaning.empty() ? std::string(effect->meaning) : step.meaning)) : "",
                     step.rmse_before, step.rmse_after, esc(e.unit),
                     (step.undecided.empty() ? std::string() : " <em>" + esc("Undecided: " + step.undecided) + "</em>") +
                         (removed.empty() ? std::string() : " " + esc("Removed (not needed once it is in): " + removed) + "."),
                     esc(step.fit.title()), esc(params_inline(step.fit)));
  }
  if (e.steps.empty()) s += "<li>Nothing needed adding: the belief explains the data within the noise.</li>\n";
  s += "</ol>\n";
  s += fmt::format("<p>{}</p>\n", esc(e.conclusion.empty() ? "done" : e.conclusion));
  s += fmt::format("<p>Final model <strong>{}</strong>, RMSE {:.3g} {}: {}</p>\n", esc(e.final_fit.title()),
                   e.final_fit.rmse, esc(e.unit), esc(params_inline(e.final_fit)));
  ReportOptions lab;
  lab.lab_units = true;  // the page gives the lab's units beside SI throughout
  s += fmt::format("<details><summary>the whole story</summary>\n<pre>{}</pre>\n</details>\n",
                   esc(format_explain(e, {}, lab)));
  return s;
}

std::string run_article(const SessionReport& report, const ReportRun& r) {
  const Run& run = r.fit.run;
  const std::string file = r.file_index < report.files.size() ? report.files[r.file_index].file : r.source;
  std::string s = fmt::format("<article class=\"run\" id=\"{}\">\n<h3>Bench {} — run {} in time order "
                              "<span class=\"meta\">(run {} of {})</span></h3>\n",
                              anchor("run-", fmt::format("{}-{}", r.bench, r.order)), esc(r.bench), r.order,
                              run.number, esc(file));
  s += fmt::format("<p class=\"meta\">cut at {:.3f} s{} · {} · {} samples fitted · lead-in {} · period {:.1f} ms · "
                   "zero level {:.3g} {} · reading noise σ {:.2g} {} · J = {:.6g} kg·m² ({}) · K_b = {:.6g} V·s/rad ({})</p>\n",
                   run.t_cut_s, r.cut_unix_s ? fmt::format(" ({})", recorded_at_text({*r.cut_unix_s, r.cut_local})) : "",
                   run.stopped ? fmt::format("stopped {:.2f} s after the cut", run.t_stop_s - run.t_cut_s)
                               : "did not stop",
                   r.tau.size(), esc(run.lead_in), 1e3 * run.period_s, run.zero_level, quantity_unit(r.fit.quantity),
                   r.fit.reading_noise, quantity_unit(r.fit.quantity),
                   r.fit.bench.inertia_kg_m2, esc(r.fit.bench.inertia_source), r.fit.bench.kb_v_s_per_rad,
                   esc(r.fit.bench.kb_source));
  s += verdict_block(r);
  s += fmt::format("<figure>\n{}</figure>\n", run_figure_svg(r));
  s += "<h4>Coefficients</h4>\n" + coefficient_table(r.fit);
  s += explain_block(r);
  s += "</article>\n";
  return s;
}

}  // namespace

std::string render_html_report(const SessionReport& report, const HtmlReportOptions& options) {
  std::string s = "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
                  "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n";
  s += fmt::format("<title>{}</title>\n<style>{}</style>\n</head>\n<body>\n<main>\n", esc(options.title), page_css);
  s += fmt::format("<h1>{}</h1>\n<p class=\"meta\">{}{} file{}, {} run{} on {} bench{}{}</p>\n", esc(options.title),
                   options.generated.empty() ? "" : esc("generated " + options.generated + " · "), report.files.size(),
                   report.files.size() == 1 ? "" : "s", report.runs.size(), report.runs.size() == 1 ? "" : "s",
                   report.benches.size(), report.benches.size() == 1 ? "" : "es",
                   report.usable() ? "" : " · <span class=\"fail\">some files or runs could not be used</span>");
  s += "<nav><a href=\"#summary\">summary</a><a href=\"#files\">files</a>";
  for (const auto& b : report.benches)
    s += fmt::format("<a href=\"#{}\">bench {}</a>", anchor("bench-", b.bench), esc(b.bench));
  s += "</nav>\n";
  s += summary_section(report);
  s += files_section(report);
  for (const auto& b : report.benches) {
    s += fmt::format("<section class=\"bench\" id=\"{}\">\n<h2>Bench {}</h2>\n", anchor("bench-", b.bench), esc(b.bench));
    for (std::size_t i : b.runs) s += run_article(report, report.runs[i]);
    s += "</section>\n";
  }
  if (report.runs.empty()) s += "<p class=\"fail\">No run could be fitted in these files.</p>\n";
  s += "</main>\n</body>\n</html>\n";
  return s;
}

}  // namespace spindown
