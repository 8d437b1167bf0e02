// What `spindown doctor` says about who sends on the lab's group and port: another lab's traffic
// (named, with the fix: another group AND port), senders that name no lab, unsigned messages with
// the key, a bench with two sources at once, two fitters with one name.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <string>
#include <vector>

#include "spindown/lab_traffic.hpp"
#include "spindown/message_stamp.hpp"

namespace spindown {
namespace {

constexpr std::int64_t t0 = 1'700'000'000'000'000;

struct Sender {
  MessageStamp stamp;
  Sender(std::string lab, std::string host, std::uint64_t session, std::optional<LabKey> key = std::nullopt)
      : stamp(SourceIdentity{std::move(lab), "239.255.76.67:7667", std::move(host), session, t0}, std::move(key)) {}
  template <class Msg>
  void send(LabTraffic& traffic, const std::string& channel, Msg m, std::int64_t at, const LabKey* key = nullptr) {
    const auto bytes = stamp.encode(channel, m);
    status_t decoded{};
    const bool is_status = channel.ends_with(".STATUS") && decode_message(decoded, bytes.data(), std::int64_t(bytes.size()));
    traffic.add(channel, bytes.data(), std::int64_t(bytes.size()), at, is_status ? &decoded : nullptr, key);
  }
};

samples_t sample(std::int64_t seq) {
  samples_t m{};
  m.bench = "bench-1";
  m.seq = seq;
  m.n = 1;
  m.device_time_us = {seq * 20000};
  m.host_time_us = {0};
  m.value = {1.0};
  m.raw_adc = {-1};
  return m;
}

status_t fitter(const std::string& host, int pid) {
  status_t s{};
  s.service = "fitter";
  s.instance = "fitter";
  s.host = host;
  s.pid = pid;
  return s;
}

const DoctorCheck* find(const std::vector<DoctorCheck>& checks, const std::string& name) {
  for (const auto& c : checks)
    if (c.name == name) return &c;
  return nullptr;
}

TEST(LabTraffic, AnotherLabOnTheGroupAndPortIsNamedWithTheFix) {
  LabTraffic traffic;
  Sender a("physics-a", "pc-a", 1), b("physics-b", "pc-b", 2);
  for (int i = 0; i < 10; ++i) {
    a.send(traffic, "SPINDOWN.bench-1.SAMPLE", sample(i), t0 + i * 20000);
    b.send(traffic, "SPINDOWN.bench-1.SAMPLE", sample(i), t0 + i * 20000 + 1000);
  }
  b.send(traffic, "SPINDOWN.fitter.STATUS", fitter("pc-b", 7), t0);
  const auto checks = traffic.checks("physics-a", std::nullopt, "udpm://239.255.76.67:7667?ttl=1", 3, t0);
  const DoctorCheck* c = find(checks, "lab traffic");
  ASSERT_NE(c, nullptr);
  EXPECT_EQ(c->level, CheckLevel::warn);
  EXPECT_NE(c->detail.find("another lab's traffic on udpm://239.255.76.67:7667?ttl=1 (this PC's lab is 'physics-a', 10 "
                           "of its messages heard): lab 'physics-b': 11 messages from host pc-b (bridge bench-1, fitter "
                           "fitter)"),
            std::string::npos)
      << c->detail;
  EXPECT_NE(c->fix.find("its own multicast group AND port"), std::string::npos);
  EXPECT_NE(c->fix.find("Linux hands every group joined on a port to each socket bound to that port"), std::string::npos);
  EXPECT_EQ(find(checks, "two sources SPINDOWN.bench-1.SAMPLE"), nullptr) << "two labs' benches are not two sources";
}

TEST(LabTraffic, OneLabAloneIsOkAndItsFaultsAreNamed) {
  LabTraffic traffic;
  std::array<unsigned char, lab_key_bytes> kb{};
  kb.fill(3);
  const LabKey key = lab_key_from_bytes(kb);
  Sender bridge("lab", "pc-a", 1, key), second("lab", "pc-b", 2, key), laptop("lab", "laptop", 3);
  Sender f1("lab", "pc-a", 4, key), f2("lab", "pc-c", 5, key);
  for (int i = 0; i < 10; ++i) {
    bridge.send(traffic, "SPINDOWN.bench-1.SAMPLE", sample(i), t0 + i * 20000, &key);
    second.send(traffic, "SPINDOWN.bench-1.SAMPLE", sample(100 + i), t0 + i * 20000 + 5000, &key);
  }
  laptop.send(traffic, "SPINDOWN.bench-1.FIT", fit_t{}, t0, &key);
  f1.send(traffic, "SPINDOWN.fitter.STATUS", fitter("pc-a", 10), t0, &key);
  f2.send(traffic, "SPINDOWN.fitter.STATUS", fitter("pc-c", 20), t0 + 1000, &key);
  const auto checks = traffic.checks("lab", key, "udpm://239.255.76.67:7667?ttl=1", 3, t0);
  const DoctorCheck* lab = find(checks, "lab traffic");
  ASSERT_NE(lab, nullptr);
  EXPECT_EQ(lab->level, CheckLevel::ok) << lab->detail;
  const DoctorCheck* sig = find(checks, "signatures");
  ASSERT_NE(sig, nullptr);
  EXPECT_EQ(sig->level, CheckLevel::warn);
  EXPECT_NE(sig->detail.find("1 not signed (from laptop)"), std::string::npos) << sig->detail;
  const DoctorCheck* two = find(checks, "two sources SPINDOWN.bench-1.SAMPLE");
  ASSERT_NE(two, nullptr);
  EXPECT_NE(two->detail.find("has two sources: host pc-a (session 0000000000000001) and host pc-b"), std::string::npos)
      << two->detail;
  const DoctorCheck* inst = find(checks, "instances fitter fitter");
  ASSERT_NE(inst, nullptr) << "two fitters named 'fitter'";
  EXPECT_NE(inst->detail.find("pid 10"), std::string::npos);
  EXPECT_NE(inst->detail.find("pid 20"), std::string::npos);
}

TEST(LabTraffic, NothingHeardIsASkipAndUnnamedSendersAreSaid) {
  LabTraffic quiet;
  EXPECT_EQ(quiet.checks("lab", std::nullopt, "u", 3, t0).front().level, CheckLevel::skip);
  LabTraffic traffic;
  samples_t old = sample(1);  // a sender from before labs were named
  std::vector<unsigned char> bytes(static_cast<std::size_t>(old.getEncodedSize()));
  old.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  traffic.add("SPINDOWN.bench-9.SAMPLE", bytes.data(), std::int64_t(bytes.size()), t0, nullptr, nullptr);
  const auto checks = traffic.checks("lab", std::nullopt, "u", 3, t0);
  const DoctorCheck* c = find(checks, "unnamed senders");
  ASSERT_NE(c, nullptr);
  EXPECT_NE(c->detail.find("1 message name no lab"), std::string::npos) << c->detail;
}

}  // namespace
}  // namespace spindown
