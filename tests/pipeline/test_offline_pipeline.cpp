// walk_file (offline_pipeline.hpp): the one offline path of fit, explain, baseline and report.
// A two-bench LCM log (bench "a": a whole synthetic run and a CONFIG; bench "b": a CONFIG and
// no samples) and a sample text file, walked with a sink that records every call.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <lcm/lcm-cpp.hpp>
#include <string>
#include <unistd.h>
#include <vector>

#include "spindown/offline_pipeline.hpp"
#include "spindown/synthetic_run.hpp"

#include "lab_messages.hpp"
#include "lcm_log_events.hpp"

using namespace spindown;

namespace {

struct Call {
  std::string what;   // "file_read", "recording", "reader", "config", "run_finder", "failure", "bench", "run"
  std::string bench;  // the recording's bench ("" for text or the whole file)
  std::string text;   // failure: why; run: its number
};

struct RecordingSink : OfflineSink {
  std::vector<Call> calls;
  std::vector<BenchParams> params;  // per run
  std::vector<std::string> students;  // per recording
  std::vector<Diagnostic> naming_problems;
  std::size_t runs_found = 0;
  void file_read(std::span<const Recording>, std::span<const RecordingInfo>, std::size_t n) override {
    runs_found = n;
    calls.push_back({"file_read", "", ""});
  }
  void recording(const OfflineRecording& r) override {
    calls.push_back({"recording", r.bench, r.where});
    students.push_back(r.student);
  }
  void diagnostics(const OfflineRecording& r, From from, std::span<const Diagnostic> diags) override {
    calls.push_back({from == From::reader   ? "reader"
                     : from == From::naming ? "naming"
                     : from == From::config ? "config"
                                            : "run_finder",
                     r.bench, ""});
    if (from == From::naming)
      for (const auto& d : diags) naming_problems.push_back(d);
  }
  void failure(const OfflineRecording* r, std::string why) override {
    calls.push_back({"failure", r ? r->bench : "", why});
  }
  void bench_chosen(const OfflineRecording& r) override {
    EXPECT_NE(r.segmentation, nullptr);
    calls.push_back({"bench", r.bench, ""});
  }
  void run(const OfflineRecording& r, const Run& run) override {
    calls.push_back({"run", r.bench, std::to_string(run.number)});
    params.push_back(r.params);
  }
  std::vector<std::string> sequence() const {
    std::vector<std::string> out;
    for (const auto& c : calls) out.push_back(c.what + (c.bench.empty() ? "" : ":" + c.bench));
    return out;
  }
};

using spindown::testing::write_event;

samples_t one_sample(const std::string& bench, std::int64_t seq, std::int64_t t_us, double value) {
  samples_t m{};
  m.bench = bench;
  m.seq = seq;
  m.quantity = samples_t::QUANTITY_BACK_EMF_V;
  m.n = 1;
  m.device_time_us = {t_us};
  m.host_time_us = {0};
  m.value = {value};
  m.raw_adc = {-1};
  return m;
}

// Bench "b" comes first (a CONFIG, then samples that are all NaN: no usable sample); bench "a"
// has a CONFIG and a whole run.
std::string two_bench_log() {
  const std::string path = ::testing::TempDir() + "spindown_offline_" + std::to_string(::getpid()) + ".lcm";
  const SyntheticRun run = make_synthetic_run(SyntheticRunSpec{});
  lcm::LogFile log(path, "w");
  EXPECT_TRUE(log.good());
  write_event(log, "SPINDOWN.b.CONFIG", test::lab_config("b", 3e-5, 0.02), 1);
  write_event(log, "SPINDOWN.a.CONFIG", test::lab_config("a", 2e-5, 0.01), 2);
  for (int i = 0; i < 3; ++i)
    write_event(log, "SPINDOWN.b.SAMPLE", one_sample("b", i, 20000 * (i + 1), std::nan("")), 3 + i);
  for (std::size_t i = 0; i < run.t_ms.size(); ++i) {
    const auto seq = static_cast<std::int64_t>(i);
    write_event(log, "SPINDOWN.a.SAMPLE", one_sample("a", seq, std::llround(run.t_ms[i] * 1000), run.volts[i]),
                10 + seq);
  }
  return path;
}

}  // namespace

TEST(OfflinePipeline, EveryRecordingInOrderReaderConfigRunsThenTheRuns) {
  const std::string log = two_bench_log();
  RecordingSink sink;
  walk_file(log, OfflinePlan{}, sink);
  const std::vector<std::string> expected = {"file_read",  "recording:b", "reader:b",     "failure:b",
                                             "recording:a", "reader:a",   "bench:a",      "run:a"};
  auto seq = sink.sequence();
  // The run finder may or may not have notes about bench a's run; nothing else may differ.
  std::erase(seq, "run_finder:a");
  EXPECT_EQ(seq, expected);
  EXPECT_EQ(sink.runs_found, 1u);
  // Several recordings in one file: each failure and recording names its source.
  EXPECT_NE(sink.calls[1].text.find("SPINDOWN.b.SAMPLE: "), std::string::npos) << sink.calls[1].text;
  EXPECT_NE(sink.calls[3].text.find("SPINDOWN.b.SAMPLE: "), std::string::npos) << sink.calls[3].text;
  // J and K_b from bench a's own CONFIG, never b's.
  ASSERT_EQ(sink.params.size(), 1u);
  EXPECT_DOUBLE_EQ(sink.params[0].inertia_kg_m2, 2e-5);
  EXPECT_DOUBLE_EQ(sink.params[0].kb_v_s_per_rad, 0.01);
  std::filesystem::remove(log);
}

