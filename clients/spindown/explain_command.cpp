#include "explain_command.hpp"

#include <CLI/CLI.hpp>
#include <cmath>
#include <exception>
#include <fmt/format.h>
#include <fstream>
#include <iostream>
#include <memory>
#include <string>

#include "exit_codes.hpp"
#include "spindown/bench.hpp"
#include "spindown/explain.hpp"
#include "spindown/explain_report.hpp"
#include "spindown/fit_report.hpp"
#include "spindown/read_recording.hpp"
#include "spindown/runs.hpp"

namespace spindown::cli {

namespace {

struct ExplainPlan {
  ReadOptions read;
  ExplainOptions explain;
  bool bench_from_user = false;  // J or K_b given on the command line: never taken from a log's config
};

CLI::Validator number_check(bool non_negative) {
  return CLI::Validator(
      [non_negative](std::string& text) -> std::string {
        std::size_t used = 0;
        double x = 0;
        try {
          x = std::stod(text, &used);
        } catch (const std::exception&) {
          used = 0;
        }
        if (used == 0 || used != text.size() || !std::isfinite(x) || x < 0 || (!non_negative && x == 0))
          return fmt::format("'{}' is not a {} number", text, non_negative ? "non-negative" : "positive");
        return {};
      },
      non_negative ? "NUMBER>=0" : "NUMBER>0");
}

[[noreturn]] void bad_usage(const std::string& why) { throw CLI::ValidationError(why); }

char parse_delimiter(const std::string& s) {
  if (s == "," || s == "comma") return ',';
  if (s == ";" || s == "semicolon") return ';';
  if (s == "\\t" || s == "\t" || s == "tab") return '\t';
  if (s == " " || s == "space" || s == "whitespace") return ' ';
  bad_usage(fmt::format("--delimiter '{}' is not one of: , ; tab space", s));
}

ExplainPlan plan_from(const ExplainCommandOptions& o) {
  ExplainPlan plan;
  BenchParams& bench = plan.explain.bench;
  if (o.inertia_given) {
    bench.inertia_kg_m2 = o.inertia_kg_m2;
    bench.inertia_source = "--inertia";
  } else if (o.flywheel_given) {
    bench.inertia_kg_m2 =
        cylinder_inertia(o.flywheel_radius_m, o.flywheel_height_m, o.flywheel_density_kg_m3) + o.rotor_inertia_kg_m2;
    bench.inertia_source = "flywheel geometry + rotor";
  }
  if (o.kb_given) {
    bench.kb_v_s_per_rad = o.kb_v_s_per_rad;
    bench.kb_source = "--kb";
  } else if (o.speed_constant_given) {
    bench.kb_v_s_per_rad = kb_from_speed_constant(o.speed_constant_rpm_per_v);
    bench.kb_source = fmt::format("speed constant {} rpm/V", o.speed_constant_rpm_per_v);
  }
  plan.bench_from_user = o.inertia_given || o.flywheel_given || o.kb_given || o.speed_constant_given;
  std::string why;
  if (!bench.is_valid(&why)) bad_usage(why);

  plan.explain.base = parse_effect_list(o.base, &why);
  if (plan.explain.base.empty()) bad_usage(fmt::format("--base: {}", why));
  if (!plan.explain.is_valid(&why)) bad_usage(fmt::format("--base: {}", why));

  DelimitedTextOptions& d = plan.read.delimited;
  d.time_column = o.time_column;
  d.value_column = o.value_column;
  if (!o.time_unit.empty()) {
    d.time_unit = parse_time_unit(o.time_unit);
    if (!d.time_unit) bad_usage(fmt::format("--time-unit '{}' is not one of: s, ms, us", o.time_unit));
  }
  if (!o.value_unit.empty()) {
    d.quantity = parse_quantity(o.value_unit);
    if (!d.quantity) bad_usage(fmt::format("--value-unit '{}' is not one of: V, rpm, rad/s", o.value_unit));
  }
  if (!o.delimiter.empty()) d.delimiter = parse_delimiter(o.delimiter);
  if (!plan.read.is_valid(&why)) bad_usage(why);
  return plan;
}

// Read, segment and explain one file. Problems become diagnostics or failures, never exceptions.
FileExplain explain_file(const std::string& path, const ExplainPlan& plan) {
  FileExplain out;
  out.file = path;
  try {
    std::vector<RecordingInfo> info;
    const auto recordings = read_recordings(path, plan.read, &info);
    for (std::size_t k = 0; k < recordings.size(); ++k) {
      const Recording& rec = recordings[k];
      const std::string where = recordings.size() > 1 ? fmt::format("{}: ", rec.source) : std::string{};
      out.samples += rec.size();
      out.diagnostics.insert(out.diagnostics.end(), rec.diagnostics.begin(), rec.diagnostics.end());
      if (rec.empty()) {
        std::string why = "no samples";
        for (const auto& d : rec.diagnostics)
          if (d.severity == Diagnostic::Severity::error) {
            why = d.message;
            break;
          }
        out.failures.push_back(where + why);
        continue;
      }
      ExplainOptions opt = plan.explain;
      if (!plan.bench_from_user && k < info.size() && info[k].config) {
        std::string why;
        if (auto b = bench_params_from_config(*info[k].config, &why))
          opt.bench = *b;
        else
          out.diagnostics.push_back({Diagnostic::Severity::warning, rec.source, 0,
                                     fmt::format("bench config not used ({}); lab defaults assumed", why)});
      }
      const Segmentation seg = find_runs(rec);
      out.diagnostics.insert(out.diagnostics.end(), seg.diagnostics.begin(), seg.diagnostics.end());
      if (seg.runs.empty()) {
        out.failures.push_back(where + fmt::format("no spin-down run found in {} samples", rec.size()));
        continue;
      }
      for (const Run& run : seg.runs) {
        ExplainResult r = explain_run(rec, run, opt);
        if (!r.ok) out.failures.push_back(where + fmt::format("run {}: {}", run.number, r.message));
        out.runs.push_back(std::move(r));
      }
    }
  } catch (const std::exception& e) {
    out.failures.push_back(fmt::format("could not be processed: {}", e.what()));
  }
  return out;
}

void report_problems(const FileExplain& file, bool verbose) {
  std::vector<Diagnostic> shown;
  for (const auto& d : file.diagnostics)
    if (verbose || d.severity != Diagnostic::Severity::note) shown.push_back(d);
  for (const auto& line : summarize_diagnostics(shown, verbose ? 0 : 8)) std::cerr << line << '\n';
  for (const auto& why : file.failures) std::cerr << file.file << ": error: not used: " << why << '\n';
  std::cerr.flush();
}

}  // namespace

void setup_explain(CLI::App& app) {
  auto opt = std::make_shared<ExplainCommandOptions>();
  CLI::App* sub = app.add_subcommand(
      "explain", "Find where the base model and the measurement disagree, name the missing effect, add it, repeat");
  sub->footer("Effects: viscous, coulomb, stribeck, windage, sensor_offset (combined = viscous,coulomb).\n"
              "Exit codes: 0 ok, 1 a file or run could not be used (the others are still reported), 2 bad usage.");
  sub->add_option("FILE", opt->files, "Arduino/PuTTY log, delimited text (CSV/TSV) or LCM log")->required();
  sub->add_option("--base", opt->base,
                  "Starting model: viscous (the lab's belief, default), coulomb, combined, or EFFECT,EFFECT,…");
  sub->add_flag("--json", opt->json, "Print one JSON object {\"files\":[{\"runs\":[{\"steps\":…}]}]} instead of text");
  sub->add_option("--svg", opt->svg, "Write a figure (measurement, base and final model, residuals) to this file");
  sub->add_flag("-v,--verbose", opt->verbose, "Show every diagnostic, notes included");

  const CLI::Validator positive = number_check(false);
  const CLI::Validator non_negative = number_check(true);
  auto* inertia = sub->add_option("--inertia", opt->inertia_kg_m2, "Moment of inertia J (kg·m²)")
                      ->check(positive)
                      ->group("Bench");
  auto* radius = sub->add_option("--flywheel-radius", opt->flywheel_radius_m, "Flywheel cylinder radius (m)")
                     ->check(positive)
                     ->group("Bench");
  auto* height = sub->add_option("--flywheel-height", opt->flywheel_height_m, "Flywheel cylinder height (m)")
                     ->check(positive)
                     ->group("Bench");
  auto* density = sub->add_option("--flywheel-density", opt->flywheel_density_kg_m3, "Flywheel density (kg/m³)")
                      ->check(positive)
                      ->group("Bench");
  auto* rotor = sub->add_option("--rotor-inertia", opt->rotor_inertia_kg_m2, "Motor rotor inertia (kg·m²)")
                    ->check(non_negative)
                    ->group("Bench");
  for (auto* o : {radius, height, density, rotor}) {
    o->excludes(inertia);
    for (auto* other : {radius, height, density, rotor})
      if (other != o) o->needs(other);
  }
  auto* kb = sub->add_option("--kb", opt->kb_v_s_per_rad, "Back-EMF constant K_b (V·s/rad)")
                 ->check(positive)
                 ->group("Bench");
  auto* kv = sub->add_option("--speed-constant", opt->speed_constant_rpm_per_v, "Motor speed constant (rpm/V)")
                 ->check(positive)
                 ->group("Bench");
  kb->excludes(kv);

  const char* text = "Delimited text";
  sub->add_option("--time-column", opt->time_column, "Time column: header name or 1-based index")->group(text);
  sub->add_option("--value-column", opt->value_column, "Value column: header name or 1-based index")->group(text);
  sub->add_option("--time-unit", opt->time_unit, "Time unit: ms, s or us")->group(text);
  sub->add_option("--value-unit", opt->value_unit, "Value unit: V, rpm or rad/s")->group(text);
  sub->add_option("--delimiter", opt->delimiter, "Column delimiter: , ; tab space")->group(text);

  sub->callback([opt, inertia, radius, kb, kv]() {
    opt->inertia_given = inertia->count() > 0;
    opt->flywheel_given = radius->count() > 0;
    opt->kb_given = kb->count() > 0;
    opt->speed_constant_given = kv->count() > 0;
    const int code = run_explain(*opt);
    if (code != exit_ok) throw CLI::RuntimeError(code);
  });
}

int run_explain(const ExplainCommandOptions& options) {
  const ExplainPlan plan = plan_from(options);
  std::vector<FileExplain> files;
  bool all_usable = true;
  for (const auto& path : options.files) {
    FileExplain file = explain_file(path, plan);
    report_problems(file, options.verbose);
    all_usable = all_usable && file.usable();
    if (!options.json) {
      std::cout << format_file_explain(file) << std::flush;
    }
    files.push_back(std::move(file));
  }
  if (options.json) std::cout << explain_report_json(files).dump(2) << std::endl;
  if (!options.svg.empty()) {
    std::ofstream svg(options.svg, std::ios::binary | std::ios::trunc);
    if (svg) svg << explain_svg(files);
    if (!svg || !svg.flush()) {
      std::cerr << options.svg << ": error: cannot write the figure\n";
      return exit_unusable;
    }
  }
  return all_usable ? exit_ok : exit_unusable;
}

}  // namespace spindown::cli
