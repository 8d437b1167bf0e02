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
#include "spindown_messages.hpp"

namespace spindown {
namespace {

using namespace spindown::test;

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
  samples_t m{};
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
  fit_t m{};
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
    run_t m{};
    std::string why;
    EXPECT_FALSE(decode_message(m, bytes.data(), static_cast<std::int64_t>(bytes.size()), &why)) << len;
    EXPECT_NE(why.find("string bench has length"), std::string::npos) << why;
  }
}

TEST(MessageDecode, SampleCountLargerThanTheArraysSentIsRefused) {
  auto bytes = encode(make_samples());
  const std::size_t n_at = 8 + 8 + (4 + 8) + 8 + 4 + 1;
  put_be32(bytes, n_at, 100);  // says 100 samples, carries 3 (and the source fields after them)
  samples_t m{};
  std::string why;
  EXPECT_FALSE(decode_message(m, bytes.data(), static_cast<std::int64_t>(bytes.size()), &why));
  EXPECT_NE(why.find("n = 100"), std::string::npos) << why;
  // One more than it carries: the arrays then end inside the source fields, which are refused.
  put_be32(bytes, n_at, 4);
  EXPECT_FALSE(decode_message(m, bytes.data(), static_cast<std::int64_t>(bytes.size()), &why));
  EXPECT_NE(why.find("samples_t: string lab has length"), std::string::npos) << why;
}

TEST(MessageDecode, NoDataOrTooMuchIsRefused) {
  status_t m{};
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
  EXPECT_FALSE(view.legacy);
  EXPECT_EQ(view.lab, sent.lab);
  EXPECT_EQ(view.sent_to, sent.sent_to);
  EXPECT_EQ(view.source_host, sent.source_host);
  EXPECT_EQ(view.source_session, static_cast<std::uint64_t>(sent.source_session));
  EXPECT_EQ(view.source_seq, sent.source_seq);
  EXPECT_EQ(view.auth_key_id, sent.auth_key_id);
  ASSERT_EQ(view.n, sent.n);
  for (std::int32_t i = 0; i < view.n; ++i) {
    EXPECT_EQ(view.device_time_us(i), sent.device_time_us[static_cast<std::size_t>(i)]);
    EXPECT_EQ(view.value(i), sent.value[static_cast<std::size_t>(i)]);
  }
  samples_t copied{};
  copied.value = {9, 9, 9, 9, 9};  // storage reused, resized to n
  samples_from_view(view, copied);
  samples_t decoded{};
  ASSERT_TRUE(decode_message(decoded, bytes.data(), static_cast<std::int64_t>(bytes.size()), &why)) << why;
  EXPECT_EQ(encode(copied), encode(decoded));
}

