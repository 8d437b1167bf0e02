#pragma once
// spindown-web as a whole: LCM in (read-only: it subscribes to SPINDOWN.* and publishes nothing),
// HTTP out. LCM's thread takes every message through the check (message signing, when the lab
// signs: one call per message, before it is decoded; a refused message is counted and named,
// never shown), decodes it (decode_message: hostile bytes cannot hurt) and feeds the WebLab;
// every flush_period_s it hands the changes to the pages (EventFanout). The HTTP threads read
// the lab under the same mutex. systemd's watchdog is fed from the LCM loop while the HTTP
// server runs.
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>

#include "spindown/message_gate.hpp"
#include "spindown/event_fanout.hpp"
#include "spindown/lcm_loop.hpp"
#include "spindown/web_lab.hpp"
#include "spindown/web_server.hpp"

namespace spindown {

class StopSignals;

// A received message's bytes → nullopt to accept it, or the gate's verdict and words when it is
// refused ("SPINDOWN.b1.FIT: … not signed …"). MessageGate::check (bus) is this hook.
using MessageCheck = std::function<std::optional<GateResult>(std::string_view channel, const void* data,
                                                             std::int64_t size, std::int64_t recv_utime)>;

struct WebServiceOptions {
  std::string lcm_url;           // "" = LCM_DEFAULT_URL or LCM's default
  WebLabOptions lab;
  EventFanoutOptions fanout;
  WebServerOptions server;
  double flush_period_s = 0.1;   // changes pushed to the pages this often
  MessageCheck check;            // empty: every well-formed message is taken
};

class WebService {
 public:
  explicit WebService(WebServiceOptions options);
  ~WebService();

  // LCM started and subscribed, and the HTTP address bound; otherwise false and *why.
  bool start(std::string* why);
  // The URL the pages are at ("http://HOST:PORT/").
  std::string url() const;
  // Until SIGINT/SIGTERM (or LCM keeps failing); 0, or 1 when LCM failed.
  int run(const StopSignals& stop);

  // Feeds one received message as LCM's thread does (tests and benchmarks without LCM).
  void take(std::string_view channel, const void* data, std::int64_t size, std::int64_t recv_utime);
  // Pushes what changed to the pages (the flush timer's work).
  void flush(std::int64_t now_us);

  WebLab& lab() { return lab_; }
  std::mutex& mutex() { return mutex_; }
  EventFanout& fanout() { return fanout_; }

 private:
  WebServiceOptions opt_;
  std::mutex mutex_;
  WebLab lab_;
  EventFanout fanout_;
  std::unique_ptr<LcmLoop> loop_;
  std::unique_ptr<WebServer> server_;
};

}  // namespace spindown
