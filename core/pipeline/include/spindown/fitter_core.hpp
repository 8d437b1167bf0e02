#pragma once
// The live fitter's logic without any I/O: raw LCM messages (channel, bytes, receive time) go
// in, run events, fits, diagnostics and a heartbeat come out through a sink. spindown-fitter
// wraps it with LCM; `spindown refit` feeds it the events of a log in log order; tests drive
// it directly. The same input gives the same runs and the same numbers everywhere.
//
// Every raw message first passes a MessageGate (message_gate.hpp): another lab's message, and
// with the lab key an unsigned, wrongly signed or replayed one, is counted and named, never used.
// Per bench: samples are checked like the log reader checks them (decode, quantity, sequence
// gaps, repeated messages, clock epochs, NaN values, device time that does not advance, the
// stream's source: a new source is a new stream, two at once are named; sample_stream.hpp), fed
// one by one to a RunDetector, and each completed run is fitted with fit_run() using J and K_b
// of the bench's latest CONFIG (or the configured default, said so in bench_source).
//
// Bounded: at most max_benches benches (the least recently active is evicted), per bench the
// detector's buffer and a mirror of it (≤ RunOptions::max_buffer samples each), a sample-rate
// cap per bench (flooding messages dropped and counted). Nothing in the input throws out of it.
#include <cstddef>
#include <cstdint>
#include <exception>
#include <map>
#include <memory>
#include <optional>
#include <regex>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <spindown/config_t.hpp>
#include <spindown/run_t.hpp>
#include <spindown/samples_t.hpp>
#include <spindown/status_t.hpp>

#include "spindown/bench.hpp"
#include "spindown/bench_file.hpp"
#include "spindown/explain.hpp"
#include "spindown/fit.hpp"
#include "spindown/message_decode.hpp"
#include "spindown/message_gate.hpp"
#include "spindown/sample_stream.hpp"
#include "spindown/motor_health.hpp"
#include "spindown/recording.hpp"
#include "spindown/run_detector.hpp"
#include "spindown/runs.hpp"
#include "spindown/short_name_cache.hpp"

