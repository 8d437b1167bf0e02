#pragma once
// Who is on the lab's group and port, for `spindown doctor` (issue 31): every SPINDOWN.* message
// heard while it listens names its lab, host and session (the fields ending every type), and
// whether it is signed. From them: another lab's traffic on this group and port (the two labs'
// services then hear each other: give each lab its own group and port), senders that name no lab
// (programs from before labs were named), unsigned or wrongly signed messages when this lab signs,
// a bench channel with two sources alive at once, and two instances of one service name; and
// messages sent to another group that reach this PC's port (the one-PC-serves-two-labs trap).
// Bounded: at most max_entries labs, hosts and channels are remembered.
#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include <spindown/status_t.hpp>

#include "spindown/doctor_check.hpp"
#include "spindown/lab_key.hpp"
#include "spindown/message_decode.hpp"
#include "spindown/service_instances.hpp"

namespace spindown {

class LabTraffic {
 public:
  explicit LabTraffic(std::size_t max_entries = 256) : max_(max_entries) {}

  // A message heard on channel (SPINDOWN.<id>.<KIND>) at recv_us; status when it is a STATUS that
  // decoded. key: this lab's key, when the doctor has one (signatures are then checked).
  void add(std::string_view channel, const void* data, std::int64_t size, std::int64_t recv_us,
           const status_t* status, const LabKey* key);

  struct Lab {
    std::int64_t messages = 0;
    std::map<std::string, std::set<std::string>> senders;  // host -> "bridge bench-1", "fitter fitter", …
  };
  const std::map<std::string, Lab>& labs() const { return labs_; }  // "" = names no lab
  // The same by the udpm group:port each message says it was sent to ("" = not said).
  const std::map<std::string, Lab>& destinations() const { return destinations_; }
  std::int64_t messages() const { return messages_; }

  // The checks: "lab traffic" (another lab, unnamed senders), "signatures" (with a key), "two
  // sources SPINDOWN.<b>.SAMPLE", "instances <service> <name>". url: the URL listened on.
  std::vector<DoctorCheck> checks(const std::string& our_lab, const std::optional<LabKey>& key, const std::string& url,
                                  double listened_s, std::int64_t now_us) const;

 private:
  struct Source {
    std::string host;
    std::uint64_t session = 0;
    std::int64_t first_us = 0, last_us = 0;
  };
  std::size_t max_;
  std::int64_t messages_ = 0;
  std::map<std::string, Lab> labs_;
  std::map<std::string, Lab> destinations_;
  std::map<std::string, std::vector<Source>> sample_sources_;  // "lab\nsent_to\nchannel" -> sources heard
  std::map<std::string, ServiceInstances> services_;            // "lab\nsent_to\nservice\ninstance"
  std::map<std::string, std::string> collisions_;               // same key -> the words naming it
  std::map<std::string, std::int64_t> auth_;                    // "not signed", "other key", … -> count
  std::map<std::string, std::set<std::string>> auth_hosts_;     // the same -> hosts
};

}  // namespace spindown
