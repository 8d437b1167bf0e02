#include "input_options.hpp"

#include <CLI/CLI.hpp>
#include <cmath>
#include <exception>
#include <iostream>
#include <ostream>
#include <stdexcept>
#include <fmt/format.h>

namespace spindown::cli {

namespace {

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

char parse_delimiter(const std::string& s) {
  if (s == "," || s == "comma") return ',';
  if (s == ";" || s == "semicolon") return ';';
  if (s == "\\t" || s == "\t" || s == "tab") return '\t';
  if (s == " " || s == "space" || s == "whitespace") return ' ';
  bad_usage(fmt::format("--delimiter '{}' is not one of: , ; tab space", s));
}

}  // namespace

void bad_usage(const std::string& why) { throw CLI::ValidationError(why); }

std::function<void()> add_input_options(CLI::App* sub, InputOptions& opt, InputParts parts) {
  const CLI::Validator positive = number_check(false);
  const CLI::Validator non_negative = number_check(true);
  auto* inertia = sub->add_option("--inertia", opt.inertia_kg_m2, "Moment of inertia J (kg·m²). J and K_b, each on its own: this command line, else the bench's "
                                  "--bench-config file, else the log's CONFIG, else the lab's defaults")
                      ->check(positive)
                      ->group("Bench");
  auto* radius = sub->add_option("--flywheel-radius", opt.flywheel_radius_m, "Flywheel cylinder radius (m)")
                     ->check(positive)
                     ->group("Bench");
  auto* height = sub->add_option("--flywheel-height", opt.flywheel_height_m, "Flywheel cylinder height (m)")
                     ->check(positive)
                     ->group("Bench");
  auto* density = sub->add_option("--flywheel-density", opt.flywheel_density_kg_m3, "Flywheel density (kg/m³)")
                      ->check(positive)
                      ->group("Bench");
  auto* rotor = sub->add_option("--rotor-inertia", opt.rotor_inertia_kg_m2, "Motor rotor inertia (kg·m²)")
                    ->check(non_negative)
                    ->group("Bench");
  for (auto* o : {radius, height, density, rotor}) {
    o->excludes(inertia);
    for (auto* other : {radius, height, density, rotor})
      if (other != o) o->needs(other);
  }
  auto* kb = sub->add_option("--kb", opt.kb_v_s_per_rad, "Back-EMF constant K_b (V·s/rad)")
                 ->check(positive)
                 ->group("Bench");
  auto* kv = sub->add_option("--speed-constant", opt.speed_constant_rpm_per_v, "Motor speed constant (rpm/V)")
                 ->check(positive)
                 ->group("Bench");
  kb->excludes(kv);
  auto* j_error = sub->add_option("--inertia-error", opt.inertia_error_pct,
                  "Standard uncertainty of J in % (geometry, density): carried into c1…c4 beside their statistical "
                  "error (default: the bench file's inertia_error_pct, the CONFIG's, else 0: J taken as exact)")
      ->check(CLI::Range(0.0, 100.0))
      ->group("Bench");
  auto* kb_error = sub->add_option("--kb-error", opt.kb_error_pct,
                  "Standard uncertainty of K_b in % (datasheet tolerance): carried into c2, c4 and omega0 of a "
                  "back-EMF reading (default: the bench file's kb_error_pct, the CONFIG's, else 0)")
      ->check(CLI::Range(0.0, 100.0))
      ->group("Bench");

  if (parts.bench_config)
    sub->add_option("--bench-config", opt.bench_configs,
                    "Per-bench TOML file(s): [bench] J/K_b (flags win) and [motor]/[baseline]/[health] for the "
                    "motor health verdict; a directory means every *.toml in it; repeat the flag for more. An LCM "
                    "log's bench takes the file of its bench id, a text file the roster's or --bench-pattern's "
                    "bench, else the only file given")
        ->allow_extra_args(false)
        ->check(CLI::ExistingPath)
        ->group("Bench");

  if (parts.text) {
    const char* text = "Delimited text";
    sub->add_option("--time-column", opt.time_column, "Time column: header name or 1-based index")->group(text);
    sub->add_option("--value-column", opt.value_column, "Value column: header name or 1-based index")->group(text);
    sub->add_option("--time-unit", opt.time_unit, "Time unit: ms, s or us")->group(text);
    sub->add_option("--value-unit", opt.value_unit,
                    "Value unit: V, rpm or rad/s (or mV, rev/s, deg/s); counts: a sketch's raw analogRead() of a 5 V "
                    "10-bit converter, x 5/1023 V")
        ->group(text);
    sub->add_option("--delimiter", opt.delimiter, "Column delimiter: , ; tab space")->group(text);
    sub->add_option("--period-ms", opt.period_ms,
                    "The readings' period when the file has no time column (a sketch printing the volts alone: "
                    "--period-ms 20 for delay(20)); row k is at k periods")
        ->check(CLI::PositiveNumber)
        ->excludes("--time-column")
        ->excludes("--time-unit")
        ->group(text);

    const char* klass = "A class's files";
    sub->add_option("--roster", opt.roster,
                    "CSV/TSV with columns file,bench[,student]: which bench (and student) each text file is from")
        ->check(CLI::ExistingFile)
        ->group(klass);
    sub->add_option("--bench-pattern", opt.bench_pattern,
                    "Regex on a text file's name: group 1 is its bench, group 2 its student, "
                    "e.g. '(bench[0-9]+)_([a-z]+)'")
        ->group(klass);
  }

  add_lab_options(sub, opt.lab, "LCM logs");

  return [&opt, inertia, radius, kb, kv, j_error, kb_error]() {
    opt.inertia_error_given = j_error->count() > 0;
    opt.kb_error_given = kb_error->count() > 0;
    opt.inertia_given = inertia->count() > 0;
    opt.flywheel_given = radius->count() > 0;
    opt.kb_given = kb->count() > 0;
    opt.speed_constant_given = kv->count() > 0;
  };
}

void print_bench_file_warnings(const BenchFile& file, std::ostream& err) {
  for (const auto& w : file.warnings) err << w << '\n';
}

BenchFiles bench_files_from(const InputOptions& o, std::ostream& err) {
  BenchFiles files;
  try {
    files = load_bench_files(o.bench_configs);
  } catch (const std::exception& e) {
    bad_usage(fmt::format("--bench-config: {}", e.what()));
  }
  for (const auto& [bench, file] : files.files) print_bench_file_warnings(file, err);
  return files;
}

BenchNaming naming_from(const InputOptions& o, const std::string& fixed_bench) {
  try {
    BenchNaming naming(o.roster, o.bench_pattern, fixed_bench);
    for (const std::string& s : naming.roster_skipped()) std::cerr << s << '\n';  // a points row, no hand-in
    return naming;
  } catch (const std::invalid_argument& e) {
    bad_usage(e.what());
  } catch (const std::exception& e) {
    bad_usage(fmt::format("--roster: {}", e.what()));
  }
}

BenchChoice bench_choice_from(const InputOptions& o) {
  return {bench_from(o), o.inertia_given || o.flywheel_given, o.kb_given || o.speed_constant_given,
          o.inertia_error_given, o.kb_error_given};
}

BenchParams bench_from(const InputOptions& o) {
  BenchParams bench;
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
  std::string why;
  if (!bench.is_valid(&why)) bad_usage(why);
  bench.inertia_rel_error = o.inertia_error_pct / 100;
  bench.kb_rel_error = o.kb_error_pct / 100;
  return bench;
}

std::vector<ModelKind> models_from(const std::vector<std::string>& names) {
  std::vector<ModelKind> models;
  for (const auto& name : names) {
    if (name == "all") {
      models.assign(std::begin(all_models), std::end(all_models));
      continue;
    }
    auto kind = parse_model(name);
    if (!kind) bad_usage(fmt::format("--models: unknown model '{}' (viscous, coulomb, combined, all)", name));
    models.push_back(*kind);
  }
  return models;
}

ReadOptions read_options_from(const InputOptions& o) {
  ReadOptions read;
  DelimitedTextOptions& d = read.delimited;
  d.time_column = o.time_column;
  d.value_column = o.value_column;
  if (!o.time_unit.empty()) {
    d.time_unit = parse_time_unit(o.time_unit);
    if (!d.time_unit) bad_usage(fmt::format("--time-unit '{}' is not one of: s, ms, us", o.time_unit));
  }
  if (o.value_unit == "counts") {  // analogRead()'s counts of the lab's Uno: 10 bits on a 5 V reference
    d.quantity = Quantity::back_emf_volts;
    d.value_scale = 5.0 / 1023.0;
  } else if (!o.value_unit.empty()) {
    const auto unit = parse_value_unit(o.value_unit);
    if (!unit) bad_usage(fmt::format("--value-unit '{}' is not one of: {}, counts", o.value_unit, value_units_read()));
    d.quantity = unit->quantity;
    d.value_scale = unit->scale;
  }
  if (!o.delimiter.empty()) d.delimiter = parse_delimiter(o.delimiter);
  if (o.period_ms > 0) d.period_ms = o.period_ms;
  read.lcm.gate = gate_options_from(o.lab);
  std::string why;
  if (!read.is_valid(&why)) bad_usage(why);
  return read;
}

}  // namespace spindown::cli
