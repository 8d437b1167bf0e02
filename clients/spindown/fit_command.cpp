#include "fit_command.hpp"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <fmt/format.h>
#include <iostream>
#include <memory>
#include <string>

#include "exit_codes.hpp"
#include "spindown/bench.hpp"
#include "spindown/fit.hpp"
#include "spindown/fit_report.hpp"
#include "spindown/read_recording.hpp"
#include "spindown/runs.hpp"

namespace spindown::cli {

namespace {

// Everything the options say, checked once before any file is read (bad usage: exit 2).
struct FitPlan {
  ReadOptions read;
  FitOptions fit;
  bool bench_from_user = false;  // J or K_b given on the command line: never taken from a log's config
  ReportOptions report;
};

// A finite number above (or, for non_negative, at least) zero; the message names no limits.
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
const CLI::Validator positive = number_check(false);
const CLI::Validator non_negative = number_check(true);

[[noreturn]] void bad_usage(const std::string& why) { throw CLI::ValidationError(why); }

char parse_delimiter(const std::string& s) {
  if (s == "," || s == "comma") return ',';
  if (s == ";" || s == "semicolon") return ';';
  if (s == "\\t" || s == "\t" || s == "tab") return '\t';
  if (s == " " || s == "space" || s == "whitespace") return ' ';
  bad_usage(fmt::format("--delimiter '{}' is not one of: , ; tab space", s));
}

FitPlan plan_from(const FitCommandOptions& o) {
  FitPlan plan;
  BenchParams& bench = plan.fit.bench;
  if (o.inertia_given) {
    bench.inertia_kg_m2 = o.inertia_kg_m2;
    bench.inertia_source = "--inertia";
  } else if (o.flywheel_given) {
    bench.inertia_kg_m2 =
        cylinder_inertia(o.flywheel_radius_m, o.flywheel_height_m, o.flywheel_density_kg_m3) + o.rotor_inertia_kg_m2;
    bench.inertia_source = fmt::format("flywheel r={} m h={} m rho={} kg/m^3 + rotor {} kg*m^2", o.flywheel_radius_m,
                                       o.flywheel_height_m, o.flywheel_density_kg_m3, o.rotor_inertia_kg_m2);
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

  if (!o.models.empty()) {
    plan.fit.models.clear();
    for (const auto& name : o.models) {
      if (name == "all") {
        plan.fit.models.assign(std::begin(all_models), std::end(all_models));
        continue;
      }
      auto kind = parse_model(name);
      if (!kind) bad_usage(fmt::format("--models: unknown model '{}' (viscous, coulomb, combined, all)", name));
      plan.fit.models.push_back(*kind);
    }
  }
  if (!plan.fit.is_valid(&why)) bad_usage(why);

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

  plan.report.lab_units = o.lab_units;
  plan.report.max_diagnostics = o.verbose ? 0 : 8;
  plan.report.diagnostics_in_text = false;  // they go to stderr, with the failures
  return plan;
}

// Read, segment and fit one file. Problems become diagnostics or failures, never exceptions.
FileFit fit_file(const std::string& path, const FitPlan& plan) {
  FileFit out;
  out.file = path;
  try {
    std::vector<RecordingInfo> info;
    const auto recordings = read_recordings(path, plan.read, &info);
    for (std::size_t k = 0; k < recordings.size(); ++k) {
      const Recording& rec = recordings[k];
      // An LCM log names several benches: say which one a failure is about.
      const std::string where = recordings.size() > 1 ? fmt::format("{}: ", rec.source) : std::string{};
      out.samples += rec.size();
      out.lines_read += rec.lines_read;
      out.lines_skipped += rec.lines_skipped;
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
      FitOptions fit_opt = plan.fit;
      if (!plan.bench_from_user && k < info.size() && info[k].config) {
        std::string why;
        if (auto b = bench_params_from_config(*info[k].config, &why))
          fit_opt.bench = *b;
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
        RunFit fit = fit_run(rec, run, fit_opt);
        if (fit.best.empty()) {
          std::string why;
          for (const auto& m : fit.models)
            if (!m.message.empty()) why += fmt::format("; {}: {}", model_name(m.kind), m.message);
          out.failures.push_back(where + fmt::format("run {}: no model converged{}", run.number, why));
        }
        out.runs.push_back(std::move(fit));
      }
    }
  } catch (const std::exception& e) {
    out.failures.push_back(fmt::format("could not be processed: {}", e.what()));
  }
  return out;
}

// Problems go to stderr, naming the file (and line): warnings and errors always, notes with -v.
void report_problems(const FileFit& file, const FitPlan& plan, bool verbose) {
  // An error that made the file unusable is said once, by its "not used" line.
  auto is_a_failure = [&](const Diagnostic& d) {
    return d.severity == Diagnostic::Severity::error &&
           std::any_of(file.failures.begin(), file.failures.end(), [&](const std::string& why) {
             return why.size() >= d.message.size() && why.ends_with(d.message);
           });
  };
  std::vector<Diagnostic> shown;
  for (const auto& d : file.diagnostics)
    if ((verbose || d.severity != Diagnostic::Severity::note) && !is_a_failure(d)) shown.push_back(d);
  for (const auto& line : summarize_diagnostics(shown, plan.report.max_diagnostics)) std::cerr << line << '\n';
  for (const auto& why : file.failures) std::cerr << file.file << ": error: not used: " << why << '\n';
  std::cerr.flush();
}

}  // namespace

void setup_fit(CLI::App& app) {
  auto opt = std::make_shared<FitCommandOptions>();
  CLI::App* sub = app.add_subcommand("fit", "Fit viscous, Coulomb and combined friction to each spin-down run");
  sub->footer("Exit codes: 0 ok, 1 a file or run could not be used (the others are still reported), 2 bad usage.");
  sub->add_option("FILE", opt->files, "Arduino/PuTTY log, delimited text (CSV/TSV) or LCM log")->required();
  sub->add_flag("--json", opt->json, "Print one JSON object {\"files\":[{\"runs\":[{\"models\":…}]}]} instead of tables");
  sub->add_option("--models", opt->models, "Models to fit, comma-separated: viscous,coulomb,combined (default all)")
      ->delimiter(',');
  sub->add_flag("--lab-units", opt->lab_units, "Also give the lab's units (g·cm², g·cm²·s⁻¹, g·cm²·rad·s⁻²)");
  sub->add_flag("-v,--verbose", opt->verbose, "Show every diagnostic, notes included");

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
    const int code = run_fit(*opt);
    if (code != exit_ok) throw CLI::RuntimeError(code);
  });
}

int run_fit(const FitCommandOptions& options) {
  const FitPlan plan = plan_from(options);
  std::vector<FileFit> files;
  bool all_usable = true;
  for (const auto& path : options.files) {
    FileFit file = fit_file(path, plan);
    report_problems(file, plan, options.verbose);
    all_usable = all_usable && file.usable();
    if (!options.json) {
      std::cout << format_file_fit(file, plan.report) << '\n';
      std::cout.flush();
    }
    if (options.json) files.push_back(std::move(file));
  }
  if (options.json) std::cout << fit_report_json(files, plan.report).dump(2) << std::endl;
  return all_usable ? exit_ok : exit_unusable;
}

}  // namespace spindown::cli
