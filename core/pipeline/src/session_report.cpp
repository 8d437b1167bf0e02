#include "spindown/session_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <exception>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <numeric>
#include <stdexcept>

#include "spindown/offline_pipeline.hpp"
#include "spindown/quantity.hpp"

namespace spindown {

namespace {

// The bench a recording is reported under: an LCM log's bench id, else the plan's naming (roster,
// --bench-pattern, --bench), else the file's name without its extension.
std::string report_bench(const OfflineRecording& r) { return !r.bench.empty() ? r.bench : file_stem(r.path); }

void keep_diagnostics(ReportFile& file, std::span<const Diagnostic> more, std::size_t cap) {
  for (const auto& d : more) {
    if (file.diagnostics.size() < cap)
      file.diagnostics.push_back(d);
    else
      ++file.diagnostics_dropped;
  }
}

std::string percent(double x) { return fmt::format("{:.0f} %", 100 * x); }

}  // namespace

BenchReference bench_reference(const BenchFile& file) {
  BenchReference ref;
  ref.file = file.path;
  ref.health = file.health;
  if (file.sets_inertia || file.sets_kb) ref.bench = file;
  return ref;
}

CoefficientTrend coefficient_trend(std::string name, std::string unit, std::string x_unit, std::vector<double> x,
                                   std::vector<double> value, std::vector<double> std_error, const TrendRules& rules) {
  CoefficientTrend t;
  t.name = std::move(name);
  t.unit = std::move(unit);
  t.x_unit = std::move(x_unit);
  t.x = std::move(x);
  t.value = std::move(value);
  t.std_error = std::move(std_error);
  const std::size_t n = std::min({t.x.size(), t.value.size(), t.std_error.size()});
  const std::string what = t.name == "c3" ? "viscous friction" : t.name == "c4" ? "dry friction" : t.name;
  // Weights 1/σ²; a zero or missing σ gets the median σ so one point cannot take all the weight.
  std::vector<double> sig;
  for (std::size_t i = 0; i < n; ++i)
    if (t.std_error[i] > 0 && std::isfinite(t.std_error[i])) sig.push_back(t.std_error[i]);
  std::sort(sig.begin(), sig.end());
  const double fallback = sig.empty() ? 1.0 : sig[sig.size() / 2];
  double sw = 0, swx = 0, swy = 0;
  std::vector<double> w(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double s = t.std_error[i] > 0 && std::isfinite(t.std_error[i]) ? t.std_error[i] : fallback;
    w[i] = 1 / (s * s);
    sw += w[i], swx += w[i] * t.x[i], swy += w[i] * t.value[i];
  }
  if (n == 0) {
    t.words = fmt::format("{}: no run with a combined fit", what);
    return t;
  }
  t.mean = swy / sw;
  t.mean_stderr = std::sqrt(1 / sw);
  // Scatter about the mean beyond the runs' own errors widens the mean's error (two runs 400
  // errors apart are not known to a hair), and is said when it is far beyond them.
  if (n >= 2) {
    double chi2_mean = 0;
    for (std::size_t i = 0; i < n; ++i) chi2_mean += w[i] * (t.value[i] - t.mean) * (t.value[i] - t.mean);
    t.scatter = std::sqrt(chi2_mean / static_cast<double>(n - 1));
    t.mean_stderr *= std::max(1.0, t.scatter);
  }
  const bool disagree = t.scatter > rules.disagree_scatter;
  const auto [lo, hi] = std::minmax_element(t.value.begin(), t.value.begin() + static_cast<std::ptrdiff_t>(n));
  const std::string disagreement =
      disagree ? fmt::format("the runs disagree far beyond their errors ({:.3g} to {:.3g} {}, {:.0f}× their standard "
                             "errors apart): check which runs belong to this motor",
                             *lo, *hi, t.unit, t.scatter)
               : "";
  const double xm = swx / sw;
  double sxx = 0, sxy = 0;
  for (std::size_t i = 0; i < n; ++i) sxx += w[i] * (t.x[i] - xm) * (t.x[i] - xm), sxy += w[i] * (t.x[i] - xm) * (t.value[i] - t.mean);
  const auto [xlo, xhi] = std::minmax_element(t.x.begin(), t.x.begin() + static_cast<std::ptrdiff_t>(n));
  const double span = *xhi - *xlo;
  t.enough = n >= rules.min_runs && span > 0 && sxx > 0;
  if (!t.enough) {
    t.words = fmt::format("{}: {} run{}, too few for a trend (need {}){}{}", what, n, n == 1 ? "" : "s",
                          rules.min_runs, disagree ? "; " : "", disagreement);
    return t;
  }
  t.slope = sxy / sxx;
  const double icpt = t.mean - t.slope * xm;
  t.intercept = icpt;
  double chi2 = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double r = t.value[i] - (icpt + t.slope * t.x[i]);
    chi2 += w[i] * r * r;
  }
  // Scatter beyond the stated errors (run-to-run variation) widens the slope's error.
  const double birge = n > 2 ? std::max(1.0, std::sqrt(chi2 / static_cast<double>(n - 2))) : 1.0;
  t.slope_stderr = birge / std::sqrt(sxx);
  t.change = t.slope * span;
  t.change_stderr = t.slope_stderr * span;
  if (t.mean != 0) {
    t.relative_change = t.change / std::abs(t.mean);
    t.relative_change_stderr = t.change_stderr / std::abs(t.mean);
  }
  const bool significant = std::abs(t.slope) > rules.drift_sigma * t.slope_stderr;
  t.drifting = significant && std::abs(t.relative_change) >= rules.drift_fraction;
  // Sessions: runs on one day are one session (runs 6 h or more apart are two); without dates, runs.
  std::vector<double> when(t.x.begin(), t.x.begin() + static_cast<std::ptrdiff_t>(n));
  std::sort(when.begin(), when.end());
  std::size_t sessions = 1;
  for (std::size_t i = 1; i < when.size(); ++i) sessions += t.x_unit == "day" ? when[i] - when[i - 1] >= 0.25 : 1;
  const std::string sessions_text = t.x_unit == "day" ? fmt::format("{} session{}", sessions, sessions == 1 ? "" : "s")
                                                       : fmt::format("{} runs", n);
  const std::string over = t.x_unit == "day" ? fmt::format("over {:.3g} days ({} runs, {})", span, n, sessions_text)
                                             : fmt::format("over {} runs", n);
  // A line that leaves the runs far beyond their errors (a step, a stray run) is no evidence of
  // steadiness: "steady" only when the runs agree with the line.
  const bool line_misses = birge > rules.disagree_scatter;
  std::string verdict = t.drifting ? "drifting" : significant ? "a small but clear change" : "steady within its uncertainty";
  // Runs far apart that line up in time are a drift, not runs of another motor: friction that
  // rises steadily is wear; one that falls steadily, running in (or a lubricant spreading).
  if (t.drifting && !line_misses)
    verdict += t.change >= 0 ? fmt::format(": friction rising steadily over {}: wear (bearings, brushes, alignment)",
                                           sessions_text)
                             : fmt::format(": friction falling steadily over {}: running in, or lubricant spreading",
                                           sessions_text);
  else if (disagree)
    verdict = t.drifting || significant ? verdict + "; " + disagreement : "not steady: " + disagreement;
  else if (line_misses && !t.drifting && !significant)
    verdict = "not steady: the runs scatter far beyond their errors about any straight line";
  t.words = fmt::format("{} {} {} ± {} {}: {}", what, t.change >= 0 ? "rose" : "fell", percent(std::abs(t.relative_change)),
                        percent(t.relative_change_stderr), over, verdict);
  return t;
}

