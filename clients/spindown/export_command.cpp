#include "export_command.hpp"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fmt/format.h>
#include <fstream>
#include <iostream>
#include <memory>
#include <regex>

#include "csv_output.hpp"
#include "exit_codes.hpp"
#include "export_mcap.hpp"
#include "refit_command.hpp"
#include "spindown/csv_cells.hpp"
#include "spindown/quantity.hpp"
#include "spindown/bench_naming.hpp"
#include "spindown/read_recording.hpp"
#include "spindown/offline_pipeline.hpp"

namespace spindown::cli {

namespace {

// A FILE* that closes itself; stdout is borrowed.
struct Output {
  std::FILE* f = nullptr;
  bool owned = false;
  std::string name;
  ~Output() {
    if (owned && f) std::fclose(f);
  }
  bool open(const std::string& path) {
    if (path.empty() || path == "-") {
      f = stdout;
      name = "stdout";
      return true;
    }
    name = path;
    f = std::fopen(path.c_str(), "w");
    owned = f != nullptr;
    return f != nullptr;
  }
  bool close(std::string* why) {
    const bool bad = std::ferror(f) != 0;
    int rc = 0;
    if (owned) {
      rc = std::fclose(f);
      f = nullptr;
      owned = false;
    } else {
      rc = std::fflush(f);
    }
    if (bad || rc != 0) {
      *why = fmt::format("writing {} failed: {}", name, std::strerror(errno ? errno : EIO));
      return false;
    }
    return true;
  }
};


std::string fits_path_for(const std::string& out) {
  if (out.size() > 4 && out.ends_with(".csv")) return out.substr(0, out.size() - 4) + ".fits.csv";
  return out + ".fits.csv";
}

// A number with six decimals in the style's decimal mark (times in seconds to the microsecond).
std::string csv_fixed6(double x, const CsvStyle& style) { return csv_decimal(fmt::format("{:.6f}", x), style); }

void write_fits(std::FILE* f, const LogRefit& r, const CsvStyle& style) {
  static const char* const param_names[] = {"c1", "c2", "c3", "c4", "omega0", "A", "B", "C"};
  const char d = style.delimiter;
  std::fputs(std::string(csv_file_start(style)).c_str(), f);
  for (const char* name : {"bench", "run", "model", "best", "converged", "t_cut_s", "t_stop_s", "stopped", "samples",
                           "rmse", "residual_unit", "r2", "aic", "bic", "t_stop_pred_s"})
    fmt::print(f, "{}{}", std::string_view(name) == "bench" ? "" : std::string(1, d), name);
  for (const char* p : param_names) fmt::print(f, "{0}{1}{0}{1}_stderr", d, p);
  fmt::print(f, "{0}J_kg_m2{0}Kb_V_s_per_rad{0}bench_source{0}zero_level\n", d);
  for (const RefitRun& run : r.runs) {
    const RunFit& fit = run.fit;
    const Run& rn = fit.run;
    for (const ModelFit& m : fit.models) {
      const std::string name(model_name(m.kind));
      fmt::print(f, "{1}{0}{2}{0}{3}{0}{4}{0}{5}{0}{6}{0}{7}{0}{8}{0}{9}{0}{10}{0}{11}{0}{12}{0}{13}{0}{14}{0}{15}", d,
                 csv_field(run.bench, style), rn.number, name, name == fit.best ? 1 : 0, m.converged ? 1 : 0,
                 csv_number(rn.t_cut_s, style), rn.stopped ? csv_number(rn.t_stop_s, style) : std::string("NaN"),
                 rn.stopped ? 1 : 0, rn.end_index - rn.cut_index, csv_number(m.rmse, style),
                 quantity_unit(fit.quantity), csv_number(m.r2, style), csv_number(m.aic, style),
                 csv_number(m.bic, style), csv_number(m.t_stop_pred_s, style));
      for (const char* p : param_names) {
        if (const Parameter* q = m.param(p))
          fmt::print(f, "{0}{1}{0}{2}", d, csv_number(q->value, style), csv_number(q->std_error, style));
        else
          fmt::print(f, "{0}{0}", d);
      }
      fmt::print(f, "{0}{1}{0}{2}{0}{3}{0}{4}\n", d, csv_number(fit.bench.inertia_kg_m2, style),
                 csv_number(fit.bench.kb_v_s_per_rad, style), csv_field(run.bench_source, style),
                 csv_number(rn.zero_level, style));
    }
  }
}

// What the file's first bytes say it is (a missing file: not a log; the text path says why).
bool is_lcm_log(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string start(4096, '\0');
  in.read(start.data(), static_cast<std::streamsize>(start.size()));
  start.resize(static_cast<std::size_t>(std::max<std::streamsize>(in.gcount(), 0)));
  return detect_format(start) == FileFormat::lcm_log;
}

// An LCM log: every SAMPLE message as recorded, and the log refitted as spindown-fitter fits live.
// J and K_b as `spindown refit` takes them: the command line's and the bench files' [bench] win over
// the CONFIG (each run's bench_source says so), else the CONFIG, else the lab's.
LogRefit export_log(const ExportCommandOptions& o, const BenchFiles& files, const std::regex& wanted, const CsvStyle& style,
                    std::FILE* f,
                    std::size_t& rows) {
  FitterOptions fopt;
  fopt.bench_regex = o.bench_regex;
  fopt.max_rate_hz = 0;
  fopt.named = bench_choice_from(o.input);
  fopt.bench_files = files.files;
  fopt.gate = gate_options_from(o.input.lab);
  // The samples of this lab (and with --key, signed ones); the refit's core names the rest.
  MessageGate gate(fopt.gate);
  auto each = [&](const LcmLogEvent& ev) {
    if (ev.kind != LcmLogEvent::Kind::samples || !std::regex_match(ev.bench.begin(), ev.bench.end(), wanted)) return;
    if (!gate.accepts_at_once(ev.samples_view.lab, ev.samples_view.sent_to) &&
        !gate.check(ev.channel, ev.data, ev.data_size, ev.log_utime).accepted())
      return;
    const samples_t& m = ev.samples;
    const auto q = quantity_from_samples_code(m.quantity);
    const std::string unit = q ? std::string(quantity_unit(*q)) : fmt::format("code {}", int(m.quantity));
    for (std::int32_t i = 0; i < m.n; ++i) {
      const std::int32_t adc = i < std::int32_t(m.raw_adc.size()) ? m.raw_adc[i] : -1;
      const double host = i < std::int32_t(m.host_time_us.size()) ? 1e-6 * double(m.host_time_us[i]) : NAN;
      fmt::print(f, "{1}{0}{2}{0}{3}{0}{4}{0}{5}{0}{6}{0}{7}{0}{8}\n", style.delimiter,
                 csv_field(std::string(ev.bench), style), m.seq + i, csv_fixed6(1e-6 * double(m.device_time_us[i]), style),
                 std::isfinite(host) ? csv_fixed6(host, style) : std::string("NaN"), csv_number(m.value[i], style),
                 csv_field(unit, style), adc >= 0 ? std::to_string(adc) : std::string(), m.clock_epoch);
      ++rows;
    }
  };
  return refit_log(o.log, fopt, false, each);
}

// A text recording's bench in the CSV: the roster's or --bench-pattern's, else the file's name.
std::string csv_bench(const OfflineRecording& r) { return r.bench.empty() ? file_stem(r.path) : r.bench; }

// A text recording (Arduino/PuTTY, CSV/TSV): its samples as read (seq: the sample's index; host
// time and raw ADC unknown; clock_epoch: Arduino resets before it), and its runs fitted as
// `spindown fit` fits them (J and K_b by the same rule). Its bench: --roster, --bench-pattern, else
// the file's name.
LogRefit export_text(const ExportCommandOptions& o, OfflinePlan plan, const std::regex& wanted,
                     const CsvStyle& style, std::FILE* f, std::size_t& rows, bool& ok) {
  struct Sink : OfflineSink {
    const std::regex& wanted;
    const CsvStyle& style;
    std::FILE* f;
    std::size_t& rows;
    LogRefit out;
    FitOptions fit_opt;
    bool export_fits = true;
    Sink(const std::regex& w, const CsvStyle& s, std::FILE* file, std::size_t& n)
        : wanted(w), style(s), f(file), rows(n) {}
    void recording(const OfflineRecording& r) override {
      const Recording& rec = r.recording;
      out.file.samples += rec.size();
      out.file.lines_read += rec.lines_read;
      out.file.lines_skipped += rec.lines_skipped;
      const std::string bench = csv_field(csv_bench(r), style), unit = csv_field(quantity_unit(rec.quantity), style);
      std::size_t epoch = 0;
      for (std::size_t i = 0; i < rec.size(); ++i) {
        while (epoch < rec.clock_restarts.size() && rec.clock_restarts[epoch] <= i) ++epoch;
        fmt::print(f, "{1}{0}{2}{0}{3}{0}NaN{0}{4}{0}{5}{0}{0}{6}\n", style.delimiter, bench, i, csv_fixed6(rec.t_s[i], style),
                   csv_number(rec.value[i], style), unit, epoch);
      }
      rows += rec.size();
    }
    void diagnostics(const OfflineRecording&, From, std::span<const Diagnostic> diags) override {
      out.file.diagnostics.insert(out.file.diagnostics.end(), diags.begin(), diags.end());
    }
    void failure(const OfflineRecording*, std::string why) override { out.file.failures.push_back(std::move(why)); }
    void run(const OfflineRecording& r, const Run& run) override {
      if (!export_fits) return;
      FitOptions opt = fit_opt;
      opt.bench = r.params;
      RunFit fit = fit_run(r.recording, run, opt);
      out.runs.push_back({csv_bench(r), fit, fmt::format("J: {}; K_b: {}", r.params.inertia_source, r.params.kb_source),
                          0, 0, std::nullopt, std::nullopt});
      out.file.runs.push_back(std::move(fit));
    }
  } sink(wanted, style, f, rows);
  sink.export_fits = !o.no_fits;
  sink.fit_opt.bench = plan.bench.given;
  plan.wanted = [&wanted](const OfflineRecording& r) { return std::regex_match(csv_bench(r), wanted); };
  sink.out.file.file = o.log;
  walk_file(o.log, plan, sink);
  if (rows == 0 && sink.out.file.failures.empty()) {
    std::cerr << fmt::format("{}: error: no samples of a bench matching --bench '{}'\n", o.log, o.bench_regex);
    ok = false;
  }
  return std::move(sink.out);
}

}  // namespace

void setup_export(CLI::App& app) {
  auto opt = std::make_shared<ExportCommandOptions>();
  CLI::App* sub =
      app.add_subcommand("export", "Write a recording's samples (and its runs' fits) as CSV: an LCM log or a text file");
  sub->footer(
      "Samples CSV: bench,seq,device_time_s,host_time_s,value,unit,raw_adc,clock_epoch — one row per recorded "
      "sample, log order (repeats and NaN kept; raw_adc empty when unknown). A text recording: seq is the "
      "sample's index, host_time_s NaN, raw_adc empty, clock_epoch the Arduino resets before it; its bench the "
      "--roster's or --bench-pattern's, else the file's name.\n"
      "Fits CSV (-o OUT.csv writes OUT.fits.csv too, or --fits FILE): a log refitted as spindown-fitter does (a "
      "text recording fitted as spindown fit does), "
      "one row per run and model: bench,run,model,best,converged,t_cut_s,t_stop_s,stopped,samples,rmse,"
      "residual_unit,r2,aic,bic,t_stop_pred_s, then value and _stderr of c1,c2,c3,c4,omega0,A,B,C, then "
      "J_kg_m2,Kb_V_s_per_rad,bench_source,zero_level. SI: c1,c3 N*m*s/rad; c2,c4 N*m; omega0 rad/s.\n"
      "--csv-locale de writes ';' and decimal commas for a German (French, Italian…) Excel, and files that start "
      "with a UTF-8 byte-order mark (--csv-locale en: the mark alone).\n"
      "MATLAB: readtable('OUT.csv'); Python: pandas.read_csv('OUT.csv') (with --csv-locale de: sep=';', "
      "decimal=',').\n"
      "Exit codes: 0 ok, 1 the log could not be read or written, 2 bad usage.");
  sub->add_option("FILE", opt->log, "LCM event log, or a text recording (Arduino/PuTTY log, CSV/TSV)")->required();
  sub->add_flag("--csv", opt->csv, "CSV output (the default; see --mcap)");
  sub->add_option("-o,--output", opt->out, "samples CSV file (default stdout)");
  auto* fits = sub->add_option("--fits", opt->fits, "fits CSV file (default: OUT with .fits.csv when -o is given)");
  sub->add_flag("--no-fits", opt->no_fits, "do not refit, samples only")->excludes(fits);
  sub->add_option("--bench", opt->bench_regex, "only benches whose id matches this regex");
  add_csv_locale_option(sub, opt->csv_locale);
  sub->add_option("--mcap", opt->mcap,
                  "write MCAP (Foxglove, PlotJuggler) to this file instead of CSV: every sample, and the log's RUN "
                  "and FIT messages, as JSON (LCM logs only)")
      ->excludes("--csv")->excludes("--output")->excludes("--fits")->excludes("--no-fits")->excludes("--csv-locale");
  // A text recording's columns, units and bench; J and K_b and --bench-config for either, as fit takes them.
  auto note_given = add_input_options(sub, opt->input);
  sub->callback([opt, note_given]() {
    note_given();
    const int code = run_export(*opt);
    if (code != exit_ok) throw CLI::RuntimeError(code);
  });
}

int run_export(const ExportCommandOptions& o) {
  std::regex wanted;
  try {
    wanted = std::regex(o.bench_regex);
  } catch (const std::regex_error& e) {
    throw CLI::ValidationError(fmt::format("--bench '{}' is not a valid regex ({})", o.bench_regex, e.what()));
  }
  if (!o.mcap.empty()) return run_export_mcap(o);
  std::string fits_path = o.fits;
  if (fits_path.empty() && !o.no_fits && !o.out.empty() && o.out != "-") fits_path = fits_path_for(o.out);
  if (!fits_path.empty() && fits_path == o.out)
    throw CLI::ValidationError("--fits and -o name the same file");

  // A text recording's options, checked before anything is written (bad usage: exit 2).
  const bool lcm_log = is_lcm_log(o.log);
  const BenchNaming naming = lcm_log ? BenchNaming() : naming_from(o.input);
  const BenchFiles bench_files = bench_files_from(o.input, std::cerr);
  OfflinePlan text_plan{read_options_from(o.input), bench_choice_from(o.input), {}, {}, {}};
  text_plan.naming = &naming;
  text_plan.bench_file = [&bench_files](const OfflineRecording& r) { return bench_files.for_bench(r.bench); };

  // A byte-order mark only on files written for a spreadsheet (--csv-locale): the default CSV is for
  // MATLAB and Python, whose csv module would read the mark into the first column's name.
  const bool for_spreadsheet = !o.csv_locale.empty();
  const CsvStyle samples_style = csv_style_from(o.csv_locale, for_spreadsheet && !o.out.empty() && o.out != "-");
  const CsvStyle fits_style = csv_style_from(o.csv_locale, for_spreadsheet);
  Output samples;
  if (!samples.open(o.out)) {
    std::cerr << "spindown export: cannot write " << o.out << ": " << std::strerror(errno) << '\n';
    return exit_unusable;
  }
  std::FILE* f = samples.f;
  std::fputs(std::string(csv_file_start(samples_style)).c_str(), f);
  fmt::print(f, "bench{0}seq{0}device_time_s{0}host_time_s{0}value{0}unit{0}raw_adc{0}clock_epoch\n",
             samples_style.delimiter);
  std::size_t rows = 0;
  bool ok = true;
  std::string why;
  const LogRefit r = lcm_log ? export_log(o, bench_files, wanted, samples_style, f, rows)
                             : export_text(o, text_plan, wanted, samples_style, f, rows, ok);
  if (!samples.close(&why)) {
    std::cerr << "spindown export: " << why << '\n';
    ok = false;
  }
  for (const auto& d : r.file.diagnostics)
    if (d.severity != Diagnostic::Severity::note) std::cerr << d.to_string() << '\n';
  if (!r.file.failures.empty() && r.file.samples == 0) {
    for (const auto& w : r.file.failures) {
      const bool said = std::any_of(r.file.diagnostics.begin(), r.file.diagnostics.end(), [&](const Diagnostic& d) {
        return d.severity == Diagnostic::Severity::error && d.message == w;  // the reader's error, already shown
      });
      if (!said) std::cerr << o.log << ": error: " << w << '\n';
    }
    ok = false;
  }
  if (!fits_path.empty()) {
    Output fits;
    if (!fits.open(fits_path)) {
      std::cerr << "spindown export: cannot write " << fits_path << ": " << std::strerror(errno) << '\n';
      return exit_unusable;
    }
    write_fits(fits.f, r, fits_style);
    if (!fits.close(&why)) {
      std::cerr << "spindown export: " << why << '\n';
      ok = false;
    }
  }
  std::cerr << fmt::format("spindown export: {} samples{}{}\n", rows,
                           o.out.empty() || o.out == "-" ? std::string() : " -> " + o.out,
                           fits_path.empty() ? std::string(" (fits: use -o OUT.csv or --fits FILE)")
                                             : fmt::format("; {} runs -> {}", r.runs.size(), fits_path));
  return ok ? exit_ok : exit_unusable;
}

}  // namespace spindown::cli
