#include "spindown/offline_pipeline.hpp"

#include <exception>
#include <fmt/format.h>

namespace spindown {

namespace {

std::string first_error(const Recording& rec) {
  for (const auto& d : rec.diagnostics)
    if (d.severity == Diagnostic::Severity::error) return d.message;
  return "no samples";
}

}  // namespace

void walk_file(const std::string& path, const OfflinePlan& plan, OfflineSink& sink) {
  try {
    std::vector<RecordingInfo> info;
    const std::vector<Recording> recordings = read_recordings(path, plan.read, &info);
    // Runs of every recording first, so a sink knows how many are coming.
    std::vector<Segmentation> segs;
    segs.reserve(recordings.size());
    std::size_t runs_found = 0;
    for (const Recording& rec : recordings) {
      segs.push_back(rec.empty() ? Segmentation{} : find_runs(rec));
      runs_found += segs.back().runs.size();
    }
    sink.file_read(recordings, info, runs_found);

    for (std::size_t k = 0; k < recordings.size(); ++k) {
      const Recording& rec = recordings[k];
      const RecordingInfo* about = k < info.size() ? &info[k] : nullptr;
      OfflineRecording r(path, rec, about);
      r.index = k;
      r.count = recordings.size();
      if (about) r.bench = about->bench;
      Diagnostic naming_problem;
      if (r.bench.empty() && plan.naming && plan.naming->active() &&
          !(about && about->format == FileFormat::lcm_log)) {
        const BenchName name = plan.naming->name(path, file_stem(path));
        r.bench = name.bench;
        r.student = name.student;
        if (!name.problem.empty())
          naming_problem = {Diagnostic::Severity::warning, path, 0, fmt::format("bench: {}", name.problem)};
      }
      if (recordings.size() > 1) r.where = fmt::format("{}: ", rec.source);
      if (plan.wanted && !plan.wanted(r)) continue;
      sink.recording(r);
      sink.diagnostics(r, OfflineSink::From::reader, rec.diagnostics);
      if (!naming_problem.message.empty()) sink.diagnostics(r, OfflineSink::From::naming, {&naming_problem, 1});
      if (rec.empty()) {
        sink.failure(&r, r.where + first_error(rec));
        continue;
      }
      r.bench_file = plan.bench_file ? plan.bench_file(r) : nullptr;
      std::vector<Diagnostic> config_problems;
      r.params = choose_bench_params(plan.bench, r.bench_file, config_bench_params(about, rec.source, config_problems));
      if (!config_problems.empty()) sink.diagnostics(r, OfflineSink::From::config, config_problems);
      const Segmentation& seg = segs[k];
      r.segmentation = &seg;
      sink.bench_chosen(r);
      if (!seg.diagnostics.empty()) sink.diagnostics(r, OfflineSink::From::run_finder, seg.diagnostics);
      if (seg.runs.empty()) {
        sink.failure(&r, r.where + fmt::format("no spin-down run found in {} samples", rec.size()));
        continue;
      }
      for (const Run& run : seg.runs) sink.run(r, run);
    }
  } catch (const std::exception& e) {
    sink.failure(nullptr, fmt::format("could not be processed: {}", e.what()));
  }
}

}  // namespace spindown
