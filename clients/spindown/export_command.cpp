#include "export_command.hpp"

#include <CLI/CLI.hpp>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fmt/format.h>
#include <iostream>
#include <memory>
#include <regex>

#include "exit_codes.hpp"
#include "refit_command.hpp"
#include "spindown/quantity.hpp"

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

// MATLAB's readtable and pandas read NaN, Inf and -Inf.
std::string number(double x) {
  if (std::isnan(x)) return "NaN";
  if (std::isinf(x)) return x > 0 ? "Inf" : "-Inf";
  return fmt::format("{:.10g}", x);
}

// Quote a CSV field only when it needs it.
std::string field(const std::string& s) {
  if (s.find_first_of(",\"\r\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) {
    if (c == '"') q += '"';
    q += c;
  }
  return q + '"';
}

std::string fits_path_for(const std::string& out) {
  if (out.size() > 4 && out.ends_with(".csv")) return out.substr(0, out.size() - 4) + ".fits.csv";
  return out + ".fits.csv";
}

void write_fits(std::FILE* f, const LogRefit& r) {
  static const char* const param_names[] = {"c1", "c2", "c3", "c4", "omega0", "A", "B", "C"};
  std::fputs("bench,run,model,best,converged,t_cut_s,t_stop_s,stopped,samples,rmse,residual_unit,r2,aic,bic,"
             "t_stop_pred_s",
             f);
  for (const char* p : param_names) fmt::print(f, ",{},{}_stderr", p, p);
  std::fputs(",J_kg_m2,Kb_V_s_per_rad,bench_source,zero_level\n", f);
  for (const RefitRun& run : r.runs) {
    const RunFit& fit = run.fit;
    const Run& rn = fit.run;
    for (const ModelFit& m : fit.models) {
      const std::string name(model_name(m.kind));
      fmt::print(f, "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}", field(run.bench), rn.number, name,
                 name == fit.best ? 1 : 0, m.converged ? 1 : 0, number(rn.t_cut_s),
                 rn.stopped ? number(rn.t_stop_s) : std::string("NaN"), rn.stopped ? 1 : 0,
                 rn.end_index - rn.cut_index, number(m.rmse), quantity_unit(fit.quantity), number(m.r2),
                 number(m.aic), number(m.bic), number(m.t_stop_pred_s));
      for (const char* p : param_names) {
        if (const Parameter* q = m.param(p))
          fmt::print(f, ",{},{}", number(q->value), number(q->std_error));
        else
          std::fputs(",,", f);
      }
      fmt::print(f, ",{},{},{},{}\n", number(fit.bench.inertia_kg_m2), number(fit.bench.kb_v_s_per_rad),
                 field(run.bench_source), number(rn.zero_level));
    }
  }
}

}  // namespace

void setup_export(CLI::App& app) {
  auto opt = std::make_shared<ExportCommandOptions>();
  CLI::App* sub = app.add_subcommand("export", "Write an LCM log's samples (and its runs' fits) as CSV");
  sub->footer(
      "Samples CSV: bench,seq,device_time_s,host_time_s,value,unit,raw_adc,clock_epoch — one row per recorded "
      "sample, log order (repeats and NaN kept; raw_adc empty when unknown).\n"
      "Fits CSV (-o OUT.csv writes OUT.fits.csv too, or --fits FILE): the log refitted as spindown-fitter does, "
      "one row per run and model: bench,run,model,best,converged,t_cut_s,t_stop_s,stopped,samples,rmse,"
      "residual_unit,r2,aic,bic,t_stop_pred_s, then value and _stderr of c1,c2,c3,c4,omega0,A,B,C, then "
      "J_kg_m2,Kb_V_s_per_rad,bench_source,zero_level. SI: c1,c3 N*m*s/rad; c2,c4 N*m; omega0 rad/s.\n"
      "MATLAB: readtable('OUT.csv'); Python: pandas.read_csv('OUT.csv').\n"
      "Exit codes: 0 ok, 1 the log could not be read or written, 2 bad usage.");
  sub->add_option("LOG", opt->log, "LCM event log")->required();
  sub->add_flag("--csv", opt->csv, "CSV output (the only format; the default)");
  sub->add_option("-o,--output", opt->out, "samples CSV file (default stdout)");
  auto* fits = sub->add_option("--fits", opt->fits, "fits CSV file (default: OUT with .fits.csv when -o is given)");
  sub->add_flag("--no-fits", opt->no_fits, "do not refit, samples only")->excludes(fits);
  sub->add_option("--bench", opt->bench_regex, "only benches whose id matches this regex");
  sub->callback([opt]() {
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
  std::string fits_path = o.fits;
  if (fits_path.empty() && !o.no_fits && !o.out.empty() && o.out != "-") fits_path = fits_path_for(o.out);
  if (!fits_path.empty() && fits_path == o.out)
    throw CLI::ValidationError("--fits and -o name the same file");

  Output samples;
  if (!samples.open(o.out)) {
    std::cerr << "spindown export: cannot write " << o.out << ": " << std::strerror(errno) << '\n';
    return exit_unusable;
  }
  std::FILE* f = samples.f;
  std::fputs("bench,seq,device_time_s,host_time_s,value,unit,raw_adc,clock_epoch\n", f);
  std::size_t rows = 0;
  auto each = [&](const LcmLogEvent& ev) {
    if (ev.kind != LcmLogEvent::Kind::samples || !std::regex_match(ev.bench.begin(), ev.bench.end(), wanted)) return;
    const samples_t& m = ev.samples;
    const auto q = quantity_from_samples_code(m.quantity);
    const std::string unit = q ? std::string(quantity_unit(*q)) : fmt::format("code {}", int(m.quantity));
    for (std::int32_t i = 0; i < m.n; ++i) {
      const std::int32_t adc = i < std::int32_t(m.raw_adc.size()) ? m.raw_adc[i] : -1;
      const double host = i < std::int32_t(m.host_time_us.size()) ? 1e-6 * double(m.host_time_us[i]) : NAN;
      fmt::print(f, "{},{},{:.6f},{},{},{},{},{}\n", field(std::string(ev.bench)), m.seq + i, 1e-6 * double(m.device_time_us[i]),
                 std::isfinite(host) ? fmt::format("{:.6f}", host) : std::string("NaN"), number(m.value[i]),
                 field(unit), adc >= 0 ? std::to_string(adc) : std::string(), m.clock_epoch);
      ++rows;
    }
  };
  FitterOptions fopt;
  fopt.bench_regex = o.bench_regex;
  fopt.max_rate_hz = 0;
  const LogRefit r = refit_log(o.log, fopt, false, each);
  std::string why;
  bool ok = samples.close(&why);
  if (!ok) std::cerr << "spindown export: " << why << '\n';
  for (const auto& d : r.file.diagnostics)
    if (d.severity != Diagnostic::Severity::note) std::cerr << d.to_string() << '\n';
  if (!r.file.failures.empty() && r.file.samples == 0) {
    for (const auto& w : r.file.failures) std::cerr << o.log << ": error: " << w << '\n';
    ok = false;
  }
  if (!fits_path.empty()) {
    Output fits;
    if (!fits.open(fits_path)) {
      std::cerr << "spindown export: cannot write " << fits_path << ": " << std::strerror(errno) << '\n';
      return exit_unusable;
    }
    write_fits(fits.f, r);
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