namespace spindown {

struct FitterOptions {
  // `spindown fit`'s defaults, but for a cap on a coast that never stops: live, a bound on memory.
  RunOptions runs{.max_coast_s = 600.0};
  std::vector<ModelKind> models{all_models[0], all_models[1], all_models[2]};
  BenchParams default_bench;             // J, K_b for a bench without (usable) CONFIG
  bool ignore_config = false;            // always use default_bench (like `spindown fit --inertia`)
  // J and K_b named for a refit (spindown refit and export of a log: --inertia/--kb/… and a
  // --bench-config file's [bench], by bench id): what they name wins over the CONFIG, each
  // parameter on its own, by the offline rule (choose_bench_params: command line, else the bench's
  // file, else the CONFIG, else default_bench), and bench_source says where each came from. The
  // live fitter names none: CONFIG, else default_bench.
  BenchChoice named{default_bench};      // its given: default_bench with the command line's values
  std::map<std::string, BenchFile, std::less<>> bench_files;
  std::string bench_regex = ".*";        // benches handled (full match on the id)
  // Benches held at once. A new bench takes a free place, or the place of the least recently
  // active bench with no run in progress; new benches are admitted at most admit_rate_hz per
  // second (bucket of max_benches). A new bench that finds neither is refused and counted: a
  // flood of bench ids never evicts a run in progress.
  std::size_t max_benches = 256;
  double admit_rate_hz = 20;
  // A bench that sends no samples for this long (host time) mid-coast has its run closed and
  // fitted to its last sample (Run::End::silent); see poll().
  double silent_s = 10;
  double max_rate_hz = 5000;             // samples per second per bench (host time); 0 = no cap
  double burst_s = 2.0;                  // the cap's bucket holds this many seconds of samples
  // Motor health references per bench id (the benches' TOML files): each fit of such a bench
  // carries a verdict (FitResult::health); other benches' fits carry none.
  std::map<std::string, MotorHealthConfig, std::less<>> health;
  // The lab this fitter serves, and with a key the signatures and replay window (message_gate.hpp).
  MessageGateOptions gate;
  // A bench stream's sources and far jumps (sample_stream.hpp).
  SampleStreamOptions stream;
  // The discrepancy workflow (explain_run) on every fitted run's own window, starting from this
  // base (FitResult::explain; published live on SPINDOWN.<bench>.EXPLAIN, reproduced by refit).
  // Empty: off.
  std::vector<const Effect*> explain_base;
  bool is_valid(std::string* why) const;
};

struct FitterCounters {
  std::int64_t messages = 0;           // messages given to the core
  std::int64_t sample_messages = 0;    // decoded samples_t
  std::int64_t config_messages = 0;    // decoded config_t
  std::int64_t samples = 0;            // samples given to a run detector
  std::int64_t runs_started = 0;       // cut events
  std::int64_t runs = 0;               // runs completed (fitted)
  std::int64_t runs_ignored = 0;       // coasts too short / abandoned by the detector
  std::int64_t fits = 0;               // fits published
  std::int64_t fit_failures = 0;       // runs where no model converged (still published)
  std::int64_t decode_errors = 0;      // wrong fingerprint, truncated, damaged
  std::int64_t invalid_bench = 0;      // channel's bench id not [A-Za-z0-9_-]{1,32}
  std::int64_t bench_mismatch = 0;     // message's bench field differs from the channel's
  std::int64_t filtered = 0;           // bench not matching bench_regex
  std::int64_t other_channels = 0;     // not SPINDOWN.<bench>.SAMPLE|CONFIG
  std::int64_t seq_gaps = 0;           // gaps in samples_t.seq
  std::int64_t samples_lost = 0;       // samples missing in those gaps
  std::int64_t duplicates = 0;         // samples of repeated messages (sequence numbers seen), skipped
  std::int64_t late_samples = 0;       // samples that came after their gap was counted lost (skipped)
  std::int64_t seq_restarts = 0;       // sequence number went back (bridge restarted)
  std::int64_t clock_restarts = 0;     // device clock epochs
  std::int64_t nan_values = 0;         // non-finite values skipped
  std::int64_t time_backwards = 0;     // samples whose device time does not advance, skipped
  std::int64_t quantity_errors = 0;    // unknown or changing quantity: message skipped
  std::int64_t bad_configs = 0;        // CONFIG with unusable J/K_b
  std::int64_t dropped_benches = 0;    // benches evicted (max_benches), never one with a run in progress
  std::int64_t benches_refused = 0;    // messages of new benches refused (table full or admission rate)
  std::int64_t partial_runs = 0;       // runs completed whose cut was not seen (joined mid-coast)
  std::int64_t runs_abandoned = 0;     // runs still open when the fitter stopped (RUN abandoned)
  std::int64_t silent_benches = 0;     // runs closed because their bench went silent (silent_s)
  std::int64_t flood_drops = 0;        // samples dropped by the rate cap
  std::int64_t flood_messages = 0;     // messages dropped by the rate cap
  std::int64_t internal_errors = 0;    // exceptions caught from the fit or detector
  // The gate (issue 31): messages not used for who sent them.
  std::int64_t other_lab = 0;          // messages of another lab
  std::int64_t unsigned_messages = 0;  // not signed, with signatures required
  std::int64_t bad_signatures = 0;     // signed with another key, or a signature that does not match
  std::int64_t replays = 0;            // signed messages seen before, or sent outside the replay window
  // A bench stream's sources (sample_stream.hpp).
  std::int64_t new_sources = 0;        // another source took over a bench's stream (bridge restarted, replugged)
  std::int64_t two_sources = 0;        // a second source sending at the same time on a bench's channel (named)
  std::int64_t other_source_samples = 0;  // samples of a source that is not its bench's stream's, refused
  std::int64_t seq_jumps = 0;          // messages far from their stream that did not continue it (forged/damaged)
  std::int64_t seq_jump_samples = 0;   // their samples, dropped
};

// One completed run's fit, as published.
struct FitResult {
  std::string bench;
  RunFit fit;                      // indices as in the bench's sample stream
  std::string bench_source;        // "config" or why the default J/K_b was used
  std::int64_t first_seq = 0, last_seq = 0;
  std::int64_t detected_utime = 0; // receive time of the message that completed the run
  double fit_seconds = 0;          // CPU-clock time the fit took
  std::optional<HealthVerdict> health;  // when FitterOptions::health has the bench
  std::span<const double> t_s;     // the run's samples [cut, end), valid during the call only
  std::span<const double> value;
  std::string bridge_host;         // the source whose samples these are (samples_t.source_*)
  std::uint64_t bridge_session = 0;
  // The run rebased onto t_s/value (cut 0; its stop, end and outliers moved with it): the one
  // window the FIT was fitted to, and the EXPLAIN too.
  Run window;
  // When FitterOptions::explain_base is set: filled after fit_ready (the FIT goes out first, its
  // latency never waits for the workflow), then given to explain_ready.
  std::optional<ExplainResult> explain;
};

class FitterSink {
 public:
  virtual ~FitterSink() = default;
  virtual void run_changed(const run_t& run) = 0;         // SPINDOWN.<bench>.RUN
  virtual void fit_ready(const FitResult& result) = 0;    // SPINDOWN.<bench>.FIT
  // SPINDOWN.<bench>.EXPLAIN: the same result, its explain filled (empty if the workflow failed),
  // right after fit_ready, only when FitterOptions::explain_base is set. Default: ignored.
  virtual void explain_ready(const FitResult& result) { (void)result; }
  // A message or sample that could not be used, in words naming the channel (also kept as
  // last_error for the heartbeat). Default: ignored.
  virtual void problem(const std::string& text) { (void)text; }
  // What a technician must see at once, not only in the heartbeat (issue 31): a new source on a
  // bench's channel, two sources at once, a far jump dropped as forged or damaged, and a message
  // the gate refused (another lab's, unsigned, wrongly signed, replayed). kind names it
  // ("new source", "two sources", "jump", or the gate's verdict), channel where. Also given to
  // problem(). Default: ignored.
  virtual void notice(std::string_view kind, std::string_view channel, const std::string& text) {
    (void)kind;
    (void)channel;
    (void)text;
  }
  // Detector notes (runs ignored, clock restarts, …) with the bench channel as source. Default: ignored.
  virtual void diagnostic(const std::string& bench, const Diagnostic& d) {
    (void)bench;
    (void)d;
  }
};

class FitterCore {
 public:
  // options must be valid (is_valid); sink must outlive the core.
  FitterCore(FitterOptions options, FitterSink& sink);
  ~FitterCore();
  FitterCore(const FitterCore&) = delete;
  FitterCore& operator=(const FitterCore&) = delete;

