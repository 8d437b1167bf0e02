#pragma once
// Who sends a message (issue 31): every program that publishes has one MessageStamp, made at its
// start, that fills the fields ending every type (lcmtypes/*.lcm) — its lab, host and session (a
// random 64-bit id: a restarted program is a new source), a count of the messages it sent — and,
// with the lab key, signs them (message_auth.hpp). LcmLoop::publish and the bridge's sink encode
// through it, so no message leaves a program without them.
#include <atomic>
#include <cstdint>
#include <cstring>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include <spindown/status_t.hpp>

#include "spindown/lab_key.hpp"

namespace spindown {

struct SourceIdentity {
  std::string lab;                // the lab's name (lab_name.hpp)
  std::string sent_to;            // the udpm GROUP:PORT it publishes on (lcm_destination)
  std::string host;               // host_name()
  std::uint64_t session = 0;      // new_session_id()
  std::int64_t start_utime = 0;   // when the process started (µs since the epoch)
};
// This process publishing on lcm_url ("" = LCM's default): host_name(), a new session id,
// start_utime now.
SourceIdentity this_process_identity(std::string lab, const std::string& lcm_url);

class MessageStamp {
 public:
  explicit MessageStamp(SourceIdentity identity, std::optional<LabKey> key = std::nullopt)
      : id_(std::move(identity)), key_(std::move(key)) {}

  const SourceIdentity& identity() const { return id_; }
  bool signing() const { return key_.has_value(); }
  const std::optional<LabKey>& key() const { return key_; }
  std::int64_t sent() const { return seq_.load(std::memory_order_relaxed); }

  // The source fields of m (not signed: auth_key_id 0, auth zeros); status_t's start_utime too
  // when it is 0. Each call counts one message.
  template <class Msg>
  void stamp(Msg& m) {
    m.lab = id_.lab;
    m.sent_to = id_.sent_to;
    m.source_host = id_.host;
    m.source_session = static_cast<std::int64_t>(id_.session);
    m.source_seq = seq_.fetch_add(1, std::memory_order_relaxed) + 1;
    m.auth_key_id = 0;
    std::memset(m.auth, 0, sizeof m.auth);
    if constexpr (std::is_same_v<Msg, status_t>)
      if (m.start_utime == 0) m.start_utime = id_.start_utime;
  }

  // m stamped, encoded and (with a key) signed for channel: the bytes to publish. Empty only when
  // the message cannot be encoded (then nothing should be sent).
  template <class Msg>
  std::vector<unsigned char> encode(std::string_view channel, Msg m) {
    stamp(m);
    std::vector<unsigned char> bytes(static_cast<std::size_t>(m.getEncodedSize()));
    if (m.encode(bytes.data(), 0, static_cast<int>(bytes.size())) != static_cast<int>(bytes.size())) return {};
    if (key_ && !sign(channel, bytes)) return {};
    return bytes;
  }

 private:
  bool sign(std::string_view channel, std::vector<unsigned char>& bytes) const;

  SourceIdentity id_;
  std::optional<LabKey> key_;
  std::atomic<std::int64_t> seq_{0};
};

}  // namespace spindown
