// The gate every reader takes messages through: another lab's message is refused with or without
// a key; with the key, unsigned, wrongly signed and replayed messages are refused; each refusal is
// counted and named with the source.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "spindown/message_gate.hpp"
#include "spindown/message_stamp.hpp"
#include "spindown_messages.hpp"

namespace spindown {
namespace {

using namespace spindown::test;

constexpr std::int64_t t0 = 1'700'000'000'000'000;

LabKey test_key(unsigned char fill = 5) {
  std::array<unsigned char, lab_key_bytes> b{};
  b.fill(fill);
  return lab_key_from_bytes(b);
}

MessageStamp stamp_for(const std::string& lab, std::optional<LabKey> key, std::uint64_t session = 42) {
  return MessageStamp(SourceIdentity{lab, "239.255.76.67:7667", "bench-pc", session, t0}, std::move(key));
}

samples_t samples_at(std::int64_t utime) {
  samples_t m = make_samples();
  m.utime = utime;
  return m;
}

fit_t fit_at(std::int64_t utime = t0) {
  fit_t m = make_fit();
  m.utime = utime;
  return m;
}

MessageGateOptions options(std::string lab, std::optional<LabKey> key = std::nullopt, std::size_t max_sources = 4096) {
  MessageGateOptions o;
  o.lab = std::move(lab);
  o.key = std::move(key);
  o.replay_window_s = 60;
  o.max_sources = max_sources;
  return o;
}

TEST(MessageGate, AnotherLabIsRefusedAndNamedWithOrWithoutAKey) {
  MessageGate gate(options("lab-a"));
  auto ours = stamp_for("lab-a", std::nullopt);
  auto theirs = stamp_for("lab-b", std::nullopt, 43);
  const auto a = ours.encode("SPINDOWN.b1.SAMPLE", samples_at(t0));
  const auto b = theirs.encode("SPINDOWN.b1.SAMPLE", samples_at(t0));
  EXPECT_TRUE(gate.check("SPINDOWN.b1.SAMPLE", a.data(), std::int64_t(a.size()), t0).accepted());
  const GateResult r = gate.check("SPINDOWN.b1.SAMPLE", b.data(), std::int64_t(b.size()), t0);
  EXPECT_EQ(r.verdict, GateVerdict::other_lab);
  EXPECT_TRUE(r.refused());
  EXPECT_NE(r.text.find("a message of lab 'lab-b', this program serves lab 'lab-a'"), std::string::npos) << r.text;
  EXPECT_NE(r.text.find("host bench-pc (session 000000000000002b)"), std::string::npos) << r.text;
  EXPECT_EQ(gate.counters().other_lab, 1);
  EXPECT_EQ(gate.counters().accepted, 1);
  // A message naming no lab (an older sender) is this lab's; so is every lab to an empty gate.
  auto old = make_samples();
  old.lab.clear();
  const auto o = encoded(old);
  EXPECT_TRUE(gate.check("SPINDOWN.b1.SAMPLE", o.data(), std::int64_t(o.size()), t0).accepted());
  MessageGate every(MessageGateOptions::every_lab());
  EXPECT_TRUE(every.check("SPINDOWN.b1.SAMPLE", b.data(), std::int64_t(b.size()), t0).accepted());
  EXPECT_TRUE(every.accepts_at_once("lab-b", ""));
  EXPECT_FALSE(gate.accepts_at_once("lab-b", ""));
  EXPECT_TRUE(gate.accepts_at_once("lab-a", ""));
}

TEST(MessageGate, WithTheKeyOnlySignedNewMessagesPass) {
  MessageGate gate(options("lab-a", test_key()));
  EXPECT_TRUE(gate.signing());
  EXPECT_FALSE(gate.accepts_at_once("lab-a", ""));  // signatures are always checked
  auto signer = stamp_for("lab-a", test_key());
  auto laptop = stamp_for("lab-a", std::nullopt, 99);
  auto other = stamp_for("lab-a", test_key(6), 98);
  const std::string ch = "SPINDOWN.b1.FIT";
  const auto first = signer.encode(ch, fit_at());
  const auto second = signer.encode(ch, fit_at());
  const auto check = [&](const std::vector<unsigned char>& b, std::int64_t at = t0) {
    return gate.check(ch, b.data(), std::int64_t(b.size()), at);
  };
  EXPECT_TRUE(check(first).accepted());
  EXPECT_TRUE(check(second).accepted());
  EXPECT_EQ(check(first).verdict, GateVerdict::replayed) << "an old message sent again";
  EXPECT_EQ(check(second).verdict, GateVerdict::replayed);
  const GateResult unsigned_one = check(laptop.encode(ch, fit_at()));
  EXPECT_EQ(unsigned_one.verdict, GateVerdict::not_signed);
  EXPECT_NE(unsigned_one.text.find("not signed, and this lab signs its messages"), std::string::npos) << unsigned_one.text;
  EXPECT_EQ(check(other.encode(ch, fit_at())).verdict, GateVerdict::other_key);
  auto forged = signer.encode(ch, fit_at());
  forged[40] ^= 0x20;  // a number changed after signing
  EXPECT_EQ(check(forged).verdict, GateVerdict::bad_signature);
  // Sent on another channel than the one it was signed for.
  const auto moved = signer.encode("SPINDOWN.b2.FIT", fit_at());
  EXPECT_EQ(check(moved).verdict, GateVerdict::bad_signature);
  // A source first heard with a message sent long before it arrives: outside the window (an old
  // capture sent again after a restart); within it, accepted.
  auto restarted = stamp_for("lab-a", test_key(), 77);
  fit_t late = fit_at();
  late.utime = t0 - 120'000'000;
  EXPECT_EQ(check(restarted.encode(ch, late)).verdict, GateVerdict::outside_window);
  late.utime = t0 - 30'000'000;
  EXPECT_TRUE(check(restarted.encode(ch, late)).accepted());
  // A known source whose wall clock stepped back 2 minutes (NTP, a laptop waking): its numbers
  // still rise, so it is live, not a replay (issue 42).
  late.utime = t0 - 150'000'000;
  EXPECT_TRUE(check(signer.encode(ch, late)).accepted());
  const GateCounters& c = gate.counters();
  EXPECT_EQ(c.accepted, 4);
  EXPECT_EQ(c.replayed, 2);
  EXPECT_EQ(c.not_signed, 1);
  EXPECT_EQ(c.other_key, 1);
  EXPECT_EQ(c.bad_signature, 2);
  EXPECT_EQ(c.outside_window, 1);
  EXPECT_EQ(c.refused(), 7);
}

// A network reorders datagrams: a late signed message never seen is taken, a copy is a replay, and
// one further back than the window can tell is refused as too old.
TEST(MessageGate, ALateSignedDatagramIsNotAReplay) {
  MessageGate gate(options("lab-a", test_key()));
  auto signer = stamp_for("lab-a", test_key());
  const std::string ch = "SPINDOWN.b1.SAMPLE";
  std::vector<std::vector<unsigned char>> sent;
  for (int i = 0; i < 1100; ++i) sent.push_back(signer.encode(ch, samples_at(t0)));
  const auto check = [&](std::size_t i) { return gate.check(ch, sent[i].data(), std::int64_t(sent[i].size()), t0); };
  EXPECT_TRUE(check(0).accepted());
  EXPECT_TRUE(check(3).accepted());
  EXPECT_TRUE(check(1).accepted()) << "late, never seen";
  EXPECT_TRUE(check(2).accepted());
  EXPECT_EQ(check(1).verdict, GateVerdict::replayed) << "a copy";
  EXPECT_EQ(check(3).verdict, GateVerdict::replayed);
  EXPECT_TRUE(check(1090).accepted());
  const GateResult old = check(4);  // 1086 behind the newest
  EXPECT_EQ(old.verdict, GateVerdict::replayed);
  EXPECT_NE(old.text.find("too old to be told from a replay"), std::string::npos) << old.text;
  EXPECT_TRUE(check(1000).accepted());
  EXPECT_EQ(gate.counters().accepted, 6);
}

// Replays are judged per source and channel: another channel's or another source's counts do not
// refuse a message; the state stays bounded.
TEST(MessageGate, ReplayStateIsPerSourceAndChannelAndBounded) {
  MessageGate gate(options("lab-a", test_key(), 2));
  auto a = stamp_for("lab-a", test_key(), 1);
  auto b = stamp_for("lab-a", test_key(), 2);
  const auto a1 = a.encode("SPINDOWN.x.SAMPLE", samples_at(t0));
  const auto a2 = a.encode("SPINDOWN.y.SAMPLE", samples_at(t0));  // a's counter goes on across channels
  const auto b1 = b.encode("SPINDOWN.x.SAMPLE", samples_at(t0));
  EXPECT_TRUE(gate.check("SPINDOWN.y.SAMPLE", a2.data(), std::int64_t(a2.size()), t0).accepted());
  EXPECT_TRUE(gate.check("SPINDOWN.x.SAMPLE", a1.data(), std::int64_t(a1.size()), t0).accepted());
  EXPECT_TRUE(gate.check("SPINDOWN.x.SAMPLE", b1.data(), std::int64_t(b1.size()), t0).accepted());
}

TEST(MessageGate, UndecodableIsLeftToTheDecoder) {
  MessageGate gate(options("lab-a", test_key()));
  const std::vector<unsigned char> junk(30, 1);
  const GateResult r = gate.check("SPINDOWN.b.SAMPLE", junk.data(), 30, t0);
  EXPECT_EQ(r.verdict, GateVerdict::undecodable);
  EXPECT_FALSE(r.refused());
  EXPECT_FALSE(r.accepted());
}

TEST(MessageStamp, FillsTheSourceFieldsAndCountsMessages) {
  auto s = stamp_for("lab-x", std::nullopt, 77);
  status_t st{};
  s.stamp(st);
  EXPECT_EQ(st.lab, "lab-x");
  EXPECT_EQ(st.source_host, "bench-pc");
  EXPECT_EQ(st.source_session, 77);
  EXPECT_EQ(st.source_seq, 1);
  EXPECT_EQ(st.start_utime, t0);
  samples_t m{};
  s.stamp(m);
  EXPECT_EQ(m.source_seq, 2);
  EXPECT_EQ(s.sent(), 2);
  const SourceIdentity me = this_process_identity("lab-y", "udpm://239.255.76.68:7668?ttl=1");
  EXPECT_EQ(me.sent_to, "239.255.76.68:7668");
  EXPECT_NE(me.session, 0u);
  EXPECT_NE(me.session, this_process_identity("lab-y", "").session);
  EXPECT_FALSE(me.host.empty());
}

// Every program builds its gate one way: the lab's name and key, and the group and port it listens
// on (another group's traffic on that port is another lab's); a log reader checks no destination.
TEST(MessageGate, TheLabGateOfAListenerAndOfALogReader) {
  LabSettings lab;
  lab.lab = "lab-a";
  lab.key = test_key();
  const MessageGateOptions live = lab_gate(lab, "udpm://239.255.76.67:7667?ttl=0");
  EXPECT_EQ(live.lab, "lab-a");
  ASSERT_TRUE(live.key.has_value());
  EXPECT_EQ(live.key->id, test_key().id);
  EXPECT_EQ(live.sent_to, "239.255.76.67:7667");
  EXPECT_EQ(live.replay_window_s, MessageGateOptions{}.replay_window_s);
  EXPECT_TRUE(lab_gate(lab).sent_to.empty());
}

// While keys change, a gate given the old key as well accepts both signers; one without it names
// the old key and the way to give both.
TEST(MessageGate, BothKeysWhileTheKeyChanges) {
  auto old_signer = stamp_for("lab-a", test_key(5), 1);
  auto new_signer = stamp_for("lab-a", test_key(6), 2);
  MessageGateOptions o = options("lab-a", test_key(6));
  o.also_accepted.push_back(test_key(5));
  MessageGate both(o);
  MessageGate new_only(options("lab-a", test_key(6)));
  const std::string ch = "SPINDOWN.b1.SAMPLE";
  const auto a = old_signer.encode(ch, samples_at(t0));
  const auto b = new_signer.encode(ch, samples_at(t0));
  EXPECT_TRUE(both.check(ch, a.data(), std::int64_t(a.size()), t0).accepted());
  EXPECT_TRUE(both.check(ch, b.data(), std::int64_t(b.size()), t0).accepted());
  const GateResult r = new_only.check(ch, a.data(), std::int64_t(a.size()), t0);
  EXPECT_EQ(r.verdict, GateVerdict::other_key);
  EXPECT_NE(r.text.find("--key NEW,OLD"), std::string::npos) << r.text;
  auto forged = old_signer.encode(ch, samples_at(t0));
  forged[30] ^= 0x10;
  EXPECT_EQ(both.check(ch, forged.data(), std::int64_t(forged.size()), t0).verdict, GateVerdict::bad_signature);
}

}  // namespace
}  // namespace spindown
