#pragma once
// spindown-fitter's LCM shell around FitterCore. The LCM thread only copies each message into
// a bounded queue (so a fit never stalls reception and LCM's own queue never overflows); one
// worker thread feeds the core in arrival order, publishes RUN and FIT, and the heartbeat on
// SPINDOWN.<instance>.STATUS.
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "spindown/effects.hpp"
#include "spindown/fitter_core.hpp"

namespace spindown {

struct FitterServiceOptions {
  FitterOptions core;
  std::string lcm_url;                  // "" = LCM_DEFAULT_URL or LCM's default
  std::string instance = "fitter";      // status on SPINDOWN.<instance>.STATUS
  double status_period_s = 1.0;
  std::size_t max_queue_messages = 200000;  // received but not yet processed
  std::size_t max_queue_bytes = 64u << 20;
  bool verbose = false;                 // one line per run event and fit on stderr
  // The discrepancy workflow on every fitted run, published on SPINDOWN.<bench>.EXPLAIN,
  // starting from this base (the lab's belief: viscous). Empty = off.
  std::vector<const Effect*> explain_base{find_effect("viscous")};
};

class FitterService final : public FitterSink {
 public:
  explicit FitterService(FitterServiceOptions options);
  ~FitterService() override;

  bool good() const { return lcm_.good(); }
  // Runs until stop() (from a signal handler: only sets a flag) and returns the exit code.
  int run(const std::atomic<bool>& stop_flag);

  // FitterSink (worker thread).
  void run_changed(const run_t& run) override;
  void fit_ready(const FitResult& result) override;
  void diagnostic(const std::string& bench, const Diagnostic& d) override;

 private:
  struct Message {
    std::string channel;
    std::vector<unsigned char> data;
    std::int64_t recv_utime = 0;
  };
  // LCM's C callback (the C++ wrapper's member-function subscription trips UBSan's vptr check
  // in LCM 1.3.1's own header).
  static void on_lcm(const lcm_recv_buf_t* rbuf, const char* channel, void* self);
  void enqueue(const lcm_recv_buf_t* rbuf, const char* channel);
  void worker();
  void publish_status(std::int64_t now_us, const char* state);
  // SPINDOWN.<bench>.EXPLAIN, after the FIT (the workflow takes tens of ms; FIT goes first).
  void publish_explain(const FitResult& result);

  FitterServiceOptions opt_;
  lcm::LCM lcm_;
  FitterCore core_;
  std::string host_;
  std::int64_t start_us_ = 0;

  std::mutex mu_;
  std::condition_variable cv_;
  std::deque<Message> queue_;
  std::size_t queue_bytes_ = 0;
  std::int64_t queue_drops_ = 0;       // messages dropped because the queue was full
  std::int64_t oversize_drops_ = 0;    // messages larger than the queue's byte limit
  std::string oversize_last_;          // the last of them: "<size> bytes on <channel>"
  std::size_t queue_high_water_ = 0;
  bool stopping_ = false;

  // Worker-side measurements for the heartbeat.
  double last_latency_s_ = 0, max_latency_s_ = 0, last_fit_s_ = 0;
  std::int64_t publish_failures_ = 0;
  std::int64_t explains_ = 0, explain_failures_ = 0;
  std::int64_t last_samples_ = 0, last_rate_us_ = 0;
  double rate_hz_ = 0;
  std::thread worker_;
};

}  // namespace spindown
