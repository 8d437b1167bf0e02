#pragma once
// What a service knows of its own publishing. LCM's udpm publish is a sendmsg: with the
// multicast route gone (an interface taken down and up loses its 224.0.0.0/4 route) it fails
// with "Network is unreachable", and with the route pointing elsewhere it succeeds and the
// datagrams go nowhere the lab listens. PublishHealth counts both: sends that failed (LCM's
// result, with errno's text) and the service's own heartbeats that never came back to it
// (multicast loopback delivers them to its own subscription when they go out on the group's
// interface). It says so on stderr at most once per report_every_s, and once when it recovers,
// and keeps the counts for the heartbeat, so they reach the network once the route is back.
//
// sent() and heartbeat_sent() from the publishing thread, echoed() from the LCM loop's thread.
#include <cstdint>
#include <mutex>
#include <string>
#include <string_view>

namespace spindown {

struct PublishHealthOptions {
  std::string program = "spindown";  // stderr prefix
  double report_every_s = 10.0;       // at most one line per this many seconds while failing
  double echo_grace_s = 3.0;          // a heartbeat not back after this long is unheard
};

class PublishHealth {
 public:
  explicit PublishHealth(PublishHealthOptions options = {});

  // After each publish: rc is LCM's result (0: sent); on failure errno is read here, so call it
  // right after the publish.
  void sent(int rc, std::string_view channel, std::int64_t now_us);
  // After publishing a heartbeat stamped utime (rc as for sent(), which it calls). judge_echo
  // false: the service itself was stalled (its own backlog holds the echo), so none is counted
  // unheard now.
  void heartbeat_sent(int rc, std::string_view channel, std::int64_t utime, std::int64_t now_us,
                      bool judge_echo = true);
  // One of the service's own heartbeats (stamped utime) came back.
  void echoed(std::int64_t utime);

  std::int64_t failures() const;          // sends that failed
  std::int64_t unheard_heartbeats() const;  // heartbeats checked and not back within echo_grace_s
  std::string last_error() const;         // the last failure in words ("" when none)
  std::int64_t last_error_utime() const;

 private:
  void report(std::int64_t now_us, const std::string& text);  // rate-limited; lock held
  void check_echo(std::int64_t now_us);                       // lock held

  PublishHealthOptions opt_;
  mutable std::mutex mutex_;
  std::int64_t failures_ = 0, unheard_ = 0;
  bool failing_ = false, deaf_ = false;
  std::int64_t next_report_us_ = 0;
  std::int64_t oldest_unechoed_us_ = 0;  // send time of the oldest heartbeat not yet back (0: none)
  std::int64_t oldest_unechoed_utime_ = 0;
  std::int64_t echoed_utime_ = 0;        // newest heartbeat stamp that came back
  std::string last_error_;
  std::int64_t last_error_utime_ = 0;
};

}  // namespace spindown