ReportRun make_report_run(const Recording& rec, const Run& run, const std::string& bench, const BenchParams& params,
                          const SessionReportOptions& options) {
  ReportRun out;
  out.bench = bench;
  out.source = rec.source;
  FitOptions fopt = options.fit;
  fopt.bench = params;
  const RunWindow window(rec.t_s, rec.value, run, fopt.weighted);  // the fit's and the explanation's
  out.fit = fit_run(window, rec.quantity, run, fopt);
  const std::size_t end = std::min(run.end_index, rec.size());
  for (std::size_t i = std::min(run.cut_index, end); i < end; ++i) {
    out.tau.push_back(rec.t_s[i] - run.t_cut_s);
    out.y.push_back(rec.value[i]);
  }
  if (options.explain_runs) {
    ExplainOptions eopt = options.explain;
    eopt.bench = params;
    eopt.weighted = window.weighted();
    try {
      out.explain = explain_run(window, rec.quantity, run, eopt, lowest_reading(rec.value));
      out.explained = true;
    } catch (const std::exception& e) {
      out.explain.ok = false;
      out.explain.message = fmt::format("could not be explained: {}", e.what());
    }
  }
  MotorHealthConfig health;
  if (auto it = options.references.find(bench); it != options.references.end()) {
    health = it->second.health;
    out.health_config = it->second.file;
  }
  out.health = assess_health(out.fit, health);
  if (!out.health.has_reference) out.health_config.clear();
  return out;
}

