#include "spindown/build_session_report.hpp"

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

}  // namespace

BenchReference bench_reference(const BenchFile& file) {
  BenchReference ref;
  ref.file = file.path;
  ref.health = file.health;
  if (file.sets_inertia || file.sets_kb) ref.bench = file;
  return ref;
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
  // The figure's samples are the fit's (outliers left out: the context around the run shows them).
  out.tau.assign(window.tau().begin(), window.tau().end());
  out.y.reserve(window.size());
  for (double y : window.y()) out.y.push_back(y + window.zero_level());
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
        if (r.info && file.format == file_format_name(FileFormat::automatic))
          file.format = std::string(file_format_name(r.info->format));
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
    if (file.format == file_format_name(FileFormat::automatic))
      file.format = std::string(file_format_name(options.read.format));
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
