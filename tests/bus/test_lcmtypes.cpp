// The generated spindown LCM types: every type round-trips with non-trivial arrays and
// strings, reports its size, refuses truncated buffers and buffers of another type.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <spindown/config_t.hpp>
#include <spindown/explain_t.hpp>
#include <spindown/fit_t.hpp>
#include <spindown/run_t.hpp>
#include <spindown/samples_t.hpp>
#include <spindown/status_t.hpp>

#include "spindown_messages.hpp"

using namespace spindown;
using namespace spindown::test;

namespace {

template <class M>
std::vector<std::uint8_t> encode(const M& m) {
  std::vector<std::uint8_t> buf(static_cast<std::size_t>(m.getEncodedSize()));
  const int n = m.encode(buf.data(), 0, static_cast<int>(buf.size()));
  EXPECT_EQ(n, static_cast<int>(buf.size())) << M::getTypeName();
  return buf;
}

// Decodes, checks every byte was used, and that encoding the result gives the same bytes.
template <class M>
M round_trip(const M& m) {
  const auto bytes = encode(m);
  M back;
  EXPECT_EQ(back.decode(bytes.data(), 0, static_cast<int>(bytes.size())), static_cast<int>(bytes.size()));
  EXPECT_EQ(encode(back), bytes) << M::getTypeName() << " does not re-encode to the same bytes";
  return back;
}

template <class M>
void refuses_truncation(const M& m) {
  const auto bytes = encode(m);
  for (std::size_t len = 0; len < bytes.size(); ++len) {
    M back;
    ASSERT_LT(back.decode(bytes.data(), 0, static_cast<int>(len)), 0)
        << M::getTypeName() << " decoded from " << len << " of " << bytes.size() << " bytes";
  }
  std::vector<std::uint8_t> small(bytes.size() - 1);
  EXPECT_LT(m.encode(small.data(), 0, static_cast<int>(small.size())), 0) << "encode into a short buffer";
}

template <class As, class M>
void refuses_other_type(const M& m) {
  const auto bytes = encode(m);
  As other;
  EXPECT_LT(other.decode(bytes.data(), 0, static_cast<int>(bytes.size())), 0)
      << "a " << M::getTypeName() << " decoded as " << As::getTypeName();
}

}  // namespace

TEST(LcmTypes, SamplesRoundTrip) {
  const samples_t m = make_samples();
  // Fixed part 8 (hash) + 8 + ("bench-a": 4 + 7 + 1) + 8 + 4 + 1 + 4, then 28 bytes per sample
  // (3), then the source fields: "lab-a", "239.255.76.67:7667" and "bench-pc" (4 + length + 1
  // each), session, seq, key id and auth[32].
  EXPECT_EQ(m.getEncodedSize(), 8 + 8 + 12 + 8 + 4 + 1 + 4 + 3 * 28 + (10 + 23 + 13) + 8 + 8 + 4 + 32);
  const samples_t b = round_trip(m);
  EXPECT_EQ(b.bench, m.bench);
  EXPECT_EQ(b.seq, m.seq);
  EXPECT_EQ(b.clock_epoch, m.clock_epoch);
  EXPECT_EQ(b.source_host, "bench-pc");
  EXPECT_EQ(int(b.quantity), int(samples_t::QUANTITY_RPM));  // int(): no ODR-use of the constant
  EXPECT_EQ(b.device_time_us, m.device_time_us);
  EXPECT_EQ(b.host_time_us, m.host_time_us);
  EXPECT_EQ(b.value, m.value);
  EXPECT_EQ(b.raw_adc, m.raw_adc);
}

TEST(LcmTypes, EmptySamplesBatch) {
  samples_t m = make_samples();
  m.n = 0;
  m.device_time_us.clear();
  m.host_time_us.clear();
  m.value.clear();
  m.raw_adc.clear();
  const samples_t b = round_trip(m);
  EXPECT_EQ(b.n, 0);
  EXPECT_TRUE(b.value.empty());
}

TEST(LcmTypes, ConfigRoundTrip) {
  config_t m = make_config();
  m.inertia_source = "geometry r=0.02 h=0.015 ρ=2700 + rotor 10.9 g·cm²";
  const config_t b = round_trip(m);
  EXPECT_EQ(b.inertia_source, m.inertia_source);  // UTF-8 survives
  EXPECT_DOUBLE_EQ(b.kb_v_s_per_rad, m.kb_v_s_per_rad);
  EXPECT_EQ(b.baud, 9600);
  EXPECT_EQ(b.device, "/dev/ttyACM0");
}