TEST(OfflinePipeline, TheOneRuleForJAndKb) {
  const std::string log = two_bench_log();
  BenchFile file;
  file.bench = "a";
  file.params.inertia_kg_m2 = 4e-5;
  file.params.inertia_source = "bench file";
  file.sets_inertia = true;  // the file gives J only: K_b still comes from the CONFIG
  OfflinePlan plan;
  plan.bench_file = [&](const OfflineRecording& r) { return r.bench == "a" ? &file : nullptr; };
  RecordingSink with_file;
  walk_file(log, plan, with_file);
  ASSERT_EQ(with_file.params.size(), 1u);
  EXPECT_DOUBLE_EQ(with_file.params[0].inertia_kg_m2, 4e-5);  // the bench file over the CONFIG
  EXPECT_DOUBLE_EQ(with_file.params[0].kb_v_s_per_rad, 0.01);  // the CONFIG over the default

  plan.bench.given.kb_v_s_per_rad = 0.005;  // the command line over everything
  plan.bench.kb_given = true;
  RecordingSink with_flag;
  walk_file(log, plan, with_flag);
  ASSERT_EQ(with_flag.params.size(), 1u);
  EXPECT_DOUBLE_EQ(with_flag.params[0].inertia_kg_m2, 4e-5);
  EXPECT_DOUBLE_EQ(with_flag.params[0].kb_v_s_per_rad, 0.005);
  std::filesystem::remove(log);
}

TEST(OfflinePipeline, AnUnwantedBenchIsNeverSeen) {
  const std::string log = two_bench_log();
  OfflinePlan plan;
  plan.wanted = [](const OfflineRecording& r) { return r.bench == "a"; };
  RecordingSink sink;
  walk_file(log, plan, sink);
  for (const auto& c : sink.calls) EXPECT_NE(c.bench, "b") << c.what;
  EXPECT_EQ(sink.params.size(), 1u);
  std::filesystem::remove(log);
}

TEST(OfflinePipeline, ATextFileIsOneRecordingWithoutPrefix) {
  RecordingSink sink;
  walk_file(std::string(SPINDOWN_SAMPLE_DATA) + "/seed-3v-run1.tsv", OfflinePlan{}, sink);
  std::vector<std::string> seq = sink.sequence();
  std::erase(seq, "run_finder");
  EXPECT_EQ(seq, (std::vector<std::string>{"file_read", "recording", "reader", "bench", "run"}));
  EXPECT_EQ(sink.calls[1].text, "");  // where: no prefix for a file of one recording
  ASSERT_EQ(sink.params.size(), 1u);
  EXPECT_EQ(sink.params[0].inertia_source, "lab default");
}

TEST(OfflinePipeline, AClassNamingGivesATextFileItsBenchAndStudent) {
  const std::string file = std::string(SPINDOWN_SAMPLE_DATA) + "/seed-3v-run1.tsv";
  const BenchNaming naming("", "(seed)-(3v)");
  OfflinePlan plan;
  plan.naming = &naming;
  RecordingSink sink;
  walk_file(file, plan, sink);
  std::vector<std::string> seq = sink.sequence();
  std::erase(seq, "run_finder:seed");
  EXPECT_EQ(seq, (std::vector<std::string>{"file_read", "recording:seed", "reader:seed", "bench:seed", "run:seed"}));
  EXPECT_EQ(sink.students, (std::vector<std::string>{"3v"}));
  EXPECT_TRUE(sink.naming_problems.empty());

  // A name the pattern does not match: the file's own name, and a warning naming the file.
  const BenchNaming other("", "(bench[0-9]+)");
  plan.naming = &other;
  RecordingSink missed;
  walk_file(file, plan, missed);
  EXPECT_EQ(missed.calls.at(1).bench, "seed-3v-run1");
  ASSERT_EQ(missed.naming_problems.size(), 1u);
  EXPECT_EQ(missed.naming_problems[0].severity, Diagnostic::Severity::warning);
  EXPECT_EQ(missed.naming_problems[0].source, file);
  EXPECT_NE(missed.naming_problems[0].message.find("does not match --bench-pattern"), std::string::npos);
}

TEST(OfflinePipeline, AMissingFileIsOneFailureNamingIt) {
  RecordingSink sink;
  walk_file("/nonexistent/run.tsv", OfflinePlan{}, sink);
  std::string failures;
  for (const auto& c : sink.calls)
    if (c.what == "failure") failures += c.text + "\n";
  EXPECT_NE(failures.find("/nonexistent/run.tsv"), std::string::npos) << failures;
  EXPECT_TRUE(sink.params.empty());
}