void set_run_context(ReportRun& out, const Recording& rec, std::span<const Run> runs, std::size_t max_points) {
  const Run& run = out.fit.run;
  std::size_t from = 0, to = rec.size();
  for (const Run& other : runs) {
    if (other.cut_index < run.cut_index) from = std::max(from, std::min(other.end_index, run.cut_index));
    if (other.cut_index > run.cut_index) to = std::min(to, other.cut_index);
  }
  to = std::min(to, rec.size());
  out.context_tau.clear();
  out.context_y.clear();
  if (from >= to) return;
  const auto add = [&](std::size_t i) {
    out.context_tau.push_back(rec.t_s[i] - run.t_cut_s);
    out.context_y.push_back(rec.value[i]);
  };
  const std::size_t count = to - from, half = std::max<std::size_t>(max_points / 2, 1);
  if (count <= max_points) {
    for (std::size_t i = from; i < to; ++i) add(i);
    return;
  }
  const std::size_t stretch = (count + half - 1) / half;
  for (std::size_t a = from; a < to; a += stretch) {
    const std::size_t b = std::min(a + stretch, to);
    std::size_t lo = a, hi = a;
    for (std::size_t i = a; i < b; ++i) {
      if (rec.value[i] < rec.value[lo]) lo = i;
      if (rec.value[i] > rec.value[hi]) hi = i;
    }
    add(std::min(lo, hi));
    if (lo != hi) add(std::max(lo, hi));
  }
}

