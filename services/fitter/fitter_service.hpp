#pragma once
// spindown-fitter's LCM shell around FitterCore. The LCM loop only copies each message into
// a bounded queue (so a fit never stalls reception and LCM's own queue never overflows); one
// worker thread feeds the core in arrival order, publishes RUN and FIT, and the heartbeat on
// SPINDOWN.<instance>.STATUS.
#include <atomic>
#include <map>
#include <string_view>
#include <cstdint>
#include <string>
#include <thread>
#include <vector>

#include "spindown/effects.hpp"
#include "spindown/fitter_core.hpp"
#include "spindown/lab_settings.hpp"
#include "spindown/lcm_loop.hpp"
#include "spindown/message_queue.hpp"
#include "spindown/message_stamp.hpp"
#include "spindown/publish_health.hpp"
#include "spindown/service_instances.hpp"
#include "spindown/service_notifier.hpp"
#include "spindown/stop_signal.hpp"

namespace spindown {

struct FitterServiceOptions {
  FitterOptions core;
  std::string lcm_url;                  // "" = LCM_DEFAULT_URL or LCM's default
  std::string instance = "fitter";      // status on SPINDOWN.<instance>.STATUS
  double status_period_s = 1.0;
  std::size_t max_queue_messages = 200000;  // received but not yet processed
  std::size_t max_queue_bytes = 64u << 20;
  bool verbose = false;                 // one line per run event and fit on stderr
  LabSettings lab{"lab", std::nullopt, {}, ""};  // the lab's name and key (also in core.gate)
};

class FitterService final : public FitterSink {
 public:
  explicit FitterService(FitterServiceOptions options);
  ~FitterService() override;

  bool good() const { return loop_.good(); }
  std::uint64_t session() const { return stamp_.identity().session; }
  // Runs until a stop signal (or LCM keeps failing) and returns the exit code. Under systemd
  // (Type=notify): READY=1 once subscribed, WATCHDOG=1 from the LCM loop while the worker
  // thread shows signs of life, STOPPING=1 at the end.
  int run(const StopSignals& stop);

  // FitterSink (worker thread).
  void run_changed(const run_t& run) override;
  void fit_ready(const FitResult& result) override;
  void explain_ready(const FitResult& result) override;
  void diagnostic(const std::string& bench, const Diagnostic& d) override;
  void notice(std::string_view kind, std::string_view channel, const std::string& text) override;

 private:
  void worker();
  // Nothing received still waits: the service's queue, LCM's and the socket's are empty.
  bool nothing_waiting() const;
  void publish_status(std::int64_t now_us, const char* state);
  // A STATUS on this instance's own channel: another fitter with the same name is named.
  void own_channel_status(const QueuedMessage& m);
  // SPINDOWN.<bench>.EXPLAIN, after the FIT (the workflow takes tens of ms; FIT goes first).

  FitterServiceOptions opt_;
  MessageStamp stamp_;  // this fitter's lab, host, session and key on everything it publishes
  LcmLoop loop_;
  FitterCore core_;
  std::string status_channel_;
  ServiceInstances instances_;      // fitters heard on status_channel_ (worker thread)
  std::string collision_;           // the latest collision named ("" none)
  // notice(): when each (kind, channel) was last said on stderr, and how many were not said since.
  struct Said {
    std::int64_t at_us = 0;
    std::int64_t quiet = 0;
  };
  std::map<std::string, Said, std::less<>> said_;
  std::string host_;
  std::int64_t start_us_ = 0;
  // A message larger than the whole queue may hold is no sign of a full queue: it is oversize
  // (LCM 1.3.1 assembles a fragmented message of whatever size its first fragment claims).
  MessageQueue queue_;

  // Worker-side measurements for the heartbeat.
  double last_latency_s_ = 0, max_latency_s_ = 0, last_fit_s_ = 0;
  PublishHealth publish_{{.program = "spindown-fitter"}};  // send errors, unheard heartbeats
  std::int64_t stalls_ = 0;
  bool draining_ = false;    // after a stall, until nothing received waits any more  // rounds that started long after the one before (a freeze)
  std::int64_t explains_ = 0, explain_failures_ = 0;
  std::int64_t last_samples_ = 0, last_rate_us_ = 0;
  double rate_hz_ = 0;
  std::atomic<std::int64_t> worker_alive_ns_{0};  // monotonic time of the worker's latest round
  ServiceNotifier notify_;
  std::thread worker_;
};

}  // namespace spindown
