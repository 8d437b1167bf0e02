#pragma once
// The LCM loop of every spindown program, as lcm's listener example reads (make LCM, check
// good(), subscribe, handle until a signal), with what each program used to write for itself:
//
// - typed subscriptions, decoded with decode_message (message_decode.hpp: a hostile message
//   cannot make it allocate gigabytes or throw); a message that does not decode is counted and
//   named (decode_errors(), last_decode_error(), on_decode_error) and its handler not called;
// - raw subscriptions, for programs that keep the bytes (the logger records them, the fitter
//   queues them for its worker);
// - a handler's exception never crosses LCM's C callback: it is caught there, the rest of that
//   message's dispatch is skipped, and run() (or drain()) rethrows it once LCM has returned —
//   or on_handler_error reports it and the loop goes on;
// - run() waits on LCM's socket and on the stop signal's pipe at once, so SIGINT/SIGTERM end
//   the wait at once whichever thread took it; it ends on a stop, stop(), a deadline or
//   repeated receive failures, and calls the timers (every()) between messages.
//
// Subscriptions go through LCM's C API: LCM 1.3.1's C++ API cannot subscribe a lambda, and its
// member-function subscription trips UBSan's vptr check inside its own header.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <exception>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "spindown/message_decode.hpp"
#include "spindown/message_stamp.hpp"

namespace spindown {

class StopSignals;

// One received message; valid while its handler runs.
struct LcmMessage {
  std::string_view channel;
  const void* data = nullptr;
  std::int64_t size = 0;
  std::int64_t recv_utime = 0;  // when LCM received it (µs since the epoch)
};

// A message that did not decode as its subscription's type.
struct LcmDecodeError {
  std::string channel;
  std::string type;  // "samples_t", …
  std::int64_t size = 0;
  std::string why;   // decode_message's words
  std::int64_t recv_utime = 0;
  // "<channel>: <size> bytes that do not decode as <type>: <why>"
  std::string text() const;
};

struct LcmSubscribeOptions {
  // Messages LCM queues for the subscription before it drops (silently: LCM 1.3.1's default is
  // 30, which a burst passes); 0 = no limit.
  int queue_capacity = 10000;
  // When set, a message whose channel it refuses is ignored before decoding (neither handled
  // nor counted).
  std::function<bool(std::string_view channel)> accept{};
};

enum class LcmLoopEnd {
  stopped,   // a stop signal, or stop()
  deadline,  // timeout_s passed
  failed,    // LCM failed to receive more than max_failures times in a row
};

struct LcmRunOptions {
  const StopSignals* stop = nullptr;  // ends the run once SIGINT/SIGTERM came
  double timeout_s = 0;               // > 0: ends the run after this long
  int max_wait_ms = 100;              // the longest single wait (the timers are kept on time)
  int max_failures = 50;              // consecutive failed receives tolerated (one more ends the run); < 0: any
};

class LcmLoop {
 public:
  // url "": LCM_DEFAULT_URL, else LCM's default.
  explicit LcmLoop(const std::string& url = {});
  ~LcmLoop();
  LcmLoop(const LcmLoop&) = delete;
  LcmLoop& operator=(const LcmLoop&) = delete;

  bool good() const { return lcm_.good(); }
  lcm::LCM& lcm() { return lcm_; }
  // Every message published from now on carries the stamp's source fields, signed when it has
  // the lab key (message_stamp.hpp). The stamp must outlive the loop's publishing.
  void set_stamp(MessageStamp* stamp) { stamp_ = stamp; }
  // 0 when sent (LCM's result); -1 when the message could not be encoded.
  template <class Msg>
  int publish(const std::string& channel, const Msg& msg) {
    if (!stamp_) return lcm_.publish(channel, &msg);
    const std::vector<unsigned char> bytes = stamp_->encode(channel, msg);
    if (bytes.empty()) return -1;
    return lcm_.publish(channel, bytes.data(), static_cast<unsigned>(bytes.size()));
  }

  // handler(const Msg&, const LcmMessage&) or handler(const Msg&), for each message on a
  // channel matching channel_regex (anchored at both ends, GLib syntax) that decodes as Msg.
  // False when LCM refuses the subscription (a bad regex).
  template <class Msg, class Handler>
  bool subscribe(const std::string& channel_regex, Handler handler, LcmSubscribeOptions options = {});
  // handler(const LcmMessage&) with the bytes as received.
  bool subscribe_raw(const std::string& channel_regex, std::function<void(const LcmMessage&)> handler,
                     LcmSubscribeOptions options = {});
  // No more messages are received or queued for this loop's subscriptions.
  void unsubscribe_all();

