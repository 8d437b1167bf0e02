// The run detector says exactly what it said when its last speed-up was checked, on the sample
// sample data read as files and each damaged in the corpus's seven ways under varied options
// (tests/run_detector_corpus.hpp): every event and when it came, every Run field to the last bit,
// every diagnostic, and a hash of buffered()/state() after every sample. Together with
// test_run_detector_corpus.cpp (the same data plain and 400 generated recordings) this pins the
// detector's behaviour.
//
// The recorded hash is what the detector gives today and what the detector of 44f0366 gave (its
// copy: git show 1ebc11f:tests/reference_run_detector.hpp, which was also compared with today's
// event for event on 1,456 recordings and 2.06 M samples, plain and damaged). If this fails after
// a change to the detector, its output changed: a behaviour change, not a speed-up. If it fails
// after a change to the sample data or the damage, check the detector against a copy of itself
// from before the change (the corpus header takes any detector class), then record the new hash:
// SPINDOWN_PRINT_CORPUS_HASH=1 prints it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "run_detector_corpus.hpp"
#include "spindown/read_recording.hpp"

namespace spindown {
namespace {

// Recorded on 2026-11-25, when an asymptotic coast's floor that the flatness test cannot tell
// from its "zeros" lead-in's zero became that zero (viscous-only.tsv's runs). Before:
// 0xdfb42f4014578905.
// Re-recorded on 2026-11-25 with run finding scored against truth (see test_run_detector_corpus.cpp
// for what changed and why; a run cut short by a clock restart now says so as a warning). Before:
// 0xba8bc83497a25bed.
// Re-recorded on 2026-11-25 (late): the sample recordings are now data/ (made by data/make-samples),
// not a folder outside the repository; the detector is unchanged. Before: 0x8988ef6342a32a4b.
// Re-recorded on 2026-11-28: the floating pin became the handout's (data/seed-3v5-run2.tsv made
// again with the simulator's new open pin: a level in 0.5–2.5 V with mains hum, a connection
// after the cut, contact bounce), and the detector changed for it and for quiet converters (see
// test_run_detector_corpus.cpp); judged against truth in test_detection_truth and
// FindRuns.SampleLogsMatchTheirTruth. Before: 0xcee5a9288e1b65bf.
// Re-recorded on 2026-12-05: a coast longer than max_buffer is fitted up to it, not abandoned, and
// the bounds are said in a user's words (see test_run_detector_corpus.cpp). Before: 0x1082a88ee03b98c5.
constexpr std::uint64_t recorded_hash = 0x1d94bf84ac988c9full;

// Each recording of the sample data (data/) as read, then damaged in each of the corpus's ways.
std::vector<corpus::Case> plain_and_damaged() {
  std::vector<std::string> files;
  for (const auto& e : std::filesystem::directory_iterator(SPINDOWN_SAMPLE_DATA))
    if (e.is_regular_file() && (e.path().extension() == ".tsv" || e.path().extension() == ".txt"))
      files.push_back(e.path().string());
  std::sort(files.begin(), files.end());
  std::vector<corpus::Case> cases;
  std::mt19937_64 rng(7);
  for (const std::string& f : files) {
    for (Recording& r : read_recordings(f)) {
      r.source = std::filesystem::path(f).filename().string();
      for (int k = 0; k < 7; ++k) {
        corpus::Case c{fmt::format("{} damage {}", r.source, k), r, corpus::varied_options(k == 0 ? 0 : 3 * k + 1)};
        corpus::mangle(c.rec, k, rng);
        cases.push_back(std::move(c));
      }
    }
  }
  return cases;
}

TEST(RunDetectorCorpus, DamagedSharedDataGivesTheRecordedOutput) {
  const auto cases = plain_and_damaged();
  ASSERT_GT(cases.size(), 7u);  // data/ holds several recordings
  std::uint64_t h = 1469598103934665603ull;
  std::size_t samples = 0;
  for (const auto& c : cases) {
    samples += c.rec.size();
    h = corpus::fnv1a(h, c.name + "\n" + corpus::stream_events<RunDetector>(c.rec, c.opt));
  }
  if (std::getenv("SPINDOWN_PRINT_CORPUS_HASH"))
    std::printf("damaged sample data: %zu recordings, %zu samples, hash %016llx\n", cases.size(), samples,
                (unsigned long long)h);
  EXPECT_EQ(h, recorded_hash) << "the run detector's output changed (see the comment at the top of this file)";
}

}  // namespace
}  // namespace spindown
