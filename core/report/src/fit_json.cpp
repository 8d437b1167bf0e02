// The `fit --json` contract (docs/cli.md), written once: JsonWriter streams it for fit,
// refit and the FIT messages; the Json documents are that text read back.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fmt/format.h>
#include <string>

#include "spindown/fit_report.hpp"
#include "spindown/lab_units.hpp"
#include "spindown/quantity.hpp"

#include "fit_report_support.hpp"
#include "json_writer.hpp"

namespace spindown {

namespace {

// A Json object keeps one member per key (a repeated key overwrites the first in place); the
// writer does not, so the text of a run with repeated parameter names is its document's dump.

bool has_repeated_param_names(const RunFit& run) {
  for (const auto& m : run.models)
    for (std::size_t i = 0; i < m.params.size(); ++i)
      for (std::size_t j = 0; j < i; ++j)
        if (m.params[i].name == m.params[j].name) return true;
  return false;
}

bool has_repeated_param_names(const FileFit& file) {
  return std::any_of(file.runs.begin(), file.runs.end(),
                     [](const RunFit& run) { return has_repeated_param_names(run); });
}

// The `fit --json` contract of one run (with the tags when given); leaves the run's object open
// (a file's entry adds "health" last).
void write_run_fit(JsonWriter& w, const RunFit& fit, const ReportOptions& opt, const RunTags* tags = nullptr) {
  const std::string_view residual_unit = quantity_unit(fit.quantity);
  const Run& run = fit.run;
  w.begin_object();
  w.key("run"); w.integer(run.number);
  w.member_number("t_cut_s", run.t_cut_s);
  w.key("t_stop_s");
  if (run.stopped) w.number(run.t_stop_s);
  else w.null();
  w.key("samples"); w.unsigned_integer(samples_in(run));
  w.key("models");
  w.begin_array();
  for (const auto& m : fit.models) {
    w.element();
    w.begin_object();
    w.member("name", model_name(m.kind));
    w.key("params");
    w.begin_object();
    for (const auto& p : m.params) {
      w.runtime_key(p.name);
      w.begin_object();
      w.member_number("value", p.value);
      w.member_number("stderr", p.std_error);
      w.member("unit", p.unit);
      w.member_number("bench_stderr", p.bench_error);
      w.member_number("total_stderr", std::hypot(p.std_error, p.bench_error));
      w.key("ci95");
      w.begin_array();
      w.element();
      w.number(p.value - 1.96 * p.std_error);
      w.element();
      w.number(p.value + 1.96 * p.std_error);
      w.end_array();
      if (opt.lab_units)
        if (auto lab = lab_unit_for(p.unit)) {
          w.key("lab");
          w.begin_object();
          w.member_number("value", p.value * lab->per_si);
          w.member_number("stderr", p.std_error * lab->per_si);
          w.member("unit", lab->ascii);
          w.end_object();
        }
      w.end_object();
    }
    w.end_object();
    w.member_number("rmse", m.rmse);
    w.member("residual_unit", residual_unit);
    w.member_number("r2", m.r2);
    w.member_number("aic", m.aic);
    w.member_number("bic", m.bic);
    w.member_number("t_stop_pred_s", m.t_stop_pred_s);
    w.key("n"); w.unsigned_integer(m.n);
    w.member("converged", m.converged);
    w.member_number("reduced_chi2", m.reduced_chi2);
    w.key("correlation");
    w.begin_object();
    w.key("params");
    w.begin_array();
    for (const auto& name : m.correlated) {
      w.element();
      w.string(name);
    }
    w.end_array();
    w.key("matrix");
    w.begin_array();
    for (std::size_t i = 0; i < m.correlated.size(); ++i) {
      w.element();
      w.begin_array();
      for (std::size_t j = 0; j < m.correlated.size(); ++j) {
        w.element();
        w.number(m.correlation[i * m.correlated.size() + j]);
      }
      w.end_array();
    }
    w.end_array();
    w.end_object();
    if (!m.message.empty()) w.member("message", m.message);
    w.end_object();
  }
  w.end_array();
  w.key("best");
  if (fit.best.empty()) w.null();
  else w.string(fit.best);
  w.member("best_reason", explain_best(fit));
  w.key("doubts");
  w.begin_array();
  for (const auto& d : fit.doubts) {
    w.element();
    w.string(d);
  }
  w.end_array();
  w.member_number("reading_step", fit.reading_step);
  w.member("stopped", run.stopped);
  w.member("end", end_name(run.end));
  w.member_number("t_end_s", run.t_end_s);
  w.member("lead_in", run.lead_in);
  w.member_number("zero_level", run.zero_level);
  w.member_number("noise_level", run.noise_level);
  w.member_number("reading_noise", fit.reading_noise);
  w.member_number("period_s", run.period_s);
  w.member("quantity", residual_unit);
  w.key("bench");
  w.begin_object();
  w.member_number("J", fit.bench.inertia_kg_m2);
  w.member("J_unit", "kg*m^2");
  w.member("J_source", fit.bench.inertia_source);
  w.member_number("Kb", fit.bench.kb_v_s_per_rad);
  w.member("Kb_unit", "V*s/rad");
  w.member("Kb_source", fit.bench.kb_source);
  if (opt.lab_units) {
    w.key("J_lab");
    w.begin_object();
    w.member_number("value", inertia_to_g_cm2(fit.bench.inertia_kg_m2));
    w.member("unit", "g*cm^2");
    w.end_object();
  }
  if (tags) w.member("id", tags->bench_id);
  w.end_object();
  if (tags && tags->has_seq) {
    w.key("first_seq"); w.integer(tags->first_seq);
    w.key("last_seq"); w.integer(tags->last_seq);
  }
}

// A run's "health" object.
void write_health(JsonWriter& w, const HealthVerdict& v) {
  w.begin_object();
  w.member("level", health_level_name(v.level));
  w.member("reason", v.reason);
  w.member("has_reference", v.has_reference);
  w.key("findings");
  w.begin_array();
  for (const auto& f : v.findings) {
    w.element();
    w.begin_object();
    w.member("what", f.what);
    w.member("level", health_level_name(f.level));
    w.member("reason", f.reason);
    w.member_number("value", f.value);
    w.member_number("stderr", f.std_error);
    w.member_number("reference", f.reference);
    w.member_number("reference_stderr", f.reference_std_error);
    w.member("reference_name", f.reference_name);
    w.member_number("ratio", f.ratio);
    w.member_number("ratio_stderr", f.ratio_std_error);
    w.member("unit", f.unit);
    w.end_object();
  }
  w.end_array();
  w.end_object();
}

// One file's entry of the contract; the writer is done (out cut to its text) on return.
void write_file_fit(std::string& out, std::size_t indent, const FileFit& file, const ReportOptions& opt,
                    bool compact = false) {
  JsonWriter w(out, indent, compact);
  w.begin_object();
  w.member("file", file.file);
  if (!file.bench.empty()) w.member("bench_id", file.bench);
  if (!file.student.empty()) w.member("student", file.student);
  w.key("runs");
  w.begin_array();
  for (std::size_t i = 0; i < file.runs.size(); ++i) {
    w.element();
    if (i < file.run_bench.size()) {
      const RunTags bench{file.run_bench[i], 0, 0, false};
      write_run_fit(w, file.runs[i], opt, &bench);
    } else {
      write_run_fit(w, file.runs[i], opt);
    }
    if (i < file.health.size() && file.health[i]) {
      w.key("health");
      write_health(w, *file.health[i]);
    }
    if (i < file.run_student.size() && !file.run_student[i].empty()) w.member("student", file.run_student[i]);
    w.end_object();
  }
  w.end_array();
  w.key("samples_read"); w.unsigned_integer(file.samples);
  w.key("lines_read"); w.unsigned_integer(file.lines_read);
  w.key("lines_skipped"); w.unsigned_integer(file.lines_skipped);
  w.key("diagnostics");
  w.begin_array();
  for (const auto& d : file.diagnostics) {
    w.element();
    w.begin_object();
    w.member("severity", severity_name(d.severity));
    w.key("line"); w.integer(d.line);
    w.member("message", d.message);
    w.end_object();
  }
  w.end_array();
  w.key("failures");
  w.begin_array();
  for (const auto& why : file.failures) {
    w.element();
    w.string(why);
  }
  w.end_array();
  w.end_object();
}

}  // namespace

std::string file_fit_json_text(const FileFit& file, const ReportOptions& opt, bool compact) {
  const std::size_t indent = compact ? 0 : 4;  // inside {"files": [ … ]}
  std::string out(indent, ' ');
  if (has_repeated_param_names(file)) {
    const std::string text = file_fit_json(file, opt).dump(compact ? -1 : 2, ' ', false, Json::error_handler_t::replace);
    for (char c : text) {
      out += c;
      if (c == '\n') out.append(indent, ' ');  // a raw newline in a dump is always layout
    }
    return out;
  }
  out.reserve(2048 + 3072 * file.runs.size() + 128 * file.diagnostics.size());
  write_file_fit(out, indent, file, opt, compact);
  return out;
}

namespace {

// The writer's text of one run (tags when given), its object closed.
std::string run_fit_text(const RunFit& fit, const ReportOptions& opt, const RunTags* tags) {
  std::string out;
  {
    JsonWriter w(out, 0);
    write_run_fit(w, fit, opt, tags);
    w.end_object();
  }
  return out;
}

}  // namespace

// The documents are the writer's text read back: one writer of the contract. Numbers are the
// shortest digits that read back as the same double, so nothing is lost on the way.
Json run_fit_json(const RunFit& fit, const ReportOptions& opt) { return Json::parse(run_fit_text(fit, opt, nullptr)); }

Json tagged_run_fit_json(const RunFit& fit, const RunTags& tags, const ReportOptions& opt) {
  return Json::parse(run_fit_text(fit, opt, &tags));
}

Json health_json(const HealthVerdict& v) {
  std::string out;
  {
    JsonWriter w(out, 0);
    write_health(w, v);
  }
  return Json::parse(out);
}

Json file_fit_json(const FileFit& file, const ReportOptions& opt) {
  std::string out;
  write_file_fit(out, 0, file, opt);
  return Json::parse(out);
}

Json fit_report_json(std::span<const FileFit> files, const ReportOptions& opt) {
  Json list = Json::array();
  for (const auto& f : files) list.push_back(file_fit_json(f, opt));
  return Json{{"files", std::move(list)}};
}

void tag_run_json(Json& run, const RunTags& tags) {
  // As tagged_run_fit_json's text reads back (a non-negative integer parses as unsigned), so the
  // two documents of one run compare equal member for member (refit --compare).
  const auto as_read_back = [](std::int64_t v) { return v >= 0 ? Json(static_cast<std::uint64_t>(v)) : Json(v); };
  run["bench"]["id"] = tags.bench_id;
  if (!tags.has_seq) return;
  run["first_seq"] = as_read_back(tags.first_seq);
  run["last_seq"] = as_read_back(tags.last_seq);
}

void append_run_fit_json_text(std::string& out, const RunFit& fit, const ReportOptions& opt, std::size_t indent,
                              const RunTags* tags, const HealthVerdict* health) {
  if (has_repeated_param_names(fit)) {
    Json j = tags ? tagged_run_fit_json(fit, *tags, opt) : run_fit_json(fit, opt);
    if (health) j["health"] = health_json(*health);
    for (char c : j.dump(2, ' ', false, Json::error_handler_t::replace)) {
      out += c;
      if (c == '\n') out.append(indent, ' ');  // a raw newline in a dump is always layout
    }
    return;
  }
  JsonWriter w(out, indent);
  write_run_fit(w, fit, opt, tags);
  if (health) {  // last, as a file's entry has it
    w.key("health");
    write_health(w, *health);
  }
  w.end_object();
}

void FitReportJsonText::add(std::string_view file_json, std::string& out) {
  if (compact_) out += any_ ? "," : "{\"files\":[";
  else out += any_ ? ",\n" : "{\n  \"files\": [\n";
  out += file_json;
  any_ = true;
}

void FitReportJsonText::finish(std::string& out) const {
  if (compact_) out += any_ ? "]}" : "{\"files\":[]}";
  else out += any_ ? "\n  ]\n}" : "{\n  \"files\": []\n}";
}

}  // namespace spindown