  // A raw LCM message: SPINDOWN.<bench>.SAMPLE and .CONFIG pass the gate (admit()) and are
  // decoded and used, other channels counted. recv_utime is the host receive time (µs since the
  // epoch; from the log when refitting) used by the rate cap, the replay window and for latency.
  void on_message(std::string_view channel, const void* data, std::int64_t size, std::int64_t recv_utime);
  // Live, two clocks: wall_utime is the wall time LCM read the message (a signed source first
  // heard must agree with it: the replay window), recv_utime the host time that never steps
  // (clock.hpp steady_wall_us) for everything else (silence, rate cap, reorder window).
  void on_message(std::string_view channel, const void* data, std::int64_t size, std::int64_t wall_utime,
                  std::int64_t recv_utime);
  // The gate alone, for a reader that decodes itself (refit): false when the message must not be
  // used (counted and named). A message that does not decode passes (its decoder names it).
  bool admit(std::string_view channel, const void* data, std::int64_t size, std::int64_t recv_utime) {
    return admit(channel, data, size, recv_utime, recv_utime);
  }
  bool admit(std::string_view channel, const void* data, std::int64_t size, std::int64_t wall_utime,
             std::int64_t recv_utime);
  // admit() for a SAMPLE already viewed (its lab read): nearly always one comparison.
  bool admit_samples(std::string_view channel, const SamplesView& view, const void* data, std::int64_t size,
                     std::int64_t wall_utime, std::int64_t recv_utime) {
    return gate_.accepts_at_once(view.lab, view.sent_to) || admit(channel, data, size, wall_utime, recv_utime);
  }
  bool admit_samples(std::string_view channel, const SamplesView& view, const void* data, std::int64_t size,
                     std::int64_t recv_utime) {
    return admit_samples(channel, view, data, size, recv_utime, recv_utime);
  }
  // Already decoded messages (tests, tools; a log reader's view); bench is the channel's bench id.
  void on_samples(std::string_view bench, const samples_t& msg, std::int64_t recv_utime);
  void on_samples(std::string_view bench, const SamplesView& msg, std::int64_t recv_utime);
  // The same from a reader that numbers its channels (LcmLogEvent::channel_id; one numbering per
  // core): after a channel's first message its bench is found by that number instead of by
  // hashing and comparing the name again. A negative id (or one past max_channel_ids) goes by name.
  void on_samples(std::int32_t channel_id, std::string_view bench, const SamplesView& msg, std::int64_t recv_utime);
  static constexpr std::int32_t max_channel_ids = 1024;
  void on_config(std::string_view bench, const config_t& msg, std::int64_t recv_utime);
  // End of the stream (refit, shutdown): open coasts are closed and fitted as `spindown fit`
  // does at the end of a file.
  void finish(std::int64_t now_utime);
  // The service stops: every run still open is published abandoned with the note why (not
  // fitted: a fitter started again takes the rest of its coast as partial), counted in
  // runs_abandoned. The core takes no samples after it.
  void abandon_open_runs(std::int64_t now_utime, const std::string& why);
  // The passing of host time (the service calls it a few times a second, refit at the log's
  // event times): a bench with a run in progress and no samples for silent_s has it closed.
  void poll(std::int64_t now_utime);
  static constexpr std::int64_t poll_period_us = 500'000;  // how often poll() is worth calling
  // Whether poll(now_utime) would close a run: a bench with a run in progress and no samples
  // for silent_s. The service then first makes sure nothing it received still waits.
  bool silence_due(std::int64_t now_utime) const;

