// An LCM log as MCAP: one JSON message per sample (the CSV's fields, log_time at the sample's
// host time), RUN and FIT decoded (FIT as `spindown fit --json` prints the run), one topic per
// bench and kind with its JSON Schema, --bench honoured, undecodable events reported by number.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <sstream>

#include <spindown/samples_t.hpp>

#include "lcm_log_events.hpp"
#include "mcap_records.hpp"
#include "spindown/fit_message.hpp"
#include "spindown/lcm_log_mcap.hpp"
#include "spindown/mcap_writer.hpp"
#include "spindown/runs.hpp"
#include "spindown/synthetic_run.hpp"

namespace spindown {
namespace {

using testing::le;
using testing::mcap_records;
using testing::mcap_string;

RunFit sample_fit() {
  SyntheticRunSpec spec;
  spec.seed = 7;
  const SyntheticRun run = make_synthetic_run(spec);
  Recording rec;
  for (std::size_t i = 0; i < run.t_ms.size(); ++i) rec.push(run.t_ms[i] / 1000.0, run.volts[i]);
  const Segmentation seg = find_runs(rec);
  EXPECT_EQ(seg.runs.size(), 1u);
  return fit_run(rec, seg.runs.at(0), FitOptions{});
}

samples_t samples(const std::string& bench, std::int64_t seq, int n, std::int64_t t0_us, bool with_adc) {
  samples_t m{};
  m.utime = 1'700'000'000'000'000 + t0_us + 5000;
  m.bench = bench;
  m.seq = seq;
  m.clock_epoch = 2;
  m.quantity = samples_t::QUANTITY_BACK_EMF_V;
  m.n = n;
  for (int i = 0; i < n; ++i) {
    m.device_time_us.push_back(t0_us + 20'000 * i);
    m.host_time_us.push_back(1'700'000'000'000'000 + t0_us + 20'000 * i + 300);
    m.value.push_back(i == 1 && bench == "b1" ? NAN : 3.0 - 0.01 * double(seq + i));
    m.raw_adc.push_back(with_adc ? 600 + i : -1);
  }
  return m;
}

struct Message {
  std::string topic;
  std::uint32_t sequence;
  std::uint64_t log_time, publish_time;
  Json json;
};

// Every message of the file, in file order, with its topic; the schemas by topic.
std::vector<Message> read_mcap(const std::string& bytes, std::map<std::string, std::string>* schema_of = nullptr) {
  std::map<std::uint64_t, std::string> topic, schema_name;
  std::map<std::uint64_t, std::uint64_t> channel_schema;
  std::vector<Message> out;
  auto on = [&](const testing::McapRecord& r, auto& self) -> void {
    if (r.op == static_cast<std::uint8_t>(McapOp::schema)) {
      std::size_t p = 2;
      schema_name[le(r.body, 0, 2)] = std::string(mcap_string(r.body, &p));
      EXPECT_EQ(mcap_string(r.body, &p), "jsonschema");
      const auto data = mcap_string(r.body, &p);
      EXPECT_TRUE(Json::parse(data, nullptr, false).is_object()) << "the JSON Schema is JSON";
    } else if (r.op == static_cast<std::uint8_t>(McapOp::channel)) {
      std::size_t p = 4;
      topic[le(r.body, 0, 2)] = std::string(mcap_string(r.body, &p));
      channel_schema[le(r.body, 0, 2)] = le(r.body, 2, 2);
      EXPECT_EQ(mcap_string(r.body, &p), "json");
    } else if (r.op == static_cast<std::uint8_t>(McapOp::chunk)) {
      const std::string_view records = r.body.substr(40, le(r.body, 16, 8));
      for (const auto& m : mcap_records(records, 0, records.size())) self(m, self);
    } else if (r.op == static_cast<std::uint8_t>(McapOp::message)) {
      const auto ch = le(r.body, 0, 2);
      out.push_back({topic.at(ch), static_cast<std::uint32_t>(le(r.body, 2, 4)), le(r.body, 6, 8), le(r.body, 14, 8),
                     Json::parse(r.body.substr(22))});
    }
  };
  const std::size_t summary = le(bytes, bytes.size() - 8 - 29 + 9, 8);
  for (const auto& r : mcap_records(bytes, 8, summary)) on(r, on);
  if (schema_of)
    for (const auto& [ch, t] : topic) (*schema_of)[t] = schema_name.at(channel_schema.at(ch));
  return out;
}

class LcmLogMcap : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("spindown-mcap-" + std::to_string(::getpid()) + "-" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(dir_);
    path_ = (dir_ / "log.lcm").string();
    lcm::LogFile log(path_, "w");
    ASSERT_TRUE(log.good());
    std::int64_t t = 1'700'000'000'000'000;
    testing::write_event(log, "SPINDOWN.b1.SAMPLE", samples("b1", 0, 3, 0, true), t += 1000);
    testing::write_event(log, "SPINDOWN.b2.SAMPLE", samples("b2", 10, 2, 0, false), t += 1000);
    testing::write_event(log, "SPINDOWN.b1.SAMPLE", samples("b1", 3, 2, 60'000, true), t += 1000);
    run_t run = to_run_message("b1", spindown::Run{}, run_t::STATE_COASTING, 3, 4, 2, "a note", t);
    run.t_cut_s = 1.5;
    run.t_stop_s = NAN;
    testing::write_event(log, "SPINDOWN.b1.RUN", run, t += 1000);
    fit_ = sample_fit();
    const fit_t fit = to_fit_message(fit_, {"b1", "config", 3, 4, 0.01, std::nullopt, "", 0}, t);
    testing::write_event(log, "SPINDOWN.b1.FIT", fit, t += 1000);
    // An event on FIT that is not a fit_t: reported, not exported.
    samples_t wrong = samples("b1", 0, 1, 0, true);
    testing::write_event(log, "SPINDOWN.b1.FIT", wrong, t += 1000);
    testing::write_event(log, "SPINDOWN.b1.CONFIG", wrong, t += 1000);  // not exported (CONFIG)
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  std::filesystem::path dir_;
  std::string path_;
  RunFit fit_;
};

TEST_F(LcmLogMcap, SamplesRunsAndFitsAsJson) {
  std::ostringstream out(std::ios::binary);
  const LcmLogMcapResult r = write_lcm_log_mcap(path_, out, {});
  EXPECT_EQ(r.events, 7);
  EXPECT_EQ(r.samples, 7);
  EXPECT_EQ(r.runs, 1);
  EXPECT_EQ(r.fits, 1);
  EXPECT_EQ(r.channels, 4);
  EXPECT_EQ(r.bytes, out.str().size());
  ASSERT_EQ(r.problems_total, 1);
  EXPECT_NE(r.problems.at(0).find("event 6 (SPINDOWN.b1.FIT)"), std::string::npos) << r.problems[0];
  EXPECT_NE(r.problems.at(0).find("fit_t"), std::string::npos) << r.problems[0];

  std::map<std::string, std::string> schema;
  const auto msgs = read_mcap(out.str(), &schema);
  EXPECT_EQ(schema["SPINDOWN.b1.SAMPLE"], "spindown.sample");
  EXPECT_EQ(schema["SPINDOWN.b2.SAMPLE"], "spindown.sample");
  EXPECT_EQ(schema["SPINDOWN.b1.RUN"], "spindown.run");
  EXPECT_EQ(schema["SPINDOWN.b1.FIT"], "spindown.fit");
  ASSERT_EQ(msgs.size(), 9u);

  // Samples: log order, one each, the CSV's fields; NaN is null, no ADC is null.
  const Message& s0 = msgs[0];
  EXPECT_EQ(s0.topic, "SPINDOWN.b1.SAMPLE");
  EXPECT_EQ(s0.json["bench"], "b1");
  EXPECT_EQ(s0.json["seq"], 0);
  EXPECT_EQ(s0.json["device_time_s"], 0.0);
  EXPECT_DOUBLE_EQ(s0.json["host_time_s"].get<double>(), 1.7e9 + 300e-6);
  EXPECT_DOUBLE_EQ(s0.json["value"].get<double>(), 3.0);
  EXPECT_EQ(s0.json["unit"], "V");
  EXPECT_EQ(s0.json["raw_adc"], 600);
  EXPECT_EQ(s0.json["clock_epoch"], 2);
  EXPECT_EQ(s0.log_time, (1'700'000'000'000'000ull + 300) * 1000) << "log_time: the sample's host time";
  EXPECT_EQ(s0.publish_time, (1'700'000'000'000'000ull + 5000) * 1000) << "publish_time: the message's utime";
  EXPECT_EQ(s0.sequence, 0u);
  EXPECT_TRUE(msgs[1].json["value"].is_null()) << msgs[1].json.dump();
  EXPECT_DOUBLE_EQ(msgs[1].json["device_time_s"].get<double>(), 0.02);
  EXPECT_EQ(msgs[3].topic, "SPINDOWN.b2.SAMPLE");
  EXPECT_EQ(msgs[3].json["seq"], 10);
  EXPECT_TRUE(msgs[3].json["raw_adc"].is_null());
  EXPECT_EQ(msgs[5].json["seq"], 3);
  EXPECT_DOUBLE_EQ(msgs[5].json["device_time_s"].get<double>(), 0.06);

  // RUN as recorded.
  const Message& run = msgs[7];
  EXPECT_EQ(run.topic, "SPINDOWN.b1.RUN");
  EXPECT_EQ(run.json["state"], "coasting");
  EXPECT_EQ(run.json["state_code"], 1);
  EXPECT_EQ(run.json["t_cut_s"], 1.5);
  EXPECT_TRUE(run.json["t_stop_s"].is_null());
  EXPECT_EQ(run.json["first_seq"], 3);
  EXPECT_EQ(run.json["note"], "a note");

  // FIT as `spindown fit --json` prints the run, tagged with the bench.
  const Message& fit = msgs[8];
  EXPECT_EQ(fit.topic, "SPINDOWN.b1.FIT");
  EXPECT_EQ(fit.json["best"], fit_.best);
  EXPECT_EQ(fit.json["bench"]["id"], "b1");
  EXPECT_EQ(fit.json["first_seq"], 3);
  ASSERT_EQ(fit.json["models"].size(), fit_.models.size());
  const Json expected = run_fit_json(fit_);
  EXPECT_EQ(fit.json["models"].dump(), expected["models"].dump());
}

TEST_F(LcmLogMcap, BenchRegexKeepsOnlyThoseBenches) {
  std::ostringstream out(std::ios::binary);
  const LcmLogMcapResult r = write_lcm_log_mcap(path_, out, {.bench_regex = "b2"});
  EXPECT_EQ(r.samples, 2);
  EXPECT_EQ(r.runs + r.fits, 0);
  EXPECT_EQ(r.problems_total, 0) << "b1's broken FIT is not read at all";
  const auto msgs = read_mcap(out.str());
  ASSERT_EQ(msgs.size(), 2u);
  for (const auto& m : msgs) EXPECT_EQ(m.topic, "SPINDOWN.b2.SAMPLE");
}

TEST_F(LcmLogMcap, MissingLogNamesTheFile) {
  std::ostringstream out(std::ios::binary);
  try {
    write_lcm_log_mcap((dir_ / "nope.lcm").string(), out, {});
    FAIL() << "no error";
  } catch (const LcmLogMcapError& e) {
    EXPECT_NE(std::string(e.what()).find("nope.lcm"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace spindown