  // Called for each message that does not decode (after it is counted).
  void on_decode_error(std::function<void(const LcmDecodeError&)> report) { decode_report_ = std::move(report); }
  // When set, a handler's exception is reported here (still inside LCM's callback, which then
  // returns normally) and the loop goes on; unset, run() rethrows it once LCM has returned.
  void on_handler_error(std::function<void(const LcmMessage&, const std::exception&)> report) {
    handler_error_ = std::move(report);
  }

  // fn(wall µs) every period_s (a steady cadence), first first_after_s from now (< 0: one
  // period); the waits are shortened to keep it on time. period_s 0: after every wait, message
  // or not. Timers run in the order they were added, on run()'s thread.
  void every(double period_s, std::function<void(std::int64_t now_us)> fn, double first_after_s = -1);

  // LCM set up reception (LCM 1.3.1's udpm does that on the first subscription, and when its
  // own loopback self-test fails it has no socket to wait on).
  bool can_receive();

  // Whether LCM holds received messages not yet dispatched (its receive thread's queue): its
  // notify pipe is readable. Safe from any thread (a poll with no wait on LCM's descriptor).
  bool messages_waiting() const;

  // Dispatches messages until a stop, a deadline or too many failed receives (see LcmRunOptions).
  // Rethrows a handler's exception (unless on_handler_error is set).
  LcmLoopEnd run(const LcmRunOptions& options = {});
  // From a handler, a timer or another thread: run() returns once the current message is
  // handled (from another thread: within max_wait_ms).
  void stop() { stop_.store(true); }
  // Dispatches what has arrived until quiet_ms pass with nothing new, for at most at_most_s
  // (what LCM's receive thread still holds after a stop). No timers.
  void drain(int quiet_ms = 50, double at_most_s = 2.0);

  std::int64_t decode_errors() const { return decode_errors_; }
  const LcmDecodeError& last_decode_error() const { return last_decode_error_; }

 private:
  struct Subscription;
  struct Timer {
    std::chrono::steady_clock::duration period;
    std::chrono::steady_clock::time_point next;
    std::function<void(std::int64_t)> fn;
  };
  static void dispatch(const lcm_recv_buf_t* rbuf, const char* channel, void* user) noexcept;
  int handle_one();  // lcm_handle, then a handler's exception rethrown
  void run_timers();
  void decode_failed(const LcmMessage& m, const char* type, std::string why);

  lcm::LCM lcm_;
  MessageStamp* stamp_ = nullptr;
  std::atomic<int> receive_fd_{-1};  // LCM's descriptor, once it has one (for messages_waiting())
  std::vector<std::unique_ptr<Subscription>> subscriptions_;
  std::vector<Timer> timers_;
  std::function<void(const LcmDecodeError&)> decode_report_;
  std::function<void(const LcmMessage&, const std::exception&)> handler_error_;
  std::exception_ptr pending_;
  std::atomic<bool> stop_{false};
  std::int64_t decode_errors_ = 0;
  LcmDecodeError last_decode_error_;
};

template <class Msg, class Handler>
bool LcmLoop::subscribe(const std::string& channel_regex, Handler handler, LcmSubscribeOptions options) {
  static_assert(std::is_invocable_v<Handler&, const Msg&, const LcmMessage&> || std::is_invocable_v<Handler&, const Msg&>,
                "handler(const Msg&, const LcmMessage&) or handler(const Msg&)");
  // One message object per subscription: decoding reuses its vectors' capacity.
  auto msg = std::make_shared<Msg>();
  return subscribe_raw(
      channel_regex,
      [this, msg, handler = std::move(handler)](const LcmMessage& m) mutable {
        std::string why;
        if (!decode_message(*msg, m.data, m.size, &why)) {
          decode_failed(m, Msg::getTypeName(), std::move(why));
          return;
        }
        if constexpr (std::is_invocable_v<Handler&, const Msg&, const LcmMessage&>)
          handler(std::as_const(*msg), m);
        else
          handler(std::as_const(*msg));
      },
      std::move(options));
}

}  // namespace spindown
