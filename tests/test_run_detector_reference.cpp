// The optimised run detector says exactly what the reference copy of the old one says
// (tests/reference_run_detector.hpp): every event, when it came, every Run field to the last
// bit, every diagnostic, and buffered()/state() after every sample.
//
// By default: the shared sample data, each also damaged in the corpus's seven ways under varied
// options, and generated recordings. More on request:
//   SPINDOWN_DETECTOR_CHECK_DIR=/tmp/prof/runs   every .txt/.tsv file in it, plain and damaged;
//   SPINDOWN_DETECTOR_CHECK_GENERATED=2000       that many generated recordings.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "reference_run_detector.hpp"
#include "run_detector_corpus.hpp"
#include "spindown/read_recording.hpp"

namespace spindown {
namespace {

int env_int(const char* name, int fallback) {
  const char* s = std::getenv(name);
  return s && *s ? std::atoi(s) : fallback;
}

// Each recording as read, then damaged in each of the corpus's ways with varied options.
std::vector<corpus::Case> plain_and_damaged(const std::vector<std::string>& files) {
  std::vector<corpus::Case> cases;
  std::mt19937_64 rng(7);
  for (const std::string& f : files) {
    for (Recording& r : read_recordings(f)) {
      r.source = std::filesystem::path(f).filename().string();
      for (int k = 0; k < 7; ++k) {
        corpus::Case c{fmt::format("{} damage {}", f, k), r, corpus::varied_options(k == 0 ? 0 : 3 * k + 1)};
        corpus::mangle(c.rec, k, rng);
        cases.push_back(std::move(c));
      }
    }
  }
  return cases;
}

std::vector<std::string> files_in(const std::string& dir) {
  std::vector<std::string> files;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    if (e.is_regular_file() && (e.path().extension() == ".tsv" || e.path().extension() == ".txt"))
      files.push_back(e.path().string());
  std::sort(files.begin(), files.end());
  return files;
}

struct Tally {
  std::size_t recordings = 0, samples = 0, mismatches = 0;
};

void compare(const std::vector<corpus::Case>& cases, Tally& tally) {
  for (const auto& c : cases) {
    const std::string now = corpus::stream_events<RunDetector>(c.rec, c.opt);
    const std::string old = corpus::stream_events<reference::RunDetector>(c.rec, c.opt);
    ++tally.recordings;
    tally.samples += c.rec.size();
    if (now != old) {
      ++tally.mismatches;
      ADD_FAILURE() << c.name << ": the detector's output differs from the reference\nnow:\n"
                    << now << "reference:\n"
                    << old;
    }
  }
}

TEST(RunDetectorReference, SameOutputOnSharedDataAndDamagedCopies) {
  std::vector<std::string> files = files_in(SPINDOWN_SHARED_DATA);
  if (const char* dir = std::getenv("SPINDOWN_DETECTOR_CHECK_DIR")) {
    const auto more = files_in(dir);
    files.insert(files.end(), more.begin(), more.end());
  }
  Tally tally;
  compare(plain_and_damaged(files), tally);
  std::printf("reference check: %zu recordings, %zu samples, %zu mismatches\n", tally.recordings, tally.samples,
              tally.mismatches);
  EXPECT_GT(tally.recordings, 0u);
}

TEST(RunDetectorReference, SameOutputOnGeneratedRecordings) {
  // The corpus's generator: beyond its first 400 these are recordings the corpus hash does not cover.
  const int generated = env_int("SPINDOWN_DETECTOR_CHECK_GENERATED", 300);
  Tally tally;
  compare(corpus::make_cases(SPINDOWN_SHARED_DATA, generated), tally);
  std::printf("reference check: %zu recordings, %zu samples, %zu mismatches\n", tally.recordings, tally.samples,
              tally.mismatches);
  EXPECT_GT(tally.recordings, 0u);
}

}  // namespace
}  // namespace spindown