  const FitterCounters& counters() const { return counters_; }
  std::size_t bench_count() const { return benches_.size(); }
  std::size_t buffered_samples() const;  // over all benches (detector + mirror)
  const std::string& last_error() const { return last_error_; }
  std::int64_t last_error_utime() const { return last_error_utime_; }
  // Benches in order of first appearance (still held).
  std::vector<std::string> benches() const;

  // Heartbeat: every counter, gauges (benches, buffered samples, sample rate), last error.
  status_t make_status(std::int64_t now_utime, std::string_view instance, std::string_view host, std::int32_t pid,
                       std::string_view state, double uptime_s) const;

 private:
  struct Bench;
  struct StreamSink;  // SampleStream's problems and samples -> counters, errors, the detector
  void flush_stream(Bench& b, std::int64_t utime);
  void expire_stream(Bench& b, std::int64_t utime);  // gaps waited out (sample_stream.hpp expire)
  inline Bench* bench_for(std::string_view id, std::int64_t recv_utime, std::string_view kind);
  Bench* find_bench(std::string_view id, std::int64_t recv_utime, std::string_view kind);  // past the cache
  bool admit(std::string_view id, std::int64_t recv_utime, std::string_view kind);  // room for a new bench?
  // bench_for() for a SAMPLE channel whose id is not yet in bench_by_channel_; remembers the answer.
  Bench* bench_for_channel(std::int32_t channel_id, std::string_view bench, std::int64_t recv_utime);
  void error(std::string text, std::int64_t utime);
  // The per-bench checks and the detector, for n samples of either form of message. Always
  // inlined: at one sample per message the calls' register saves cost as much as the checks.
  template <class Message>
  [[gnu::always_inline]] inline void take_samples(Bench& b, const Message& m, std::size_t n, std::int64_t recv_utime);
  [[gnu::always_inline]] inline void push_sample(Bench& b, std::int64_t seq, double t_s, double value,
                                                 std::int64_t recv_utime);
  void internal_error(const Bench& b, std::int64_t seq, const std::exception& e, std::int64_t recv_utime);
  void retract_stop(Bench& b, std::int64_t recv_utime);
  void handle_events(Bench& b, std::int64_t recv_utime);
  void restart_clock(Bench& b, std::int64_t recv_utime);
  void fit_and_publish(Bench& b, const Run& run, const std::string& why_unstopped, std::int64_t recv_utime);
  void publish_run(Bench& b, const Run& run, std::int8_t state, std::string note, std::int64_t utime);
  inline void trim_mirror(Bench& b);

  FitterOptions opt_;
  FitterSink& sink_;
  MessageGate gate_;
  std::regex bench_filter_;
  std::map<std::string, std::unique_ptr<Bench>, std::less<>> benches_;
  ShortNameCache<Bench> bench_cache_;  // bench id -> bench, before the map
  std::vector<Bench*> bench_by_channel_;  // by a reader's channel id; nullptr: not known (or evicted)
  std::uint64_t activity_ = 0;   // increases per message: least recently active = smallest
  std::uint64_t arrivals_ = 0;   // order of first appearance
  double admit_tokens_ = -1;     // admission bucket (< 0: not started)
  std::int64_t admit_utime_ = 0;
  FitterCounters counters_;
  std::string last_error_;
  std::int64_t last_error_utime_ = 0;
  std::vector<double> scratch_t_, scratch_v_;
};

}  // namespace spindown