void summarize_session(SessionReport& report) {
  // By bench id, then file (time) order, then run number.
  std::stable_sort(report.runs.begin(), report.runs.end(), [](const ReportRun& a, const ReportRun& b) {
    if (a.bench != b.bench) return a.bench < b.bench;
    if (a.file_index != b.file_index) return a.file_index < b.file_index;
    return a.fit.run.number < b.fit.run.number;
  });
  // Within a bench whose every run has a wall-clock time, that time decides.
  for (auto first = report.runs.begin(); first != report.runs.end();) {
    auto last = std::find_if(first, report.runs.end(), [&](const ReportRun& r) { return r.bench != first->bench; });
    if (std::all_of(first, last, [](const ReportRun& r) { return r.cut_unix_s.has_value(); }))
      std::stable_sort(first, last, [](const ReportRun& a, const ReportRun& b) { return *a.cut_unix_s < *b.cut_unix_s; });
    first = last;
  }
  report.benches.clear();
  for (std::size_t i = 0; i < report.runs.size(); ++i) {
    ReportRun& r = report.runs[i];
    if (report.benches.empty() || report.benches.back().bench != r.bench) {
      report.benches.emplace_back();
      report.benches.back().bench = r.bench;
    }
    BenchSummary& b = report.benches.back();
    b.runs.push_back(i);
    r.order = static_cast<int>(b.runs.size());
    if (static_cast<int>(r.health.level) > static_cast<int>(b.worst)) b.worst = r.health.level;
    if (r.health.has_reference) {
      b.has_reference = true;
      b.reference_file = r.health_config;
    }
  }
  for (BenchSummary& b : report.benches) {
    bool wall_clock = true;
    for (std::size_t i : b.runs) wall_clock = wall_clock && report.runs[i].cut_unix_s.has_value();
    double t0 = 0;
    if (wall_clock && !b.runs.empty()) t0 = *report.runs[b.runs.front()].cut_unix_s;
    std::vector<double> x, cv, cv_se, cc, cc_se;
    for (std::size_t i : b.runs) {
      const ReportRun& r = report.runs[i];
      const auto f = combined_friction(r.fit);
      if (!f) continue;
      x.push_back(wall_clock ? (*r.cut_unix_s - t0) / 86400.0 : static_cast<double>(r.order));
      cv.push_back(f->c_viscous), cv_se.push_back(f->c_viscous_stderr);
      cc.push_back(f->c_coulomb), cc_se.push_back(f->c_coulomb_stderr);
    }
    // Runs minutes apart on one day say nothing per day: fall back to run order then.
    const std::string x_unit =
        wall_clock && !x.empty() && *std::max_element(x.begin(), x.end()) >= 1.0 ? "day" : "run";
    if (x_unit == "run" && wall_clock) {
      x.clear();
      for (std::size_t i : b.runs)
        if (combined_friction(report.runs[i].fit)) x.push_back(static_cast<double>(report.runs[i].order));
    }
    b.viscous = coefficient_trend("c3", "N*m*s/rad", x_unit, x, cv, cv_se);
    b.coulomb = coefficient_trend("c4", "N*m", x_unit, x, cc, cc_se);
  }
}

bool SessionReport::usable() const {
  for (const auto& f : files)
    if (!f.failures.empty()) return false;
  return true;
}

