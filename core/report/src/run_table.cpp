#include "spindown/run_table.hpp"

#include <cmath>
#include <fmt/format.h>
#include <optional>
#include <variant>
#include <vector>

#include "spindown/csv_cells.hpp"
#include "spindown/quantity.hpp"
#include "fit_report_support.hpp"
#include "json_writer.hpp"

namespace spindown {

namespace {

// One cell: text, a number (NaN: none), or an integer.
using Cell = std::variant<std::string, double, long long>;
struct Column {
  std::string name;
  Cell value;
};

// One run's row, in the header's order.
std::vector<Column> row(const FileFit& file, std::size_t i) {
  constexpr double none = std::numeric_limits<double>::quiet_NaN();
  const RunFit& fit = file.runs[i];
  const Run& run = fit.run;
  const std::string bench = i < file.run_bench.size() ? file.run_bench[i] : file.bench;
  std::string doubts;
  for (const auto& d : fit.doubts) doubts += (doubts.empty() ? "" : " | ") + d;
  std::vector<Column> r;
  r.reserve(40);
  r.push_back({"file", file.file});
  r.push_back({"bench", bench});
  r.push_back({"student", i < file.run_student.size() && !file.run_student[i].empty() ? file.run_student[i] : file.student});
  r.push_back({"run", static_cast<long long>(run.number)});
  r.push_back({"t_cut_s", run.t_cut_s});
  r.push_back({"t_stop_s", run.stopped ? run.t_stop_s : none});
  r.push_back({"stopped", static_cast<long long>(run.stopped ? 1 : 0)});
  r.push_back({"samples", static_cast<long long>(run.end_index - run.cut_index)});
  r.push_back({"best", fit.best});
  r.push_back({"trust", std::string(fit.doubts.empty() ? "ok" : "doubtful")});
  r.push_back({"doubts", doubts});
  // c1 of the viscous model, c2 of the Coulomb model, c3 and c4 of the combined model.
  const std::pair<const char*, ModelKind> coefficients[] = {{"c1", ModelKind::viscous},
                                                            {"c2", ModelKind::coulomb},
                                                            {"c3", ModelKind::combined},
                                                            {"c4", ModelKind::combined}};
  for (const auto& [name, kind] : coefficients) {
    const ModelFit* m = fit.model(kind);
    const Parameter* p = m && m->converged ? m->param(name) : nullptr;
    r.push_back({name, p ? p->value : none});
    r.push_back({std::string(name) + "_stderr", p ? p->std_error : none});
    r.push_back({std::string(name) + "_total_stderr", p ? std::hypot(p->std_error, p->bench_error) : none});
  }
  const ModelFit* best = best_model(fit);
  const Parameter* w0 = best ? best->param("omega0") : nullptr;
  r.push_back({"omega0", w0 ? w0->value : none});
  r.push_back({"omega0_stderr", w0 ? w0->std_error : none});
  r.push_back({"rmse", best ? best->rmse : none});
  r.push_back({"residual_unit", std::string(quantity_unit(fit.quantity))});
  r.push_back({"reduced_chi2", best ? best->reduced_chi2 : none});
  r.push_back({"reading_noise", fit.reading_noise > 0 ? fit.reading_noise : none});  // σ, residual_unit
  const bool judged = i < file.health.size() && file.health[i].has_value();
  r.push_back({"health", judged ? std::string(health_level_name(file.health[i]->level)) : std::string()});
  r.push_back({"health_reason", judged ? file.health[i]->reason : std::string()});
  r.push_back({"J_kg_m2", fit.bench.inertia_kg_m2});
  r.push_back({"J_rel_error", fit.bench.inertia_rel_error});
  r.push_back({"Kb_V_s_per_rad", fit.bench.kb_v_s_per_rad});
  r.push_back({"Kb_rel_error", fit.bench.kb_rel_error});
  return r;
}

std::string csv_cell(const Cell& c, const CsvStyle& style) {
  if (const auto* s = std::get_if<std::string>(&c)) return csv_field(*s, style);
  if (const auto* n = std::get_if<long long>(&c)) return std::to_string(*n);
  const double x = std::get<double>(c);
  return std::isnan(x) ? std::string() : csv_number(x, style);  // an empty cell: not part of that run's fits
}

// A dummy file with one run, for the header's names.
std::vector<std::string> column_names() {
  FileFit f;
  f.runs.emplace_back();
  std::vector<std::string> names;
  for (auto& c : row(f, 0)) names.push_back(std::move(c.name));
  return names;
}

}  // namespace

std::string run_table_csv_header(const CsvStyle& style) {
  static const std::vector<std::string> names = column_names();
  std::string h(csv_file_start(style));
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (i > 0) h += style.delimiter;
    h += names[i];
  }
  return h + '\n';
}

std::string run_table_csv_rows(const FileFit& file, const CsvStyle& style) {
  std::string out;
  for (std::size_t i = 0; i < file.runs.size(); ++i) {
    bool first = true;
    for (const auto& c : row(file, i)) {
      if (!first) out += style.delimiter;
      first = false;
      out += csv_cell(c.value, style);
    }
    out += '\n';
  }
  return out;
}

void append_run_table_json_rows(const FileFit& file, std::string& out, bool& first_row) {
  for (std::size_t i = 0; i < file.runs.size(); ++i) {
    out += first_row ? "\n  " : ",\n  ";
    first_row = false;
    JsonWriter w(out, 2);
    w.begin_object();
    for (const auto& c : row(file, i)) {
      w.runtime_key(c.name);
      if (const auto* s = std::get_if<std::string>(&c.value))
        w.string(*s);  // bytes that are not UTF-8 (a Latin-1 file name) are replaced, as fit --json does
      else if (const auto* n = std::get_if<long long>(&c.value))
        w.integer(*n);
      else
        w.number(csv_number_value(std::get<double>(c.value)));  // the CSV's 10 digits, shortest; NaN/inf: null
    }
    w.end_object();
  }
}

}  // namespace spindown
