#pragma once
// The offline path, written once: a file -> its recordings (one per bench) -> J and K_b by the
// one rule (choose_bench_params: command line, else the bench's file, else the log's CONFIG,
// else the lab's) -> the runs -> the command's per-run work. spindown fit, explain, baseline
// and report walk their files through walk_file; what each does with a run, and how it reports,
// is its sink's. Logs refitted as the live fitter saw them take log_refit.hpp instead (the live
// rule: CONFIG, else the fitter's defaults), so that refit equals live.
#include <cstddef>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "spindown/bench.hpp"
#include "spindown/bench_file.hpp"
#include "spindown/bench_naming.hpp"
#include "spindown/read_recording.hpp"
#include "spindown/recording.hpp"
#include "spindown/runs.hpp"

namespace spindown {

// One bench's recording of a file, as walk_file hands it to the sink.
struct OfflineRecording {
  OfflineRecording(const std::string& file, const Recording& rec, const RecordingInfo* found)
      : path(file), recording(rec), info(found) {}
  const std::string& path;         // the file
  const Recording& recording;
  const RecordingInfo* info;       // what read_recordings found beside it (nullptr: nothing)
  std::size_t index = 0, count = 1;  // its place among the file's recordings
  std::string bench;               // an LCM log's bench id; a text file's by the plan's naming, else ""
  std::string student;             // a text file's student, when the roster or pattern names one
  std::string where;               // "SOURCE: " when the file holds several recordings, else ""
  // Set once the recording has samples, before its runs:
  const BenchFile* bench_file = nullptr;  // the plan's bench file for it (nullptr: none)
  BenchParams params;                     // J and K_b by choose_bench_params
  const Segmentation* segmentation = nullptr;
};

struct OfflinePlan {
  ReadOptions read;
  BenchChoice bench;  // the command line's J and K_b
  // The bench file of a recording (nullptr: none). Unset: none for any.
  std::function<const BenchFile*(const OfflineRecording&)> bench_file;
  // Which bench a text file is from (roster, file-name pattern, --bench). nullptr or inactive: text
  // files name no bench. A file it cannot name is reported under its file name, with a warning.
  const BenchNaming* naming = nullptr;
  // Whether a recording is wanted at all (baseline: one bench of a log). Unset: all.
  std::function<bool(const OfflineRecording&)> wanted;
};

// What a command does along the path. Calls come in file order: file_read once, then per
// recording: recording, its diagnostics (the reader's, then the bench naming's, then the CONFIG's
// problems, then the run finder's), and either one failure or bench_chosen and its runs.
class OfflineSink {
 public:
  virtual ~OfflineSink() = default;
  // The file's recordings and what was found beside them, each already segmented: runs_found
  // runs in all.
  virtual void file_read(std::span<const Recording> recordings, std::span<const RecordingInfo> info,
                         std::size_t runs_found) {
    (void)recordings, (void)info, (void)runs_found;
  }
  virtual void recording(const OfflineRecording& r) { (void)r; }
  enum class From { reader, naming, config, run_finder };
  virtual void diagnostics(const OfflineRecording& r, From from, std::span<const Diagnostic> diags) = 0;
  // Why a recording (r) or the whole file (r == nullptr) gave no runs, prefixed by r->where:
  // "no samples" or the reader's first error, "no spin-down run found in N samples",
  // "could not be processed: …".
  virtual void failure(const OfflineRecording* r, std::string why) = 0;
  // J and K_b are chosen and the runs found; before the first run.
  virtual void bench_chosen(const OfflineRecording& r) { (void)r; }
  virtual void run(const OfflineRecording& r, const Run& run) = 0;
};

// Never throws for bad input or a failing run: an exception along the path is one failure
// "could not be processed: …" and the file's walk ends there.
void walk_file(const std::string& path, const OfflinePlan& plan, OfflineSink& sink);

}  // namespace spindown
