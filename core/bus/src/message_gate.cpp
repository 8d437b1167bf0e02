#include "spindown/message_gate.hpp"

#include <cmath>
#include <fmt/format.h>
#include <functional>

#include "spindown/lcm_url.hpp"
#include "spindown/session_id.hpp"

namespace spindown {

std::string_view gate_verdict_name(GateVerdict v) {
  switch (v) {
    case GateVerdict::accepted: return "accepted";
    case GateVerdict::undecodable: return "undecodable";
    case GateVerdict::other_lab: return "other lab";
    case GateVerdict::not_signed: return "not signed";
    case GateVerdict::other_key: return "other key";
    case GateVerdict::bad_signature: return "bad signature";
    case GateVerdict::replayed: return "replayed";
    case GateVerdict::outside_window: return "outside the replay window";
  }
  return "?";
}

std::size_t MessageGate::PairHash::operator()(const PairKey& k) const {
  return std::hash<std::string>()(k.channel) ^ (std::hash<std::uint64_t>()(k.session) * 0x9e3779b97f4a7c15ull);
}

bool same_port(std::string_view a, std::string_view b) {
  const auto port = [](std::string_view to) {
    const std::size_t colon = to.rfind(':');
    return colon == std::string_view::npos ? std::string_view() : to.substr(colon + 1);
  };
  return port(a) == port(b);
}

MessageGate::MessageGate(MessageGateOptions options) : o_(std::move(options)) {}

GateResult MessageGate::check(std::string_view channel, const void* data, std::int64_t size, std::int64_t recv_utime) {
  GateResult r;
  std::string why;
  if (!read_message_trailer(data, size, r.trailer, &why)) {
    r.verdict = GateVerdict::undecodable;
    r.text = fmt::format("{}: {}", channel, why);
    ++counters_.undecodable;
    return r;
  }
  const MessageTrailer& t = r.trailer;
  const auto refuse = [&](GateVerdict v, std::int64_t& counter, std::string text) {
    r.verdict = v;
    r.text = fmt::format("{}: {} from {}: {}; not used", channel, t.type, source_text(t.source_host, t.source_session),
                         text);
    ++counter;
    return r;
  };
  if (!o_.lab.empty() && !t.lab.empty() && t.lab != o_.lab)
    return refuse(GateVerdict::other_lab, counters_.other_lab,
                  fmt::format("a message of lab '{}', this program serves lab '{}' (two labs on one network: give "
                              "each its own multicast group and port, docs/lab-setup.md)",
                              shown_name(t.lab), o_.lab));
  // Sent to another group on this port: Linux hands every group joined on a port to each socket
  // bound to it, so that is another lab's live traffic. Sent to another port, it did not reach this
  // socket by that trap: a log replayed (or relayed) here on purpose, as README's replay recipe does.
  if (!o_.sent_to.empty() && !t.sent_to.empty() && t.sent_to != o_.sent_to && same_port(t.sent_to, o_.sent_to))
    return refuse(GateVerdict::other_lab, counters_.other_lab,
                  fmt::format("sent to {}, not to {} where this program listens: another lab's traffic on this "
                              "port (Linux hands every group joined on a port to each socket bound to that port: "
                              "give each lab its own port too, docs/lab-setup.md)",
                              shown_name(t.sent_to), o_.sent_to));
  if (!o_.key) {
    ++counters_.accepted;
    return r;
  }
  const LabKey* chosen = &*o_.key;  // the key the message names, when it is one accepted
  for (const LabKey& k : o_.also_accepted)
    if (t.auth_key_id == k.id && t.auth_key_id != o_.key->id) chosen = &k;
  const LabKey& key = *chosen;
  const AuthCheck a = verify_message(channel, data, size, key);
  switch (a.status) {
    case AuthStatus::valid: break;
    case AuthStatus::not_signed:
      return refuse(GateVerdict::not_signed, counters_.not_signed,
                    fmt::format("not signed, and this lab signs its messages (key {})", key_id_text(key.id)));
    case AuthStatus::other_key:
      return refuse(GateVerdict::other_key, counters_.other_key,
                    fmt::format("signed with key {}, not this lab's key {} (another lab's key, or an old one: "
                                "while keys change, give both, --key NEW,OLD, docs/security.md)",
                                key_id_text(t.auth_key_id), key_id_text(key.id)));
    case AuthStatus::bad_signature:
      return refuse(GateVerdict::bad_signature, counters_.bad_signature,
                    "the signature does not match the message (forged, or changed on the way)");
    case AuthStatus::malformed:
      return refuse(GateVerdict::bad_signature, counters_.bad_signature, a.why + ": its signature cannot be checked");
  }
  PairKey k{t.source_session, std::string(channel)};
  auto it = last_seq_.find(k);
  if (it == last_seq_.end()) {  // a source first heard: its clock must agree with this one's
    const double skew_s = 1e-6 * double(recv_utime - t.utime);
    if (!(std::abs(skew_s) <= o_.replay_window_s))
      return refuse(GateVerdict::outside_window, counters_.outside_window,
                    fmt::format("sent {:.1f} s {} it was received, beyond the {:g} s replay window: an old message "
                                "sent again, or that host's clock is off (spindown doctor --listen measures it)",
                                std::abs(skew_s), skew_s >= 0 ? "before" : "after", o_.replay_window_s));
    if (o_.max_sources > 0 && last_seq_.size() >= o_.max_sources) {
      last_seq_.erase(order_.front());
      order_.pop_front();
    }
    Seen seen;
    seen.high = t.source_seq;
    seen.below.set(0);
    last_seq_.emplace(k, seen);
    order_.push_back(std::move(k));
    ++counters_.accepted;
    return r;
  }
  Seen& seen = it->second;
  if (t.source_seq > seen.high) {
    const std::int64_t ahead = t.source_seq - seen.high;
    seen.below = ahead >= seq_window ? std::bitset<seq_window>{} : seen.below << static_cast<std::size_t>(ahead);
    seen.below.set(0);
    seen.high = t.source_seq;
  } else {
    const std::int64_t behind = seen.high - t.source_seq;
    if (behind >= seq_window || seen.below.test(static_cast<std::size_t>(behind)))
      return refuse(GateVerdict::replayed, counters_.replayed,
                    behind >= seq_window
                        ? fmt::format("message {} of that source, {} behind the newest ({}) on this channel: too old "
                                      "to be told from a replay",
                                      t.source_seq, behind, seen.high)
                        : fmt::format("message {} of that source again (already seen on this channel): a replay",
                                      t.source_seq));
    seen.below.set(static_cast<std::size_t>(behind));  // a late datagram, not seen before
  }
  ++counters_.accepted;
  return r;
}

MessageGateOptions lab_gate(const LabSettings& lab, const std::string& lcm_url) {
  MessageGateOptions g;
  g.lab = lab.lab;
  g.key = lab.key;
  g.also_accepted = lab.also_accepted;
  // Another group's traffic on this port is another lab's (message_gate.cpp check()).
  if (!lcm_url.empty()) g.sent_to = lcm_destination(lcm_url);
  return g;
}

}  // namespace spindown