SessionReport build_session_report(std::span<const std::string> paths, const SessionReportOptions& options,
                                   const ReportProgressFn& progress) {
  SessionReport report;
  // File sizes and start times first: the order of the session and the total for progress.
  std::uintmax_t total = 0;
  for (const auto& path : paths) {
    ReportFile f;
    f.file = path;
    std::error_code ec;
    const auto size = std::filesystem::file_size(path, ec);
    f.bytes = ec ? 0 : size;
    total += f.bytes;
    if (const auto at = recording_start(path, FileFormat::automatic, options.read)) {
      f.start_unix_s = at->unix_s;
      f.start_local = at->local;
    }
    report.files.push_back(std::move(f));
  }
  report.files_time_ordered =
      !report.files.empty() &&
      std::all_of(report.files.begin(), report.files.end(), [](const ReportFile& f) { return f.start_unix_s.has_value(); });
  if (report.files_time_ordered)
    std::stable_sort(report.files.begin(), report.files.end(),
                     [](const ReportFile& a, const ReportFile& b) { return *a.start_unix_s < *b.start_unix_s; });
  else if (report.files.size() > 1)
    report.notes.push_back("not every file tells when it was recorded (PuTTY header or LCM log): runs are in the "
                           "order the files were given");

  ReportProgress p;
  p.bytes_total = total;
  std::uintmax_t bytes_before = 0;
  std::vector<bool> reference_used(options.references.size(), false);
  for (std::size_t fi = 0; fi < report.files.size(); ++fi) {
    ReportFile& file = report.files[fi];
    p.file = file.file;
    if (progress) progress(p);
    // The offline path (offline_pipeline.hpp): the report's work per recording and run.
    struct Sink : OfflineSink {
      SessionReport& report;
      ReportFile& file;
      std::size_t fi;
      const SessionReportOptions& options;
      const ReportProgressFn& progress;
      ReportProgress& p;
      std::uintmax_t bytes_before;
      std::size_t runs_in_file = 0, runs_done_in_file = 0;
      Sink(SessionReport& rep, ReportFile& f, std::size_t index, const SessionReportOptions& o,
           const ReportProgressFn& pr, ReportProgress& pp, std::uintmax_t before)
          : report(rep), file(f), fi(index), options(o), progress(pr), p(pp), bytes_before(before) {}

      void file_read(std::span<const Recording>, std::span<const RecordingInfo>, std::size_t runs_found) override {
        runs_in_file = runs_found;
        p.runs_found += runs_found;
      }
      void recording(const OfflineRecording& r) override {
        if (r.info && file.format == FileFormat::automatic) file.format = r.info->format;
        const std::string bench = report_bench(r);
        if (std::find(file.benches.begin(), file.benches.end(), bench) == file.benches.end())
          file.benches.push_back(bench);
        if (!r.student.empty()) file.student = r.student;
        file.samples += r.recording.size();
      }
      void diagnostics(const OfflineRecording&, From, std::span<const Diagnostic> diags) override {
        keep_diagnostics(file, diags, options.max_diagnostics_per_file);
      }
      void failure(const OfflineRecording*, std::string why) override { file.failures.push_back(std::move(why)); }
      void run(const OfflineRecording& r, const Run& run) override {
        ReportRun rr = make_report_run(r.recording, run, report_bench(r), r.params, options);
        rr.file_index = fi;
        if (r.segmentation) set_run_context(rr, r.recording, r.segmentation->runs);
        if (file.start_unix_s && !r.recording.t_s.empty()) {
          rr.cut_unix_s = *file.start_unix_s + (run.t_cut_s - r.recording.t_s.front());
          rr.cut_local = file.start_local;
        }
        if (rr.fit.best.empty()) {
          std::string why;
          for (const auto& m : rr.fit.models)
            if (!m.message.empty()) why += fmt::format("; {}: {}", model_name(m.kind), m.message);
          file.failures.push_back(r.where + fmt::format("run {}: no model converged{}", run.number, why));
        }
        report.runs.push_back(std::move(rr));
        ++p.runs_done;
        ++runs_done_in_file;
        p.bytes_done = bytes_before + file.bytes * runs_done_in_file / std::max<std::size_t>(runs_in_file, 1);
        if (progress) progress(p);
      }
    } sink(report, file, fi, options, progress, p, bytes_before);
    // J and K_b by the one rule (choose_bench_params): command line, else the bench's file,
    // else the log's CONFIG, else the lab's.
    OfflinePlan plan{options.read, options.bench, {}, {}, {}};
    plan.naming = &options.naming;
    plan.bench_file = [&](const OfflineRecording& r) -> const BenchFile* {
      const auto ref = options.references.find(report_bench(r));
      if (ref == options.references.end()) return nullptr;
      reference_used[static_cast<std::size_t>(std::distance(options.references.begin(), ref))] = true;
      return ref->second.bench ? &*ref->second.bench : nullptr;
    };
    walk_file(file.file, plan, sink);
    if (file.format == FileFormat::automatic) file.format = options.read.format;
    bytes_before += file.bytes;
    p.bytes_done = bytes_before;
    if (progress) progress(p);
  }
  std::size_t i = 0;
  for (const auto& [bench, ref] : options.references)
    if (!reference_used[i++])
      report.notes.push_back(fmt::format("bench config {} (bench {}) matches no bench in these files", ref.file, bench));
  summarize_session(report);
  return report;
}

}  // namespace spindown