TEST(MessageDecode, SamplesViewRefusesWhatTheDecoderRefusesInTheReadersWords) {
  SamplesView view;
  std::string why;
  auto bytes = encode(make_samples());
  const std::size_t n_at = 8 + 8 + (4 + 8) + 8 + 4 + 1;
  put_be32(bytes, n_at, 100);  // says 100 samples, carries 3
  EXPECT_FALSE(view_samples_message(view, bytes.data(), static_cast<std::int64_t>(bytes.size()), &why));
  EXPECT_EQ(why, fmt::format("sample count 100 does not fit in {} bytes (truncated or damaged)", bytes.size()));
  put_be32(bytes, n_at, 4);  // the arrays then end inside the source fields
  EXPECT_FALSE(view_samples_message(view, bytes.data(), static_cast<std::int64_t>(bytes.size()), &why));
  EXPECT_NE(why.find("lab string length"), std::string::npos) << why;
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
  samples_t m{};
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

// A message of the encoding spindown wrote before the source and signature fields: the current
// one without its appended fields, under the type's older fingerprint (what a log recorded then
// holds). `appended` is how many bytes the appended fields take at their defaults.
template <class Msg>
std::vector<std::uint8_t> legacy_bytes(Msg m, std::size_t appended, std::uint64_t old_hash) {
  m.lab.clear();
  m.sent_to.clear();
  m.source_host.clear();
  auto b = encode(m);
  b.resize(b.size() - appended);
  for (int k = 0; k < 8; ++k) b[static_cast<std::size_t>(k)] = static_cast<std::uint8_t>(old_hash >> (56 - 8 * k));
  return b;
}

// Every type's legacy encoding decodes to the same message with the new fields empty; the
// trailer reads as legacy; the samples view reads it in place.
template <class Msg>
void expect_legacy_decodes(Msg sent, std::size_t appended, std::uint64_t old_hash) {
  const auto old = legacy_bytes(sent, appended, old_hash);
  Msg back{};
  std::string why;
  ASSERT_TRUE(decode_message(back, old.data(), static_cast<std::int64_t>(old.size()), &why)) << Msg::getTypeName() << ": " << why;
  Msg expected = sent;
  expected.lab.clear();
  expected.sent_to.clear();
  expected.source_host.clear();
  expected.source_session = 0;
  expected.source_seq = 0;
  expected.auth_key_id = 0;
  std::memset(expected.auth, 0, sizeof expected.auth);
  if constexpr (requires { expected.bridge_session; }) {
    expected.bridge_host.clear();
    expected.bridge_session = 0;
  }
  if constexpr (requires { expected.start_utime; }) expected.start_utime = 0;
  EXPECT_EQ(encode(back), encode(expected)) << Msg::getTypeName();
  MessageTrailer t;
  ASSERT_TRUE(read_message_trailer(old.data(), static_cast<std::int64_t>(old.size()), t, &why)) << why;
  EXPECT_TRUE(t.legacy);
  EXPECT_EQ(t.type, Msg::getTypeName());
  EXPECT_EQ(t.end, static_cast<std::int64_t>(old.size()));
  // Every proper prefix is still refused.
  for (std::size_t cut = 0; cut < old.size(); ++cut)
    EXPECT_FALSE(decode_message(back, old.data(), static_cast<std::int64_t>(cut))) << Msg::getTypeName() << " " << cut;
}

TEST(MessageDecode, EncodingsFromBeforeTheSourceFieldsStillDecode) {
  // lab, sent_to, source_host (empty: 5 bytes each), source_session, source_seq, auth_key_id, auth[32].
  constexpr std::size_t trailer = 5 + 5 + 5 + 8 + 8 + 4 + 32;
  expect_legacy_decodes(make_samples(), trailer, 0x6366464c24ab26e1ull);
  expect_legacy_decodes(make_config(), trailer, 0xf33bcecf4e9c80bdull);
  expect_legacy_decodes(make_run(), trailer + 5 + 8, 0x52fa3d633257d3efull);  // + bridge_host, bridge_session
  expect_legacy_decodes(make_fit(), trailer + 5 + 8, 0x9a6ae2b7c7c8e61cull);
  expect_legacy_decodes(make_explain(), trailer, 0x8e7064d4b8398716ull);
  expect_legacy_decodes(make_status(), trailer + 8, 0x056ac82d6252dc21ull);  // + start_utime

  const auto old = legacy_bytes(make_samples(), trailer, 0x6366464c24ab26e1ull);
  SamplesView view;
  std::string why;
  ASSERT_TRUE(view_samples_message(view, old.data(), static_cast<std::int64_t>(old.size()), &why)) << why;
  EXPECT_TRUE(view.legacy);
  EXPECT_EQ(view.n, 3);
  EXPECT_EQ(view.value(2), 3.5);
  EXPECT_TRUE(view.lab.empty());
  EXPECT_EQ(view.source_session, 0u);
  samples_t copied{};
  samples_from_view(view, copied);
  EXPECT_EQ(copied.source_seq, 0);
}

// The six fields that end every type, read in place for any type by its fingerprint.
TEST(MessageDecode, TrailerOfEveryTypeIsReadInPlace) {
  const auto check = [](auto m) {
    set_source(m, "physics-2", "pc-17", 0x0102030405060708, 77);
    m.auth_key_id = 0x11223344;
    for (int i = 0; i < 32; ++i) m.auth[i] = static_cast<std::uint8_t>(i + 1);
    const auto b = encode(m);
    MessageTrailer t;
    std::string why;
    ASSERT_TRUE(read_message_trailer(b.data(), static_cast<std::int64_t>(b.size()), t, &why)) << why;
    EXPECT_FALSE(t.legacy);
    EXPECT_EQ(t.type, decltype(m)::getTypeName());
    EXPECT_EQ(t.utime, m.utime);
    EXPECT_EQ(t.lab, "physics-2");
    EXPECT_EQ(t.sent_to, "239.255.76.67:7667");
    EXPECT_EQ(t.source_host, "pc-17");
    EXPECT_EQ(t.source_session, 0x0102030405060708u);
    EXPECT_EQ(t.source_seq, 77);
    EXPECT_EQ(t.auth_key_id, 0x11223344);
    EXPECT_EQ(t.auth_offset, static_cast<std::int64_t>(b.size()) - 32);
    EXPECT_EQ(t.auth[0], 1);
    EXPECT_EQ(t.auth[31], 32);
    EXPECT_EQ(t.end, static_cast<std::int64_t>(b.size()));
  };
  check(make_samples());
  check(make_config());
  check(make_run());
  check(make_fit());
  check(make_explain());
  check(make_status());
  MessageTrailer t;
  std::string why;
  const std::vector<std::uint8_t> junk(40, 0x5a);
  EXPECT_FALSE(read_message_trailer(junk.data(), 40, t, &why));
  EXPECT_NE(why.find("not a spindown message"), std::string::npos) << why;
}

// The fingerprint view_samples_message compares against is read once; it is the generated one.
TEST(MessageDecode, SamplesFingerprintIsTheGeneratedHash) {
  EXPECT_EQ(samples_fingerprint, static_cast<std::uint64_t>(samples_t::getHash()));
}

}  // namespace
}  // namespace spindown
