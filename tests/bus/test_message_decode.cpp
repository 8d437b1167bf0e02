// decode_message: what the generated decoders accept, without their unbounded allocations.
// The layouts in message_decode.cpp are checked against lcm-gen's encoder for every type, so a
// field added to a .lcm file without a layout update fails here.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "spindown/message_decode.hpp"

namespace spindown {
namespace {

template <class Msg>
std::vector<std::uint8_t> encode(const Msg& m) {
  std::vector<std::uint8_t> b(static_cast<std::size_t>(m.getEncodedSize()));
  EXPECT_EQ(m.encode(b.data(), 0, static_cast<int>(b.size())), static_cast<int>(b.size()));
  return b;
}

void put_be32(std::vector<std::uint8_t>& b, std::size_t at, std::int32_t v) {
  const auto u = static_cast<std::uint32_t>(v);
  b[at] = std::uint8_t(u >> 24);
  b[at + 1] = std::uint8_t(u >> 16);
  b[at + 2] = std::uint8_t(u >> 8);
  b[at + 3] = std::uint8_t(u);
}

// Every field non-empty, every array with distinct lengths, so a layout error shifts bytes.
samples_t make_samples() {
  samples_t s;
  s.utime = 1;
  s.bench = "bench-a";
  s.seq = 7;
  s.clock_epoch = 2;
  s.quantity = samples_t::QUANTITY_RPM;
  s.n = 3;
  s.device_time_us = {1, 2, 3};
  s.host_time_us = {4, 5, 6};
  s.value = {1.5, 2.5, 3.5};
  s.raw_adc = {-1, -1, 7};
  return s;
}
config_t make_config() {
  config_t c;
  c.bench = "b";
  c.inertia_kg_m2 = 1e-5;
  c.inertia_source = "lab default";
  c.kb_v_s_per_rad = 0.008;
  c.kb_source = "x";
  c.quantity = 1;
  c.adc_bits = 10;
  c.firmware = "fw";
  c.protocol = "lab-tsv";
  c.baud = 9600;
  c.device = "/dev/ttyACM0";
  c.host = "h";
  c.inertia_rel_error = 0.02;
  c.kb_rel_error = 0.05;
  return c;
}
run_t make_run() {
  run_t r;
  r.bench = "b";
  r.run = 3;
  r.state = run_t::STATE_STOPPED;
  r.t_cut_s = 1;
  r.t_stop_s = NAN;
  r.samples = 9;
  r.note = "note";
  return r;
}
fit_t make_fit() {
  fit_t f;
  f.bench = "bench-a";
  f.residual_unit = "V";
  f.bench_source = "config";
  f.nmodels = 2;
  f.model = {"viscous", "combined"};
  f.rmse = {1, 2};
  f.r2 = {1, 2};
  f.aic = {1, 2};
  f.bic = {1, 2};
  f.t_stop_pred_s = {INFINITY, 2};
  f.converged = {1, 0};
  f.model_samples = {10, 11};
  f.model_message = {"", "did not converge"};
  f.nparams = 3;
  f.param_model = {0, 1, 1};
  f.param_name = {"c4", "c3", "c4"};
  f.param_value = {1, 2, 3};
  f.param_stderr = {0.1, 0.2, 0.3};
  f.param_unit = {"a", "b", "c"};
  f.best = "viscous";
  f.best_reason = "r";
  f.verdict = "ok";
  f.verdict_reason = "v";
  f.inertia_source = "i";
  f.kb_source = "k";
  f.lead_in = "zeros";
  f.first_seq = 1;
  f.last_seq = 2;
  f.health_reference = 1;
  f.nfindings = 2;
  f.finding_what = {"dry friction", "time to stop"};
  f.finding_level = {"ok", "check"};
  f.finding_reason = {"r1", "r2"};
  f.finding_value = {1, 2};
  f.finding_stderr = {1, 2};
  f.finding_reference = {1, 2};
  f.finding_reference_stderr = {1, 2};
  f.finding_reference_name = {"baseline", "lab limit"};
  f.finding_ratio = {1, 2};
  f.finding_ratio_stderr = {1, 2};
  f.finding_unit = {"N*m", "s"};
  f.ndoubts = 2;
  f.doubts = {"d1", "d2"};
  f.reading_step = 0.01;
  f.model_reduced_chi2 = {1, 2};
  f.ncorrelations = 3;
  f.corr_model = {0, 1, 1};
  f.corr_a = {"omega0", "omega0", "c3"};
  f.corr_b = {"c1", "c3", "c4"};
  f.corr_value = {0.5, 0.6, -0.9};
  f.inertia_rel_error = 0.02;
  f.kb_rel_error = 0.05;
  f.param_bench_error = {0.01, 0.02, 0.03};
  f.reading_noise = 0.0042;
  return f;
}
explain_t make_explain() {
  explain_t e;
  e.bench = "b";
  e.nbase = 1;
  e.base = {"viscous"};
  e.nsteps = 2;
  e.step_added = {"coulomb", "windage"};
  e.step_rmse_before = {3, 2};
  e.step_rmse_after = {2, 1};
  e.step_why = {"w1", "w2"};
  e.nwhere = 3;
  e.where_step = {0, 0, 1};
  e.where_t_from_s = {0, 1, 2};
  e.where_t_to_s = {1, 2, 3};
  e.where_mean_residual = {0.1, 0.2, 0.3};
  e.nfinal = 3;
  e.final_effects = {"viscous", "coulomb", "windage"};
  e.nparams = 4;
  e.param_name = {"c1", "c2", "c3", "c4"};
  e.param_value = {1, 2, 3, 4};
  e.param_stderr = {1, 2, 3, 4};
  e.param_unit = {"u", "u", "u", "u"};
  e.story = "story";
  return e;
}
status_t make_status() {
  status_t s;
  s.service = "bridge";
  s.instance = "bench-a";
  s.host = "h";
  s.pid = 1;
  s.state = "connected";
  s.ncounters = 2;
  s.counter_name = {"lines_good", "lines_bad"};
  s.counter_value = {10, 1};
  s.ngauges = 1;
  s.gauge_name = {"rate_hz"};
  s.gauge_value = {50};
  s.last_error = "e";
  return s;
}

template <class Msg>
void expect_layout_matches(const Msg& original) {
  const auto bytes = encode(original);
  Msg back;
  std::string why;
  ASSERT_TRUE(decode_message(back, bytes.data(), static_cast<std::int64_t>(bytes.size()), &why)) << why;
  EXPECT_EQ(encode(back), bytes);
  // Every proper prefix is refused with a reason, and so is every prefix the generated decoder
  // refuses: the layout walk and lcm-gen's decoder agree byte for byte.
  for (std::size_t cut = 0; cut < bytes.size(); ++cut) {
    Msg m;
    why.clear();
    EXPECT_FALSE(decode_message(m, bytes.data(), static_cast<std::int64_t>(cut), &why)) << Msg::getTypeName() << " " << cut;
    EXPECT_FALSE(why.empty());
    EXPECT_LT(Msg().decode(bytes.data(), 0, static_cast<int>(cut)), 0) << Msg::getTypeName() << " " << cut;
  }
}

TEST(MessageDecode, LayoutOfEveryTypeMatchesTheGeneratedEncoder) {
  expect_layout_matches(make_samples());
  expect_layout_matches(make_config());
  expect_layout_matches(make_run());
  expect_layout_matches(make_fit());
  expect_layout_matches(make_explain());
  expect_layout_matches(make_status());
}

TEST(MessageDecode, WrongFingerprintIsNamed) {
  const auto bytes = encode(make_config());
  samples_t m;
  std::string why;
  EXPECT_FALSE(decode_message(m, bytes.data(), static_cast<std::int64_t>(bytes.size()), &why));
  EXPECT_NE(why.find("not a samples_t"), std::string::npos) << why;
}

// The fuzzer's first find: a count of 2^31 − 1 in a small message made lcm-gen's decoder
// resize vectors to tens of gigabytes before noticing the bytes were not there.
TEST(MessageDecode, HugeArrayCountIsRefusedBeforeAnyAllocation) {
  auto bytes = encode(make_fit());
  // nmodels follows utime, bench, run, t_cut_s, t_stop_s, samples, J, K_b, bench_source,
  // zero_level, residual_unit.
  const std::size_t at = 8 + 8 + (4 + 8) + 4 + 8 + 8 + 4 + 8 + 8 + (4 + 7) + 8 + (4 + 2);
  std::int32_t was = 0;
  for (int k = 0; k < 4; ++k) was = (was << 8) | bytes[at + k];
  ASSERT_EQ(was, 2);
  put_be32(bytes, at, 0x7fffffff);
  fit_t m;
  std::string why;
  EXPECT_FALSE(decode_message(m, bytes.data(), static_cast<std::int64_t>(bytes.size()), &why));
  EXPECT_NE(why.find("nmodels = 2147483647"), std::string::npos) << why;
  put_be32(bytes, at, -5);
  EXPECT_FALSE(decode_message(m, bytes.data(), static_cast<std::int64_t>(bytes.size()), &why));
  EXPECT_NE(why.find("negative"), std::string::npos) << why;
}

// A string length of INT_MIN overflowed `len - 1` inside the generated header (UB); zero made
// std::string::assign throw.
TEST(MessageDecode, BadStringLengthsAreRefused) {
  auto bytes = encode(make_run());
  for (const std::int32_t len : {0, -1, std::int32_t(0x80000000u), 0x7fffffff}) {
    put_be32(bytes, 16, len);  // bench's length word, after the fingerprint and utime
    run_t m;
    std::string why;
    EXPECT_FALSE(decode_message(m, bytes.data(), static_cast<std::int64_t>(bytes.size()), &why)) << len;
    EXPECT_NE(why.find("string bench has length"), std::string::npos) << why;
  }
}

TEST(MessageDecode, SampleCountLargerThanTheArraysSentIsRefused) {
  auto bytes = encode(make_samples());
  const std::size_t n_at = 8 + 8 + (4 + 8) + 8 + 4 + 1;
  put_be32(bytes, n_at, 4);  // says 4 samples, carries 3
  samples_t m;
  std::string why;
  EXPECT_FALSE(decode_message(m, bytes.data(), static_cast<std::int64_t>(bytes.size()), &why));
  EXPECT_NE(why.find("n = 4"), std::string::npos) << why;
}

TEST(MessageDecode, NoDataOrTooMuchIsRefused) {
  status_t m;
  std::string why;
  EXPECT_FALSE(decode_message(m, nullptr, 0, &why));
  EXPECT_FALSE(decode_message(m, "x", std::int64_t{1} << 32, &why));
  EXPECT_NE(why.find("more than an LCM message"), std::string::npos) << why;
}

// The in-place view of a samples_t (the log reader's and the fitter's fast path) reads every
// field as the generated decoder does, and accepts and refuses the same bytes.
TEST(MessageDecode, SamplesViewAgreesWithTheGeneratedDecoder) {
  const samples_t sent = make_samples();
  const auto bytes = encode(sent);
  SamplesView view;
  std::string why;
  ASSERT_TRUE(view_samples_message(view, bytes.data(), static_cast<std::int64_t>(bytes.size()), &why)) << why;
  EXPECT_EQ(view.utime, sent.utime);
  EXPECT_EQ(view.bench, sent.bench);
  EXPECT_EQ(view.seq, sent.seq);
  EXPECT_EQ(view.clock_epoch, sent.clock_epoch);
  EXPECT_EQ(view.quantity, sent.quantity);
  ASSERT_EQ(view.n, sent.n);
  for (std::int32_t i = 0; i < view.n; ++i) {
    EXPECT_EQ(view.device_time_us(i), sent.device_time_us[static_cast<std::size_t>(i)]);
    EXPECT_EQ(view.value(i), sent.value[static_cast<std::size_t>(i)]);
  }
  samples_t copied;
  copied.value = {9, 9, 9, 9, 9};  // storage reused, resized to n
  samples_from_view(view, copied);
  samples_t decoded;
  ASSERT_TRUE(decode_message(decoded, bytes.data(), static_cast<std::int64_t>(bytes.size()), &why)) << why;
  EXPECT_EQ(encode(copied), encode(decoded));
}

TEST(MessageDecode, SamplesViewRefusesWhatTheDecoderRefusesInTheReadersWords) {
  SamplesView view;
  std::string why;
  auto bytes = encode(make_samples());
  const std::size_t n_at = 8 + 8 + (4 + 8) + 8 + 4 + 1;
  put_be32(bytes, n_at, 4);  // says 4 samples, carries 3
  EXPECT_FALSE(view_samples_message(view, bytes.data(), static_cast<std::int64_t>(bytes.size()), &why));
  EXPECT_EQ(why, fmt::format("sample count 4 does not fit in {} bytes (truncated or damaged)", bytes.size()));
  put_be32(bytes, n_at, -1);
  EXPECT_FALSE(view_samples_message(view, bytes.data(), static_cast<std::int64_t>(bytes.size()), &why));
  EXPECT_NE(why.find("sample count -1"), std::string::npos) << why;

  bytes = encode(make_samples());
  put_be32(bytes, 16, 1000);  // bench string longer than the message
  EXPECT_FALSE(view_samples_message(view, bytes.data(), static_cast<std::int64_t>(bytes.size()), &why));
  EXPECT_EQ(why, fmt::format("bench string length 1000 does not fit in {} bytes", bytes.size()));

  bytes = encode(make_samples());
  EXPECT_FALSE(view_samples_message(view, bytes.data(), 30, &why));  // cut before the count
  EXPECT_EQ(why, "truncated: 30 bytes end before the sample count");
  EXPECT_FALSE(view_samples_message(view, bytes.data(), 12, &why));
  EXPECT_EQ(why, "12 bytes, too short for samples_t");

  // Not a samples_t at all: decode_message's words.
  const auto config_bytes = encode(make_config());
  std::string decoder_why;
  samples_t m;
  EXPECT_FALSE(view_samples_message(view, config_bytes.data(), static_cast<std::int64_t>(config_bytes.size()), &why));
  EXPECT_FALSE(decode_message(m, config_bytes.data(), static_cast<std::int64_t>(config_bytes.size()), &decoder_why));
  EXPECT_EQ(why, decoder_why);
  EXPECT_FALSE(view_samples_message(view, config_bytes.data(), 4, &why));
  EXPECT_EQ(why, "4 bytes, too short for samples_t");
  EXPECT_FALSE(view_samples_message(view, nullptr, 0, &why));
}

// The inline checks of view_samples_message and the worded ones agree byte for byte on damaged
// messages: every truncation, and every byte of the header, bench length and sample count set
// to values that break them. Both also accept exactly what the generated decoder's walk accepts.
TEST(MessageDecode, SamplesViewInlineChecksAgreeWithTheWordedOnes) {
  const auto sound = encode(make_samples());
  const std::size_t n_at = 8 + 8 + (4 + 8) + 8 + 4 + 1;
  std::vector<std::vector<std::uint8_t>> cases;
  for (std::size_t size = 0; size <= sound.size(); ++size)
    cases.emplace_back(sound.begin(), sound.begin() + static_cast<std::ptrdiff_t>(size));
  for (std::size_t at = 0; at < n_at + 4; ++at)
    for (std::uint8_t v : {std::uint8_t{0}, std::uint8_t{1}, std::uint8_t{0x7f}, std::uint8_t{0x80},
                           std::uint8_t{0xff}, std::uint8_t(sound[at] ^ 1)}) {
      auto bytes = sound;
      bytes[at] = v;
      cases.push_back(bytes);
    }
  for (std::int32_t n : {-1, 0, 1, 2, 3, 4, 1 << 30}) {
    auto bytes = sound;
    put_be32(bytes, n_at, n);
    cases.push_back(bytes);
  }
  std::size_t accepted = 0;
  for (const auto& bytes : cases) {
    const auto size = static_cast<std::int64_t>(bytes.size());
    SamplesView fast, worded;
    std::string fast_why = "unset", worded_why = "unset";
    const bool ok = view_samples_message(fast, bytes.data(), size, &fast_why);
    ASSERT_EQ(ok, view_samples_message_worded(worded, bytes.data(), size, &worded_why)) << size;
    ASSERT_EQ(fast_why, worded_why);
    SamplesView silent;
    ASSERT_EQ(view_samples_message(silent, bytes.data(), size), ok);  // no words asked for
    EXPECT_EQ(check_message_encoding<samples_t>(bytes.data(), size), ok) << fast_why;
    if (!ok) continue;
    ++accepted;
    EXPECT_EQ(fast.utime, worded.utime);
    EXPECT_EQ(fast.bench, worded.bench);
    EXPECT_EQ(fast.seq, worded.seq);
    EXPECT_EQ(fast.clock_epoch, worded.clock_epoch);
    EXPECT_EQ(fast.quantity, worded.quantity);
    EXPECT_EQ(fast.n, worded.n);
    EXPECT_EQ(fast.device_time_bytes, worded.device_time_bytes);
    EXPECT_EQ(fast.host_time_bytes, worded.host_time_bytes);
    EXPECT_EQ(fast.value_bytes, worded.value_bytes);
    EXPECT_EQ(fast.raw_adc_bytes, worded.raw_adc_bytes);
  }
  EXPECT_GT(accepted, 20u);                 // the bytes that do not matter to the layout
  EXPECT_LT(accepted, cases.size() - 100);  // and plenty that do
}

// The fingerprint view_samples_message compares against is read once; it is the generated one.
TEST(MessageDecode, SamplesFingerprintIsTheGeneratedHash) {
  EXPECT_EQ(samples_fingerprint, static_cast<std::uint64_t>(samples_t::getHash()));
}

}  // namespace
}  // namespace spindown
