#include "spindown/fit_report.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <optional>
#include <sstream>

#include <fmt/format.h>

#include "spindown/health_report.hpp"
#include "spindown/lab_units.hpp"
#include "spindown/quantity.hpp"

#include "fit_report_support.hpp"

namespace spindown {

namespace {

bool is_curve_constant(const Parameter& p) { return p.name == "A" || p.name == "B" || p.name == "C"; }

// Display width of UTF-8 text: code points, not bytes (·, ², ω, ± are multibyte).
std::size_t display_width(std::string_view s) {
  return static_cast<std::size_t>(
      std::count_if(s.begin(), s.end(), [](char c) { return (static_cast<unsigned char>(c) & 0xC0) != 0x80; }));
}

std::vector<std::string> split_lines(const std::string& s) {
  std::vector<std::string> lines;
  std::istringstream in(s);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  if (lines.empty()) lines.emplace_back();
  return lines;
}

// A left-aligned table whose cells may span several lines.
std::string render_table(const std::vector<std::vector<std::string>>& rows, std::string_view indent) {
  if (rows.empty()) return {};
  const std::size_t ncol = rows.front().size();
  std::vector<std::vector<std::vector<std::string>>> cells;
  std::vector<std::size_t> width(ncol, 0);
  for (const auto& row : rows) {
    auto& r = cells.emplace_back();
    for (std::size_t c = 0; c < ncol; ++c) {
      r.push_back(split_lines(c < row.size() ? row[c] : std::string{}));
      for (const auto& l : r.back()) width[c] = std::max(width[c], display_width(l));
    }
  }
  // Rows that span several lines are kept apart by a blank line.
  bool tall_rows = false;
  for (std::size_t ri = 1; ri < cells.size(); ++ri)
    for (const auto& cell : cells[ri]) tall_rows = tall_rows || cell.size() > 1;
  std::string out;
  for (std::size_t ri = 0; ri < cells.size(); ++ri) {
    if (tall_rows && ri > 1) out += '\n';
    std::size_t height = 0;
    for (const auto& cell : cells[ri]) height = std::max(height, cell.size());
    for (std::size_t li = 0; li < height; ++li) {
      std::string line(indent);
      for (std::size_t c = 0; c < ncol; ++c) {
        const std::string text = li < cells[ri][c].size() ? cells[ri][c][li] : std::string{};
        line += text;
        if (c + 1 < ncol) line.append(width[c] - display_width(text) + 2, ' ');
      }
      while (!line.empty() && line.back() == ' ') line.pop_back();
      out += line + '\n';
    }
    if (ri == 0) {  // rule under the header
      std::size_t total = 0;
      for (std::size_t c = 0; c < ncol; ++c) total += width[c] + (c + 1 < ncol ? 2 : 0);
      out += std::string(indent) + std::string(total, '-') + '\n';
    }
  }
  return out;
}

std::string display_name(const Parameter& p) { return parameter_display_name(p.name); }

std::string with_unit(std::string text, std::string_view ascii_unit) {
  if (ascii_unit.empty()) return text;
  return text + " " + std::string(pretty_unit(ascii_unit));
}

std::string coefficient_cell(const ModelFit& m, const ReportOptions& opt) {
  std::string cell;
  for (const auto& p : m.params) {
    if (is_curve_constant(p)) continue;
    if (!cell.empty()) cell += '\n';
    cell += display_name(p) + " = " + with_unit(format_value_error(p.value, p.std_error), p.unit);
    if (p.bench_error > 0)  // J and K_b's own uncertainty beside the statistical one
      cell += "\n  with J, K_b: " + format_value_error(p.value, std::hypot(p.std_error, p.bench_error));
    if (opt.lab_units) cell += lab_unit_text(p);
  }
  return cell.empty() ? "-" : cell;
}

std::string curve_cell(const ModelFit& m) {
  std::string cell;
  for (const auto& p : m.params) {
    if (!is_curve_constant(p)) continue;
    if (!cell.empty()) cell += '\n';
    cell += p.name + " = " + with_unit(fmt::format("{:.6g}", p.value), p.unit);
  }
  return cell.empty() ? "-" : cell;
}

std::string stop_cell(double t_stop_pred_s) {
  return std::isfinite(t_stop_pred_s) ? fmt::format("{:.2f} s", t_stop_pred_s) : std::string("never");
}

// The lowest-BIC converged model other than the best, to compare against.
const ModelFit* runner_up(const RunFit& fit, const ModelFit* best) {
  const ModelFit* second = nullptr;
  for (const auto& m : fit.models) {
    if (&m == best || !m.converged || !std::isfinite(m.bic)) continue;
    if (!second || m.bic < second->bic) second = &m;
  }
  return second;
}

// Kass & Raftery's reading of a BIC difference.
std::string_view evidence(double delta_bic) {
  if (delta_bic > 10) return "very strong";
  if (delta_bic > 6) return "strong";
  if (delta_bic > 2) return "positive";
  return "weak";
}

}  // namespace

std::string format_value_error(double value, double std_error) {
  if (!std::isfinite(value)) return fmt::format("{}", value);
  if (!std::isfinite(std_error) || std_error <= 0) {
    const std::string v = fmt::format("{:.6g}", value);
    return std::isnan(std_error) || std::isinf(std_error) ? v + " ± ?" : v;
  }
  const int err_exp = static_cast<int>(std::floor(std::log10(std_error)));
  const int val_exp = value != 0 ? static_cast<int>(std::floor(std::log10(std::fabs(value)))) : err_exp;
  const int magnitude = std::max(val_exp, err_exp);
  if (magnitude >= -3 && magnitude < 6) {
    const int decimals = std::clamp(1 - err_exp, 0, 12);
    return fmt::format("{:.{}f} ± {:.{}f}", value, decimals, std_error, decimals);
  }
  // Shared exponent: both numbers as mantissas of 10^magnitude, error to two digits.
  const double scale = std::pow(10.0, magnitude);
  const int decimals = std::clamp(magnitude - err_exp + 1, 0, 12);
  return fmt::format("({:.{}f} ± {:.{}f})e{:+03d}", value / scale, decimals, std_error / scale, decimals, magnitude);
}

std::string parameter_display_name(std::string_view name) {
  if (name == "omega0") return "ω0";
  if (name == "w_s") return "ω_s";
  if (name == "sensor_offset") return "sensor offset";
  return std::string(name);
}

std::string lab_unit_text(const Parameter& p) {
  const auto lab = lab_unit_for(p.unit);
  return lab ? fmt::format(" = {} {}", format_value_error(p.value * lab->per_si, p.std_error * lab->per_si), lab->pretty)
             : std::string();
}

std::string parameter_text(const Parameter& p, bool lab_units) {
  return parameter_display_name(p.name) + " = " + with_unit(format_value_error(p.value, p.std_error), p.unit) +
         (lab_units ? lab_unit_text(p) : std::string());
}

std::string explain_best(const RunFit& fit) {
  if (!fit.best_reason.empty()) return fit.best_reason;
  const ModelFit* best = best_model(fit);
  if (!best) return "no model converged";
  const ModelFit* second = runner_up(fit, best);
  if (!second)
    return fmt::format("{} is the only model {}", fit.best, fit.models.size() == 1 ? "asked for" : "that converged");
  const double delta = second->bic - best->bic;
  return fmt::format("lowest BIC: ΔBIC = {:.1f} below {} ({} evidence); RMSE {:.4g} vs {:.4g}", delta,
                     model_name(second->kind), evidence(delta), best->rmse, second->rmse);
}

std::vector<std::string> summarize_diagnostics(std::span<const Diagnostic> diagnostics, std::size_t max_shown) {
  std::vector<const Diagnostic*> order;
  for (const auto& d : diagnostics) order.push_back(&d);
  auto rank = [](const Diagnostic* d) {
    return d->severity == Diagnostic::Severity::error ? 0 : d->severity == Diagnostic::Severity::warning ? 1 : 2;
  };
  std::stable_sort(order.begin(), order.end(), [&](auto* a, auto* b) { return rank(a) < rank(b); });
  std::vector<std::string> lines;
  const std::size_t shown = max_shown == 0 ? order.size() : std::min(max_shown, order.size());
  for (std::size_t i = 0; i < shown; ++i) lines.push_back(order[i]->to_string());
  if (shown < order.size()) {
    std::size_t count[3] = {0, 0, 0};
    for (std::size_t i = shown; i < order.size(); ++i) ++count[rank(order[i])];
    std::string rest;
    const char* names[3] = {"error", "warning", "note"};
    for (int s = 0; s < 3; ++s) {
      if (count[s] == 0) continue;
      if (!rest.empty()) rest += ", ";
      rest += fmt::format("{} {}{}", count[s], names[s], count[s] == 1 ? "" : "s");
    }
    lines.push_back(fmt::format("{}: ... and {} more not shown ({})", order[shown]->source, order.size() - shown, rest));
  }
  return lines;
}

namespace {

// What lmfit's and SciPy's reports hold beside the values: 95 % intervals, the correlation of the
// parameters and the reduced χ² of the weighted fit (against the run's own noise model).
std::string fit_details(const RunFit& fit, const std::string& unit) {
  std::string out = "\n  details (95 % interval = value ± 1.96 standard errors):\n";
  if (fit.reading_step > 0) out += fmt::format("    reading step {:.3g} {}\n", fit.reading_step, unit);
  for (const auto& m : fit.models) {
    if (!m.converged) continue;
    out += fmt::format("    {}: reduced χ² {}\n", model_name(m.kind),
                       std::isfinite(m.reduced_chi2) ? fmt::format("{:.3g}", m.reduced_chi2) : std::string("-"));
    for (const auto& name : m.correlated) {
      const Parameter* p = m.param(name);
      if (!p) continue;
      out += fmt::format("      {:<7} 95 %: [{:.6g}, {:.6g}] {}\n", p->name, p->value - 1.96 * p->std_error,
                         p->value + 1.96 * p->std_error, p->unit);
    }
    const std::size_t k = m.correlated.size();
    for (std::size_t i = 0; i < k; ++i)
      for (std::size_t j = i + 1; j < k; ++j)
        out += fmt::format("      correlation {}–{}: {:+.3f}\n", m.correlated[i], m.correlated[j],
                           m.correlation[i * k + j]);
  }
  return out;
}

}  // namespace

std::string format_run_fit(const RunFit& fit, const ReportOptions& opt) {
  const Run& run = fit.run;
  const std::string unit(quantity_unit(fit.quantity));
  std::string out;
  // A partial coast's first sample is not its cut: the text says so (JSON keeps "t_cut_s").
  const char* from = run.partial() ? "its first sample" : "the cut";
  if (run.partial()) out += fmt::format("run {}: coast from t = {:.3f} s (its cut was not recorded)", run.number, run.t_cut_s);
  else out += fmt::format("run {}: cut at t = {:.3f} s", run.number, run.t_cut_s);
  if (run.stopped && std::isfinite(run.t_stop_s))
    out += fmt::format(", stopped at t = {:.3f} s ({:.2f} s after {}), fitted to t = {:.3f} s", run.t_stop_s,
                       run.t_stop_s - run.t_cut_s, from, run.t_end_s);
  else
    out += fmt::format(", did not stop: fitted to t = {:.3f} s ({})", run.t_end_s, end_name(run.end));
  out += fmt::format(", {} samples", samples_in(run));
  if (!run.lead_in.empty()) out += fmt::format(", lead-in: {}", run.lead_in);
  // A doubt stands before the numbers it doubts.
  for (const auto& d : fit.doubts) out += fmt::format("\n  doubtful: {}", d);
  // The reading noise σ (reading_noise.hpp), the one noise figure fit, explain and the report name.
  // A zero level other than 0 is subtracted here; spindown explain names it as a sensor offset instead.
  out += fmt::format("\n  zero level {:.3g} {}{}, reading noise σ {:.2g} {}, period {:.1f} ms\n", run.zero_level, unit,
                     run.zero_level != 0 ? " (subtracted: every model reads zero level + k·ω; explain names it a sensor offset)"
                                         : "",
                     fit.reading_noise, unit, run.period_s * 1e3);
  out += fmt::format("  bench: J = {:.6g} kg·m² ({}), K_b = {:.6g} V·s/rad ({})", fit.bench.inertia_kg_m2,
                     fit.bench.inertia_source, fit.bench.kb_v_s_per_rad, fit.bench.kb_source);
  if (fit.bench.inertia_rel_error > 0 || fit.bench.kb_rel_error > 0)
    out += fmt::format("; uncertain by {:.3g} % (J), {:.3g} % (K_b)", 100 * fit.bench.inertia_rel_error,
                       100 * fit.bench.kb_rel_error);
  if (opt.lab_units) out += fmt::format("; J = {:.6g} g·cm²", inertia_to_g_cm2(fit.bench.inertia_kg_m2));
  out += "\n\n";

  std::vector<std::vector<std::string>> rows;
  rows.push_back({"model", "curve constants", "coefficients ± standard error", "RMSE", "R²", "BIC", "stop pred."});
  for (const auto& m : fit.models) {
    std::string name(model_name(m.kind));
    if (!m.converged) name += "\n(not converged)";
    rows.push_back({name, curve_cell(m), coefficient_cell(m, opt), fmt::format("{:.4g} {}", m.rmse, unit),
                    fmt::format("{:.5f}", m.r2), fmt::format("{:.1f}", m.bic), stop_cell(m.t_stop_pred_s)});
  }
  out += render_table(rows, "  ");
  out += fit.best.empty() ? fmt::format("\n  best: none ({})\n", explain_best(fit))
                          : fmt::format("\n  best: {} — {}\n", fit.best, explain_best(fit));
  for (const auto& m : fit.models)
    if (!m.message.empty()) out += fmt::format("  {}: {}\n", model_name(m.kind), m.message);
  if (opt.details) out += fit_details(fit, unit);
  return out;
}

std::string format_file_fit(const FileFit& file, const ReportOptions& opt) {
  std::size_t errors = 0, warnings = 0;
  for (const auto& d : file.diagnostics) {
    if (d.severity == Diagnostic::Severity::error) ++errors;
    if (d.severity == Diagnostic::Severity::warning) ++warnings;
  }
  std::string who;
  if (!file.bench.empty() || !file.student.empty())
    who = fmt::format(" ({}{}{})", file.bench.empty() ? "" : "bench " + file.bench,
                      !file.bench.empty() && !file.student.empty() ? ", " : "",
                      file.student.empty() ? "" : "student " + file.student);
  std::string out = fmt::format("== {}{}: {} samples from {} {} ({} skipped), {} run{} fitted", file.file, who,
                                file.samples, file.lines_read, file.lcm_log ? "messages" : "lines",
                                file.lines_skipped, file.runs.size(), file.runs.size() == 1 ? "" : "s");
  auto count = [](std::size_t n, std::string_view what) { return fmt::format("{} {}{}", n, what, n == 1 ? "" : "s"); };
  if (errors + warnings > 0) out += ", " + count(errors, "error") + ", " + count(warnings, "warning");
  out += '\n';
  if (opt.diagnostics_in_text) {
    for (const auto& line : summarize_diagnostics(file.diagnostics, opt.max_diagnostics)) out += "  " + line + '\n';
    for (const auto& why : file.failures) out += fmt::format("  not used: {}\n", why);
  }
  for (std::size_t i = 0; i < file.runs.size(); ++i) {
    if (i < file.run_bench.size() && (i == 0 || file.run_bench[i] != file.run_bench[i - 1]))
      out += fmt::format("\n-- bench {}\n", file.run_bench[i]);
    if (i < file.run_student.size() && !file.run_student[i].empty() &&
        (i == 0 || file.run_student[i] != file.run_student[i - 1]))
      out += fmt::format("\n-- {} (the name written in the file before the run)\n", file.run_student[i]);
    out += '\n' + format_run_fit(file.runs[i], opt);
    if (i < file.health.size() && file.health[i]) out += format_health_verdict(*file.health[i]);
  }
  return out;
}

}  // namespace spindown
