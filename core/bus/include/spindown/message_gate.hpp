#pragma once
// What a reader lets through (issue 31): a received message's bytes, before anything uses them.
// The lab first — a message of another lab is counted and named, never used, with or without
// signatures — then, with the lab key, its signature (verify_message) and replays: a signed
// message's source_seq must not have been seen from its source on its channel (a sliding window of
// the last seq_window numbers, as IPsec's anti-replay window: a network that reorders datagrams
// does not make a late one a replay), and the first message of a source must have been sent
// within replay_window_s of its receive time (its utime), so an old message sent again after a
// restart is refused. Once a source is known its source_seq alone tells a replay: a wall clock
// stepped on either PC (NTP, a laptop waking) does not refuse a live bench (issue 42). The fitter (FitterCore, live and refit), the logger (it records
// everything and counts), `spindown watch` and the log reader all take messages through one.
//
// Bounded: the replay state keeps max_sources (source, channel) pairs, the oldest forgotten
// first; only messages whose signature is valid enter it.
#include <bitset>
#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "spindown/lab_key.hpp"
#include "spindown/lab_settings.hpp"
#include "spindown/message_auth.hpp"
#include "spindown/message_decode.hpp"
#include "spindown/session_id.hpp"

namespace spindown {

// Whether two udpm destinations ("GROUP:PORT") name the same port: a message sent to another group
// on this port reached this socket through the kernel (another lab's traffic); one sent to another
// port was replayed or relayed here.
bool same_port(std::string_view a, std::string_view b);

struct MessageGateOptions {
  std::string lab = "lab";               // this program's lab; "" takes every lab
  std::string sent_to;                   // the udpm GROUP:PORT it listens on; "" takes every group (logs)
  std::optional<LabKey> key;             // signatures required when set
  std::vector<LabKey> also_accepted;     // and these keys' signatures accepted too (a rotation)
  double replay_window_s = 60;           // signed: |receive time − utime| at most this
  std::size_t max_sources = 4096;        // (source, channel) pairs remembered for replays
  // Every lab's messages, no key (a library reader's default: the caller narrows it).
  static MessageGateOptions every_lab() {
    MessageGateOptions o;
    o.lab.clear();
    return o;
  }
};

enum class GateVerdict {
  accepted,
  undecodable,    // not a spindown message: the caller's decoder names it
  other_lab,      // lab field names another lab
  not_signed,     // signatures required, none
  other_key,      // signed with another key
  bad_signature,  // this key's id, the signature does not match (forged or damaged)
  replayed,       // a signed message not newer than the last seen from its source on its channel
  outside_window, // a signed message whose utime is more than replay_window_s from its receive time
};
std::string_view gate_verdict_name(GateVerdict v);  // "accepted", "other lab", "not signed", …

struct GateResult {
  GateVerdict verdict = GateVerdict::accepted;
  MessageTrailer trailer;  // the message's source fields (empty when undecodable)
  std::string text;        // why it was refused, naming the channel and the source ("" when accepted)
  bool accepted() const { return verdict == GateVerdict::accepted; }
  bool refused() const { return verdict != GateVerdict::accepted && verdict != GateVerdict::undecodable; }
};

struct GateCounters {
  std::int64_t accepted = 0, undecodable = 0, other_lab = 0, not_signed = 0, other_key = 0, bad_signature = 0,
               replayed = 0, outside_window = 0;
  std::int64_t refused() const { return other_lab + not_signed + other_key + bad_signature + replayed + outside_window; }
};

class MessageGate {
 public:
  explicit MessageGate(MessageGateOptions options = {});

  // The message as received on channel at recv_utime (µs since the epoch; the log's time in a
  // refit). A message with no lab ("" or from before the field existed) is this lab's; one sent
  // to another group (sent_to) than the one this program listens on is another lab's.
  GateResult check(std::string_view channel, const void* data, std::int64_t size, std::int64_t recv_utime);

  // A message whose lab and sent_to fields are these is accepted without more (no key, this lab
  // or none, this group or none): the check a reader of SamplesView makes per message before
  // check(). Counted.
  bool accepts_at_once(std::string_view lab, std::string_view sent_to) {
    if (o_.key || !(o_.lab.empty() || lab.empty() || lab == o_.lab) ||
        !(o_.sent_to.empty() || sent_to.empty() || sent_to == o_.sent_to))
      return false;
    ++counters_.accepted;
    return true;
  }

  const MessageGateOptions& options() const { return o_; }
  bool signing() const { return o_.key.has_value(); }
  const GateCounters& counters() const { return counters_; }

 private:
  struct PairKey {
    std::uint64_t session;
    std::string channel;
    bool operator==(const PairKey&) const = default;
  };
  struct PairHash {
    std::size_t operator()(const PairKey& k) const;
  };
  MessageGateOptions o_;
  GateCounters counters_;
  static constexpr std::int64_t seq_window = 1024;
  struct Seen {
    std::int64_t high = 0;               // highest source_seq accepted
    std::bitset<seq_window> below;       // bit i: high - i accepted
  };
  std::unordered_map<PairKey, Seen, PairHash> last_seq_;
  std::deque<PairKey> order_;                                     // insertion order, for the bound
};

// The gate of a program of lab `lab` (its name and key) listening on lcm_url: the one way every
// program builds it (fitter, logger, watch, web; refit and the log readers with lcm_url "", where
// no destination is checked). The replay window stays the default unless the caller sets it.
MessageGateOptions lab_gate(const LabSettings& lab, const std::string& lcm_url = "");

}  // namespace spindown
