// ShortNameCache (core/base/include/spindown/short_name_cache.hpp) and the two lookups that use it
// per message: LcmLogReader's channel and FitterCore's bench. With more names than slots (so
// names share slots and evict each other) and names in random order, every event must still get
// its own channel's id, bench and kind, and every bench its own runs.
#include <gtest/gtest.h>

#include <fmt/format.h>
#include <lcm/lcm-cpp.hpp>

#include <cmath>
#include <cstdint>
#include <map>
#include <random>
#include <set>
#include <string>
#include <unistd.h>
#include <vector>

#include "spindown/fitter_core.hpp"
#include "spindown/lcm_log_reader.hpp"
#include "spindown/short_name_cache.hpp"
#include "spindown/synthetic_run.hpp"

namespace spindown {
namespace {

TEST(ShortNameCache, SlotsAreStableInRangeAndForgotten) {
  using Cache = ShortNameCache<const int, 6>;
  Cache cache;
  const int a = 1, b = 2;
  std::set<std::size_t> used;
  for (int i = 0; i < 1000; ++i) {
    const std::string name = fmt::format("SPINDOWN.bench{:03d}.SAMPLE", i);
    const std::size_t slot = Cache::index(name);
    EXPECT_LT(slot, 64u);
    EXPECT_EQ(slot, Cache::index(std::string(name)));  // the bytes, not the address
    used.insert(slot);
  }
  EXPECT_GT(used.size(), 48u);  // names differing in one digit spread over the slots
  for (std::size_t n = 0; n < 20; ++n) EXPECT_LT(Cache::index(std::string(n, 'x')), 64u);

  // Two names sharing a slot: the later entry replaces the earlier one there. forget() empties
  // only the slots holding the entry it is given.
  std::string other;
  for (int i = 0; other.empty(); ++i)
    if (const std::string name = fmt::format("n{}", i); name != "one" && Cache::index(name) == Cache::index("one"))
      other = name;
  const int c = 3;
  std::string apart = "two";
  for (int i = 0; Cache::index(apart) == Cache::index("one"); ++i) apart = fmt::format("m{}", i);
  cache.slot("one") = &a;
  cache.slot(apart) = &c;
  EXPECT_EQ(cache.slot("one"), &a);
  cache.slot(other) = &b;
  EXPECT_EQ(cache.slot("one"), &b);
  cache.forget(&b);
  EXPECT_EQ(cache.slot("one"), nullptr);
  EXPECT_EQ(cache.slot(apart), &c);
  cache.forget(&c);
  EXPECT_EQ(cache.slot(apart), nullptr);
}

std::vector<std::uint8_t> encode_samples(const std::string& bench, std::int64_t seq) {
  samples_t m{};  // every field zero (lcm-gen types leave them uninitialised)
  m.bench = bench;
  m.seq = seq;
  m.n = 1;
  m.quantity = samples_t::QUANTITY_BACK_EMF_V;
  m.device_time_us = {seq * 1000};
  m.host_time_us = {0};
  m.value = {1.5};
  m.raw_adc = {-1};
  std::vector<std::uint8_t> buf(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(buf.data(), 0, static_cast<int>(buf.size()));
  return buf;
}

// 300 channel names (more than the 64 cache slots and the reader's 256 ids), in random order.
TEST(LcmLogReaderChannels, ManyChannelsInRandomOrderKeepTheirIdsBenchesAndKinds) {
  const std::string path =
      ::testing::TempDir() + "spindown_name_cache_" + std::to_string(::getpid()) + ".lcm";
  std::vector<std::string> names;
  for (int i = 0; i < 300; ++i)
    names.push_back(i % 3 == 2 ? fmt::format("OTHER.{}", i) : fmt::format("SPINDOWN.b{}.SAMPLE", i));
  std::mt19937 rng(7);
  std::vector<std::size_t> order;
  for (int k = 0; k < 6000; ++k) order.push_back(k < 300 ? static_cast<std::size_t>(k) : rng() % names.size());
  {
    lcm::LogFile log(path, "w");
    ASSERT_TRUE(log.good());
    std::int64_t seq = 0;
    for (std::size_t i : order) {
      auto bytes = encode_samples(fmt::format("b{}", i), ++seq);
      lcm::LogEvent e;
      e.eventnum = 0;
      e.timestamp = 1000 + seq;
      e.channel = names[i];
      e.datalen = static_cast<std::int32_t>(bytes.size());
      e.data = bytes.data();
      ASSERT_EQ(log.writeEvent(&e), 0);
    }
  }
  LcmLogReader reader(path, LcmSamples::view_only);
  ASSERT_TRUE(reader.good());
  LcmLogEvent ev;
  std::map<std::string, std::int32_t> ids;
  std::size_t k = 0;
  for (; reader.next(ev); ++k) {
    ASSERT_LT(k, order.size());
    const std::size_t i = order[k];
    ASSERT_EQ(ev.channel, names[i]);
    if (i % 3 == 2) {
      EXPECT_EQ(ev.kind, LcmLogEvent::Kind::other);
      EXPECT_EQ(ev.bench, "");
    } else {
      ASSERT_EQ(ev.kind, LcmLogEvent::Kind::samples) << ev.problem;
      EXPECT_EQ(ev.bench, fmt::format("b{}", i));
      EXPECT_EQ(ev.samples_view.bench, ev.bench);
    }
    // The first 256 distinct names keep one id each; later ones have none.
    if (i < LcmLogReader::max_channel_ids) {
      auto [it, fresh] = ids.emplace(names[i], ev.channel_id);
      EXPECT_EQ(ev.channel_id, it->second) << names[i];
      if (fresh) {
        EXPECT_EQ(ev.channel_id, static_cast<std::int32_t>(i));
      }
    } else {
      EXPECT_EQ(ev.channel_id, -1) << names[i];
    }
  }
  EXPECT_EQ(k, order.size());
  ::unlink(path.c_str());
}

struct FitList : FitterSink {
  std::map<std::string, std::vector<std::string>> by_bench;
  void run_changed(const run_t&) override {}
  void fit_ready(const FitResult& r) override {
    by_bench[r.bench].push_back(fmt::format("{} {} {} {:.12g}", r.fit.run.number, r.first_seq, r.last_seq,
                                            r.fit.best.empty() ? 0.0 : r.fit.models.front().rmse));
  }
};

// 90 benches (more than the cache's slots) interleaved at random give each bench the runs it
// gives alone.
TEST(FitterCoreBenches, ManyBenchesInRandomOrderEachGetTheirOwnRuns) {
  SyntheticRunSpec spec;
  spec.seed = 5;
  const SyntheticRun run = make_synthetic_run(spec);
  std::vector<std::uint8_t> bytes;  // the latest message's encoding, which its view reads
  auto message = [&](const std::string& bench, std::size_t i) {
    SamplesView v;
    samples_t m{};  // every field zero (lcm-gen types leave them uninitialised)
    m.bench = bench;
    m.seq = static_cast<std::int64_t>(i);
    m.n = 1;
    m.quantity = samples_t::QUANTITY_BACK_EMF_V;
    m.device_time_us = {std::llround(run.t_ms[i] * 1000)};
    m.host_time_us = {0};
    m.value = {run.volts[i]};
    m.raw_adc = {-1};
    bytes.resize(static_cast<std::size_t>(m.getEncodedSize()));
    m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
    EXPECT_TRUE(view_samples_message(v, bytes.data(), static_cast<std::int64_t>(bytes.size())));
    return v;
  };
  FitterOptions o;
  o.max_rate_hz = 0;
  FitList alone;
  {
    FitterCore core(o, alone);
    for (std::size_t i = 0; i < run.t_ms.size(); ++i) core.on_samples("solo", message("solo", i), 1000 + i);
    core.finish(0);
  }
  ASSERT_EQ(alone.by_bench["solo"].size(), 1u);

  constexpr int benches = 90;
  FitList mixed;
  FitterCore core(o, mixed);
  std::vector<std::size_t> next(benches, 0);
  std::mt19937 rng(11);
  std::int64_t utime = 0;
  for (std::size_t left = benches * run.t_ms.size(); left > 0; --left) {
    std::size_t b = rng() % benches;
    while (next[b] == run.t_ms.size()) b = (b + 1) % benches;
    const std::string id = fmt::format("bench{:02d}", b);
    core.on_samples(id, message(id, next[b]++), ++utime);
  }
  core.finish(utime);
  EXPECT_EQ(core.bench_count(), static_cast<std::size_t>(benches));
  ASSERT_EQ(mixed.by_bench.size(), static_cast<std::size_t>(benches));
  for (const auto& [id, fits] : mixed.by_bench) EXPECT_EQ(fits, alone.by_bench["solo"]) << id;
}

}  // namespace
}  // namespace spindown
