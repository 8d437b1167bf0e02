// FitterCore: generated runs fed as samples_t batches give one fit per run with the bench's
// CONFIG (or the flagged default); caps and malformed input are counted and never touch the
// other benches' results; the same input gives the same numbers as find_runs + fit_run.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <cmath>
#include <cstring>
#include <map>
#include <string>
#include <vector>

#include "spindown/fit_message.hpp"
#include "spindown/fitter_core.hpp"
#include "spindown/message_decode.hpp"
#include "spindown/runs.hpp"
#include "spindown/synthetic_run.hpp"
#include "fitter_test_support.hpp"

namespace spindown {
namespace {

using namespace test;

TEST(FitterCore, OneFitPerRunWithTheBenchsConfigAndTheDefaultFlagged) {
  CollectingSink sink;
  FitterCore core({}, sink);
  const Stream s = make_stream(2, 7);
  core.on_config("withcfg", lab_config("withcfg", 2.0e-5), 1);
  std::int64_t utime = 10;
  feed(core, "withcfg", s, 5, utime);
  feed(core, "nocfg", s, 5, utime);
  core.finish(utime);

  const auto a = sink.of("withcfg"), b = sink.of("nocfg");
  ASSERT_EQ(a.size(), 2u);
  ASSERT_EQ(b.size(), 2u);
  EXPECT_EQ(a[0]->bench_source, "config");
  EXPECT_DOUBLE_EQ(a[0]->fit.bench.inertia_kg_m2, 2.0e-5);
  EXPECT_EQ(a[0]->fit.bench.inertia_source, "lab flywheel + rotor");
  EXPECT_NE(b[0]->bench_source.find("no CONFIG"), std::string::npos) << b[0]->bench_source;
  EXPECT_DOUBLE_EQ(b[0]->fit.bench.inertia_kg_m2, BenchParams{}.inertia_kg_m2);
  EXPECT_EQ(a[0]->fit.run.number, 1);
  EXPECT_EQ(a[1]->fit.run.number, 2);
  EXPECT_EQ(a[1]->first_seq, static_cast<std::int64_t>(a[1]->fit.run.cut_index));
  for (const auto* f : a) EXPECT_EQ(f->fit.best, "combined");
  // Friction scales with J: the same data with a larger J gives larger coefficients.
  const double c4a = a[0]->fit.model(ModelKind::combined)->param("c4")->value;
  const double c4b = b[0]->fit.model(ModelKind::combined)->param("c4")->value;
  EXPECT_NEAR(c4a / c4b, 2.0e-5 / BenchParams{}.inertia_kg_m2, 1e-6);
  EXPECT_EQ(core.counters().fits, 4);
  EXPECT_EQ(core.counters().decode_errors, 0);

  // The run's life: coasting, stopped, stopped (complete) per run.
  int coasting = 0, stopped = 0;
  for (const auto& r : sink.runs)
    if (r.bench == "withcfg") (r.state == run_t::STATE_COASTING ? coasting : stopped) += 1;
  EXPECT_EQ(coasting, 2);
  EXPECT_EQ(stopped, 4);
}

// A refit names J or K_b (spindown refit/export: --inertia…, a --bench-config file's [bench]):
// what it names wins over the CONFIG, each parameter on its own, and bench_source says so; the
// bench file's health references give each fit a verdict; nothing named is the live rule.
TEST(FitterCore, WhatARefitNamesWinsOverTheConfigAndIsSaid) {
  const Stream s = make_stream(1, 7);
  const auto run_with = [&](const FitterOptions& o) {
    CollectingSink sink;
    FitterCore core(o, sink);
    core.on_config("b1", lab_config("b1", 2.0e-5), 1);
    std::int64_t utime = 10;
    feed(core, "b1", s, 5, utime);
    core.finish(utime);
    const auto fits = sink.of("b1");
    EXPECT_EQ(fits.size(), 1u);
    return fits.empty() ? FitResult{} : *fits[0];
  };
  FitterOptions live;
  const FitResult plain = run_with(live);
  EXPECT_EQ(plain.bench_source, "config");
  EXPECT_DOUBLE_EQ(plain.fit.bench.inertia_kg_m2, 2.0e-5);
  EXPECT_FALSE(plain.health.has_value());

  FitterOptions flag;
  flag.named.given.inertia_kg_m2 = 3.0e-5;
  flag.named.given.inertia_source = "--inertia";
  flag.named.inertia_given = true;
  const FitResult by_flag = run_with(flag);
  EXPECT_DOUBLE_EQ(by_flag.fit.bench.inertia_kg_m2, 3.0e-5);
  EXPECT_DOUBLE_EQ(by_flag.fit.bench.kb_v_s_per_rad, lab_config("b1", 2.0e-5).kb_v_s_per_rad);  // K_b: still the CONFIG's
  EXPECT_EQ(by_flag.bench_source, "J: the command line (over the log's CONFIG: 2e-05 kg·m²); K_b: CONFIG");
  const double c4_plain = plain.fit.model(ModelKind::combined)->param("c4")->value;
  EXPECT_NEAR(by_flag.fit.model(ModelKind::combined)->param("c4")->value / c4_plain, 1.5, 1e-6);

  FitterOptions file;
  BenchFile b1;
  b1.path = "benches/b1.toml";
  b1.bench = "b1";
  b1.params.kb_v_s_per_rad = 0.009;
  b1.params.kb_source = "config file";
  b1.sets_kb = true;
  b1.health.baseline = HealthBaseline{1.8e-7, 2e-9, 1.14e-4, 4e-7, 0, 0, 3, "2024-09-14", 0, "test"};
  file.bench_files.emplace("b1", b1);
  file.health.emplace("b1", b1.health);
  file.bench_files.emplace("other", BenchFile{});  // another bench's file changes nothing here
  const FitResult by_file = run_with(file);
  EXPECT_DOUBLE_EQ(by_file.fit.bench.inertia_kg_m2, 2.0e-5);  // J: the CONFIG's
  EXPECT_DOUBLE_EQ(by_file.fit.bench.kb_v_s_per_rad, 0.009);
  EXPECT_NE(by_file.bench_source.find("K_b: bench file benches/b1.toml (over the log's CONFIG:"), std::string::npos)
      << by_file.bench_source;
  ASSERT_TRUE(by_file.health.has_value());
  EXPECT_TRUE(by_file.health->has_reference);
}

TEST(FitterCore, SameNumbersAsFindRunsAndFitRun) {
  const Stream s = make_stream(2, 11);
  Recording rec;
  for (std::size_t i = 0; i < s.t_us.size(); ++i) rec.push(double(s.t_us[i]) / 1e6, s.v[i]);
  const Segmentation seg = find_runs(rec);
  ASSERT_EQ(seg.runs.size(), 2u);

  CollectingSink sink;
  FitterCore core({}, sink);
  std::int64_t utime = 0;
  feed(core, "b", s, 3, utime);
  core.finish(utime);
  ASSERT_EQ(sink.fits.size(), 2u);
  for (std::size_t k = 0; k < 2; ++k) {
    FitOptions fo;
    const RunFit offline = fit_run(rec, seg.runs[k], fo);
    const RunFit& live = sink.fits[k].fit;
    EXPECT_EQ(run_fit_json(offline).dump(), run_fit_json(live).dump()) << "run " << k + 1;
  }
}

TEST(FitterCore, MalformedMessagesAreCountedAndOtherBenchesUnaffected) {
  const Stream s = make_stream(1, 3);
  CollectingSink clean_sink;
  {
    FitterCore clean({}, clean_sink);
    std::int64_t utime = 0;
    feed(clean, "good", s, 4, utime);
    clean.finish(utime);
  }
  ASSERT_EQ(clean_sink.fits.size(), 1u);

  CollectingSink sink;
  FitterCore core({}, sink);
  std::int64_t utime = 0, seq = 0;
  for (std::size_t i = 0; i < s.t_us.size(); i += 4) {
    const auto good = encode(batch("good", s, i, 4, std::int64_t(i)));
    utime += 80000;
    core.on_message("SPINDOWN.good.SAMPLE", good.data(), std::int64_t(good.size()), utime);
    // The bad bench interleaved: every kind of damage.
    samples_t m = batch("bad", s, i, 4, seq);
    seq += m.n;
    const std::size_t k = i / 4;
    if (k % 7 == 1) m.value[0] = std::nan("");
    if (k % 11 == 2) m.device_time_us[1] = m.device_time_us[0] - 1000;
    auto bytes = encode(m);
    core.on_message("SPINDOWN.bad.SAMPLE", bytes.data(), std::int64_t(bytes.size()), utime);
    if (k % 13 == 3) core.on_message("SPINDOWN.bad.SAMPLE", bytes.data(), std::int64_t(bytes.size()), utime);  // dup
    if (k % 17 == 4) seq += 3;  // gap
    if (k % 19 == 5) {
      const std::string junk = "not an lcm message at all";
      core.on_message("SPINDOWN.bad.SAMPLE", junk.data(), std::int64_t(junk.size()), utime);
    }
    if (k % 23 == 6) core.on_message("SPINDOWN.bad.SAMPLE", bytes.data(), std::int64_t(bytes.size() / 2), utime);
    if (k % 29 == 7) {
      std::vector<unsigned char> huge_n = bytes;
      // n sits after hash(8) utime(8) bench(4+len+1) seq(8) epoch(4) quantity(1)
      const std::size_t at = 8 + 8 + 4 + 4 + 8 + 4 + 1;
      huge_n[at] = 0x7f;
      core.on_message("SPINDOWN.bad.SAMPLE", huge_n.data(), std::int64_t(huge_n.size()), utime);
    }
    if (k % 31 == 8) core.on_message("SPINDOWN.bad bench!.SAMPLE", bytes.data(), std::int64_t(bytes.size()), utime);
  }
  core.finish(utime);
  const FitterCounters& c = core.counters();
  EXPECT_GT(c.nan_values, 0);
  EXPECT_GT(c.time_backwards, 0);
  EXPECT_GT(c.duplicates, 0);
  EXPECT_GT(c.seq_gaps, 0);
  EXPECT_GE(c.decode_errors, 3);
  EXPECT_GT(c.invalid_bench, 0);
  EXPECT_FALSE(core.last_error().empty());
  const auto good = sink.of("good");
  ASSERT_EQ(good.size(), 1u);
  EXPECT_EQ(run_fit_json(good[0]->fit).dump(), run_fit_json(clean_sink.fits[0].fit).dump());
  EXPECT_EQ(sink.of("bad").size(), 1u);  // damaged, yet its run is still found and fitted
  const status_t st = core.make_status(utime, "fitter", "host", 1, "running", 1.0);
  EXPECT_EQ(st.ncounters, static_cast<std::int32_t>(st.counter_name.size()));
  EXPECT_FALSE(st.last_error.empty());
}

TEST(FitterCore, BenchesAreCappedAndTheLeastRecentlyActiveEvicted) {
  CollectingSink sink;
  FitterOptions o;
  o.max_benches = 4;
  FitterCore core(o, sink);
  const Stream s = make_stream(1, 5);
  // A bench id new every second (within the admission rate): each takes an idle bench's place.
  for (int i = 0; i < 100; ++i) {
    const samples_t m = batch("stray" + std::to_string(i), s, 0, 2, 0);
    core.on_samples(m.bench, m, std::int64_t(i) * 1'000'000);
  }
  EXPECT_LE(core.bench_count(), 4u);
  EXPECT_EQ(core.counters().dropped_benches, 96);
  EXPECT_EQ(core.counters().benches_refused, 0);
  EXPECT_NE(core.last_error().find("evicted"), std::string::npos);
  // Faster than admit_rate_hz: past the bucket's max_benches, new ids are refused, not admitted.
  for (int i = 0; i < 100; ++i) {
    const samples_t m = batch("burst" + std::to_string(i), s, 0, 2, 0);
    core.on_samples(m.bench, m, 100'000'000 + i);
  }
  EXPECT_EQ(core.counters().dropped_benches, 100);
  EXPECT_EQ(core.counters().benches_refused, 96);
  EXPECT_NE(core.last_error().find("more than 20 new benches per second"), std::string::npos) << core.last_error();
}

TEST(FitterCore, AFloodingBenchIsCappedAndCounted) {
  CollectingSink sink;
  FitterOptions o;
  o.max_rate_hz = 100;
  o.burst_s = 1.0;
  FitterCore core(o, sink);
  const Stream s = make_stream(1, 5);
  // 1000 samples within 0.1 s of host time: the bucket holds 100.
  for (int i = 0; i < 100; ++i) {
    const samples_t m = batch("flood", s, std::size_t(i) * 10, 10, i * 10);
    core.on_samples("flood", m, 1000 * i);
  }
  EXPECT_GT(core.counters().flood_drops, 800);
  EXPECT_LT(core.counters().samples, 200);
}

TEST(FitterCore, ARunThatNeverStopsIsClosedWithinMaxCoast) {
  CollectingSink sink;
  FitterOptions o;
  o.runs.max_coast_s = 5.0;
  FitterCore core(o, sink);
  // A slow linear decline that would take minutes to stop.
  samples_t m{};  // every field zero (lcm-gen types leave them uninitialised)
  m.quantity = samples_t::QUANTITY_BACK_EMF_V;
  m.bench = "slow";
  std::int64_t seq = 0;
  for (int i = 0; i < 3000; ++i) {
    m = batch("slow", Stream{{std::int64_t(i) * 20000}, {i < 150 ? 0.0 : 3.0 - 0.002 * (i - 150)}}, 0, 1, seq++);
    core.on_samples("slow", m, i);
  }
  EXPECT_LE(core.buffered_samples(), 2 * 3000u);
  bool abandoned = false;
  for (const auto& r : sink.runs) abandoned |= r.state == run_t::STATE_ABANDONED;
  EXPECT_TRUE(abandoned);
  ASSERT_GE(sink.fits.size(), 1u);
  EXPECT_FALSE(sink.fits[0].fit.run.stopped);
}

TEST(FitterCore, OptionsSayWhatIsWrong) {
  FitterOptions o;
  std::string why;
  EXPECT_TRUE(o.is_valid(&why));
  o.bench_regex = "(";
  EXPECT_FALSE(o.is_valid(&why));
  EXPECT_NE(why.find("regex"), std::string::npos);
  o = {};
  o.max_benches = 0;
  EXPECT_FALSE(o.is_valid(&why));
}

namespace {
// One line per fit (bench, run, first and last seq, the first model's RMSE): what two ways of
// feeding a core must agree on.
std::vector<std::string> fit_lines(const CollectingSink& sink) {
  std::vector<std::string> out;
  for (const auto& f : sink.fits)
    out.push_back(fmt::format("{} {} {} {} {}", f.bench, f.fit.run.number, f.first_seq, f.last_seq,
                              f.fit.best.empty() ? 0.0 : f.fit.models.front().rmse));
  return out;
}
}  // namespace

// The log reader's in-place view and the decoded samples_t give the same runs, numbers and
// counters, with benches interleaved (the bench guess) and evicted (the guess forgets them).
TEST(FitterCore, SamplesViewAndDecodedMessageGiveTheSameResults) {
  const Stream a = make_stream(2, 11), b = make_stream(1, 21), c = make_stream(1, 31);
  auto run = [&](bool view, std::size_t max_benches) {
    CollectingSink sink;
    FitterOptions o;
    o.max_benches = max_benches;
    FitterCore core(o, sink);
    const std::pair<const char*, const Stream*> benches[] = {{"a", &a}, {"b", &b}, {"c", &c}};
    std::int64_t utime = 0;
    for (std::size_t i = 0; i < a.t_us.size(); ++i)
      for (const auto& [id, s] : benches) {
        if (i >= s->t_us.size()) continue;
        const samples_t m = batch(id, *s, i, 1, static_cast<std::int64_t>(i));
        utime += 5000;
        if (view) {
          const auto bytes = encode(m);
          SamplesView v;
          EXPECT_TRUE(view_samples_message(v, bytes.data(), static_cast<std::int64_t>(bytes.size())));
          core.on_samples(id, v, utime);
        } else {
          core.on_samples(id, m, utime);
        }
      }
    core.finish(utime);
    std::vector<std::string> out = fit_lines(sink);
    out.push_back(fmt::format("{} {} {}", core.counters().samples, core.counters().dropped_benches, sink.runs.size()));
    return out;
  };
  const auto decoded = run(false, 256);
  EXPECT_GE(decoded.size(), 5u);  // four runs and the counters
  EXPECT_EQ(run(true, 256), decoded);
  EXPECT_EQ(run(true, 2), run(false, 2));  // three benches, two held: evictions all along
}

// Benches found by the reader's channel number (refit) give what finding them by name gives,
// with benches interleaved, evicted and filtered, and ids that are negative or out of range.
TEST(FitterCore, ChannelIdsGiveTheSameResultsAsBenchNames) {
  const Stream a = make_stream(2, 12), b = make_stream(1, 22), c = make_stream(1, 32);
  auto run = [&](bool by_id, std::size_t max_benches) {
    CollectingSink sink;
    FitterOptions o;
    o.max_benches = max_benches;
    o.bench_regex = "[abc]";
    FitterCore core(o, sink);
    const std::pair<const char*, const Stream*> benches[] = {{"a", &a}, {"b", &b}, {"c", &c}, {"z", &c}};
    const std::int32_t ids[] = {3, 0, FitterCore::max_channel_ids + 5, 7};  // "z" is filtered
    std::int64_t utime = 0;
    for (std::size_t i = 0; i < a.t_us.size(); ++i)
      for (std::size_t k = 0; k < 4; ++k) {
        const auto& [id, s] = benches[k];
        if (i >= s->t_us.size()) continue;
        const auto bytes = encode(batch(id, *s, i, 1, static_cast<std::int64_t>(i)));
        SamplesView v;
        EXPECT_TRUE(view_samples_message(v, bytes.data(), static_cast<std::int64_t>(bytes.size())));
        utime += 5000;
        if (by_id)
          core.on_samples(i % 97 == 5 ? -1 : ids[k], id, v, utime);
        else
          core.on_samples(id, v, utime);
      }
    core.finish(utime);
    std::vector<std::string> out = fit_lines(sink);
    const FitterCounters& n = core.counters();
    out.push_back(fmt::format("{} {} {} {} {}", n.samples, n.sample_messages, n.dropped_benches, n.filtered,
                              sink.runs.size()));
    return out;
  };
  const auto by_name = run(false, 256);
  EXPECT_GE(by_name.size(), 5u);
  EXPECT_EQ(run(true, 256), by_name);
  EXPECT_EQ(run(true, 2), run(false, 2));  // evictions all along: a channel's bench is found anew
}

}  // namespace
}  // namespace spindown