TEST(LcmTypes, RunRoundTrip) {
  const run_t b = round_trip(make_run());
  EXPECT_EQ(int(b.state), int(run_t::STATE_STOPPED));
  EXPECT_TRUE(std::isnan(b.t_stop_s));
  EXPECT_EQ(b.run, make_run().run);
  EXPECT_EQ(b.note, make_run().note);
}

TEST(LcmTypes, FitRoundTrip) {
  fit_t m = make_fit();
  m.finding_reason[0] = "dry friction 2.5× the baseline";
  const fit_t b = round_trip(m);
  EXPECT_EQ(b.model, m.model);
  EXPECT_EQ(b.converged, m.converged);
  EXPECT_TRUE(std::isinf(b.t_stop_pred_s[0]));
  EXPECT_EQ(b.param_name, m.param_name);
  EXPECT_EQ(b.param_value, m.param_value);
  EXPECT_EQ(b.param_unit, m.param_unit);
  EXPECT_EQ(b.best, m.best);
  EXPECT_EQ(b.verdict, m.verdict);
  EXPECT_TRUE(b.health_reference);
  EXPECT_EQ(b.nfindings, 2);
  EXPECT_EQ(b.doubts, m.doubts);
  EXPECT_EQ(b.finding_what, m.finding_what);
  EXPECT_EQ(b.finding_reason, m.finding_reason);  // UTF-8 (×) survives
  EXPECT_EQ(b.finding_ratio, m.finding_ratio);
  EXPECT_EQ(b.finding_reference_name, m.finding_reference_name);
}

TEST(LcmTypes, ExplainRoundTrip) {
  const explain_t m = make_explain();
  const explain_t b = round_trip(m);
  EXPECT_EQ(b.step_why, m.step_why);
  EXPECT_EQ(b.where_step, m.where_step);
  EXPECT_EQ(b.final_effects, m.final_effects);
  EXPECT_EQ(b.story, m.story);
}

TEST(LcmTypes, StatusRoundTrip) {
  const status_t m = make_status();
  const status_t b = round_trip(m);
  EXPECT_EQ(b.counter_name, m.counter_name);
  EXPECT_EQ(b.counter_value, m.counter_value);
  EXPECT_EQ(b.gauge_value, m.gauge_value);
  EXPECT_EQ(b.last_error, m.last_error);
}

TEST(LcmTypes, TruncatedBuffersDoNotDecode) {
  refuses_truncation(make_samples());
  refuses_truncation(make_config());
  refuses_truncation(make_run());
  refuses_truncation(make_fit());
  refuses_truncation(make_explain());
  refuses_truncation(make_status());
}

TEST(LcmTypes, AnotherTypesBytesDoNotDecode) {
  refuses_other_type<config_t>(make_samples());
  refuses_other_type<fit_t>(make_samples());
  refuses_other_type<samples_t>(make_config());
  refuses_other_type<status_t>(make_run());
  refuses_other_type<explain_t>(make_fit());
  refuses_other_type<fit_t>(make_explain());
  refuses_other_type<samples_t>(make_status());
}

TEST(LcmTypes, FingerprintsAreDistinct) {
  const std::vector<std::int64_t> hashes{samples_t::getHash(), config_t::getHash(),  run_t::getHash(),
                                         fit_t::getHash(),     explain_t::getHash(), status_t::getHash()};
  for (std::size_t i = 0; i < hashes.size(); ++i)
    for (std::size_t j = i + 1; j < hashes.size(); ++j) EXPECT_NE(hashes[i], hashes[j]) << i << " " << j;
}

TEST(LcmTypes, DecodingAtAnOffset) {
  const auto bytes = encode(make_samples());
  std::vector<std::uint8_t> padded(13 + bytes.size(), 0xAB);
  std::copy(bytes.begin(), bytes.end(), padded.begin() + 13);
  samples_t b{};
  EXPECT_EQ(b.decode(padded.data(), 13, static_cast<int>(bytes.size())), static_cast<int>(bytes.size()));
  EXPECT_EQ(b.value, make_samples().value);
}
