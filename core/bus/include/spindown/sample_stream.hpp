#pragma once
// A bench's SAMPLE stream, checked once for everyone who reads it: the live fitter
// (FitterCore), the LCM log reader (read_lcm_log) and `spindown watch` take every message through
// SampleStream::take, so a refit of a log sees exactly the samples the fitter saw live, with the
// same words for what was wrong.
//
// A stream has one source: the bridge process (its host and session, samples_t.source_*) whose
// samples it takes (issue 31). Per message of that source: the quantity code must be known and
// must not change; the sequence number orders the stream: a message past a gap waits in a
// reorder window (reorder_window.hpp) until the gap fills (a late datagram, taken in its place)
// or has waited reorder.window_us (then the gap's samples are lost); a message with samples
// already taken is a repeat (skipped), one whose gap was already called lost is late (skipped,
// named as late). A new clock epoch, or times that start again below the last, is a restarted
// device clock (a new timeline). Per sample: a value must be finite and a device time must
// advance.
//
// What a forged or damaged message cannot do any more:
// - A message far from where the stream is (more than max_gap_samples ahead, device time more
//   than max_gap_us ahead, another clock epoch, or back with new times) is held, not taken: it
//   becomes the stream's position only when messages that continue it keep coming for confirm_s
//   while none continues the old position (a real gap, a real reset). When the old position goes
//   on, the held samples are dropped and named (SampleProblem::jump): one datagram with sequence
//   number 2^40 never makes every later real sample "repeated".
// - Another source on the channel (a restarted bridge, a replugged board: a new session) is a new
//   stream, like a reset (SampleProblem::new_source), once the stream's source has been quiet for
//   takeover_s: its first messages are held until then and taken in order, so a restart loses
//   nothing and is never "repeated". When the stream's source still sends, both are alive at once:
//   SampleProblem::two_sources is named (once per source) and the other's samples are refused
//   (other_source) — never fitted as this stream's. The first source is kept; a second takes over
//   only when the first goes quiet.
// Messages from before sources were named (session 0, no host) are one source, as before.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <fmt/format.h>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <spindown/samples_t.hpp>

#include "spindown/message_decode.hpp"
#include "spindown/recording.hpp"
#include "spindown/reorder_window.hpp"
#include "spindown/session_id.hpp"

namespace spindown {

std::optional<Quantity> quantity_from_samples_code(std::int8_t code);  // samples_t::QUANTITY_*
std::int8_t samples_code_of(Quantity quantity);

enum class SampleProblem {
  unknown_quantity,  // message skipped
  quantity_change,   // message skipped
  samples_lost,      // count: samples missing before this message
  repeated,          // message skipped
  sequence_restart,  // the bridge restarted its sequence numbers (an unnamed source: a new one is new_source)
  clock_restart,     // the device clock restarted: a new timeline starts with this message
  bad_value,         // a NaN or infinite value: that sample skipped
  time_backwards,    // a device time that does not advance: that sample skipped
  new_source,        // another source replaced the stream's: a new stream (like clock_restart) starts here
  two_sources,       // a second source sends at the same time as the stream's (named once per source)
  other_source,      // count: samples of a source that is not the stream's, refused
  jump,              // count: held samples that did not continue the stream, dropped (forged or damaged)
  late,              // count: samples that arrived after their gap was called lost (counted there); skipped
};

struct SampleStreamOptions {
  double takeover_s = 1.0;               // a new source takes over once the stream's is quiet this long
  double confirm_s = 0.5;                // a far jump is taken once continued this long (old position silent)
  std::int64_t max_gap_samples = 256;    // a forward sequence gap up to this is ordinary loss
  std::int64_t max_gap_us = 10'000'000;  // and a forward device-time step up to this
  std::size_t max_held_samples = 8192;   // held per stream at most (more are refused and counted)
  std::size_t max_sources = 4;           // other sources remembered per channel
  ReorderOptions reorder;                // how long a message past a gap waits for the gap to fill
};

// A sample's device time and value from either form of samples_t, and the message's source.
inline std::int64_t sample_time_us(const samples_t& m, std::size_t i) { return m.device_time_us[i]; }
inline double sample_value(const samples_t& m, std::size_t i) { return m.value[i]; }
inline std::int64_t sample_time_us(const SamplesView& m, std::size_t i) {
  return m.device_time_us(static_cast<std::int32_t>(i));
}
inline double sample_value(const SamplesView& m, std::size_t i) { return m.value(static_cast<std::int32_t>(i)); }
inline std::uint64_t sample_session(const samples_t& m) { return static_cast<std::uint64_t>(m.source_session); }
inline std::uint64_t sample_session(const SamplesView& m) { return m.source_session; }

// A message held back (a far jump, a new source waiting for the old one to go quiet).
struct HeldSamples {
  std::int64_t seq = 0;
  std::int32_t clock_epoch = 0;
  std::int8_t quantity = 0;
  std::uint64_t source_session = 0;
  std::string source_host;
  std::vector<std::int64_t> t_us;
  std::vector<double> v;
  std::int64_t origin = 0;  // the caller's name for the message (a log's event number), see take()
};
inline std::int64_t sample_time_us(const HeldSamples& m, std::size_t i) { return m.t_us[i]; }
inline double sample_value(const HeldSamples& m, std::size_t i) { return m.v[i]; }
inline std::uint64_t sample_session(const HeldSamples& m) { return m.source_session; }

struct SampleStream {
  SampleStreamOptions options;

  bool quantity_known = false;
  Quantity quantity = Quantity::back_emf_volts;
  std::int8_t quantity_code = 0;  // the samples_t code that gave quantity
  // Where the stream is.
  bool have_seq = false, have_epoch = false;
  std::int64_t next_seq = 0;
  std::int32_t epoch = 0;
  std::int64_t last_t_us = std::numeric_limits<std::int64_t>::min();
  // Its source, and when that was last heard (receive time, µs).
  bool have_source = false;
  std::uint64_t session = 0;
  std::string host;
  std::int64_t last_recv_us = 0;

  // Takes a message of n samples (n already checked against its arrays), received at recv_us.
  // For each thing wrong, sink.problem(SampleProblem, count, text) with the words to report; for
  // each sample kept, sink.sample(seq, device_time_us, value). Returns true when the message is
  // the stream's: taken now, or waiting past a gap to be taken in order; false when it is skipped,
  // refused or held (a far jump, another source). origin names the message for the caller (a log's
  // event number): when a message that waited is taken later, sink.origin(its origin) is called
  // first, if the sink has it, so what is said of it names the right message. Inlined: at one
  // sample per message a call costs as much as the checks; everything rare is a call.
  template <class Message, class Sink>
  [[gnu::always_inline]] inline bool take(const Message& m, std::size_t n, std::int64_t recv_us, Sink&& sink,
                                          std::int64_t origin = 0) {
    origin_ = origin;
    if (!have_source) [[unlikely]] {
      adopt_source(sample_session(m), m.source_host, recv_us);
    } else if (sample_session(m) != session || m.source_host != host) [[unlikely]] {
      return take_other(m, n, recv_us, sink);
    }
    last_recv_us = recv_us;
    if (!others_.empty()) [[unlikely]]
      source_heard(sink);
    return take_own(m, n, recv_us, sink);
  }

  // End of the stream (a refit's end, a fitter stopping): a held jump nothing contradicted is
  // taken; a new source's held messages that never took over are counted as refused.
  template <class Sink>
  void flush(Sink&& sink) {
    if (starting_) begin_stream(std::numeric_limits<std::int64_t>::max(), sink);
    release_waiting(std::numeric_limits<std::int64_t>::max(), sink);
    if (jump_.active) adopt_jump(jump_.first_recv_us, sink);
    for (Other& o : others_) {
      if (o.held_samples > 0)
        sink.problem(SampleProblem::other_source, o.held_samples,
                     fmt::format("{} sample(s) of {} held back at the end: {} never went quiet", o.held_samples,
                                 source_words(o.session, o.host), source_words(session, host)));
      o.held.clear();
      o.held_samples = 0;
    }
  }

  // Time passes with no message (the fitter's poll): gaps waited for long enough are lost, and
  // what waited behind them is taken.
  template <class Sink>
  void expire(std::int64_t now_us, Sink&& sink) {
    if (starting_) [[unlikely]]
      begin_stream(now_us, sink);
    else if (!waiting_.empty())
      release_waiting(now_us, sink);
  }
  bool waiting() const { return !waiting_.empty(); }

  // "host bench-pc (session 3f9a0c1d5e7b2a48)" of the stream's source.
  std::string source_text() const { return source_words(session, host); }

 private:
  enum class Role { candidate, second, retired };
  struct Other {
    std::uint64_t session = 0;
    std::string host;
    Role role = Role::candidate;
    std::int64_t first_recv_us = 0, last_recv_us = 0;
    std::int64_t high_seq = 0;  // retired: where its stream was
    bool named = false;         // "two sources" said
    std::vector<HeldSamples> held;
    std::int64_t held_samples = 0;
  };
  struct Jump {
    bool active = false;
    std::int64_t first_recv_us = 0;
    std::int64_t next_seq = 0;
    std::int32_t epoch = 0;
    std::int64_t last_t_us = 0;
    std::vector<HeldSamples> held;
    std::int64_t held_samples = 0;
  };
  enum class Relation { continues, repeated, jump };
  bool starting_ = false;  // first heard past sequence number 0: waiting for what it overtook

  static std::string source_words(std::uint64_t s, std::string_view h) { return spindown::source_text(h, s); }

  void adopt_source(std::uint64_t s, std::string_view h, std::int64_t recv_us) {
    have_source = true;
    session = s;
    host.assign(h);
    last_recv_us = recv_us;
  }

  template <class Message>
  HeldSamples hold(const Message& m, std::size_t n) {
    HeldSamples h;
    h.seq = m.seq;
    h.origin = origin_;
    h.clock_epoch = m.clock_epoch;
    h.quantity = m.quantity;
    h.source_session = sample_session(m);
    h.source_host.assign(m.source_host);
    h.t_us.resize(n);
    h.v.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      h.t_us[i] = sample_time_us(m, i);
      h.v[i] = sample_value(m, i);
    }
    return h;
  }

  // Where m stands against a position (its next sequence number, clock epoch and last time).
  template <class Message>
  Relation relation(const Message& m, std::size_t n, std::int64_t pos_next, std::int32_t pos_epoch,
                    std::int64_t pos_last_t) const {
    const bool same_epoch = !have_epoch || m.clock_epoch == pos_epoch;
    if (same_epoch && m.seq < pos_next && (n == 0 || sample_time_us(m, n - 1) <= pos_last_t)) return Relation::repeated;
    if (same_epoch && m.seq >= pos_next && m.seq - pos_next <= options.max_gap_samples &&
        (n == 0 || pos_last_t == std::numeric_limits<std::int64_t>::min() ||
         sample_time_us(m, 0) <= pos_last_t || sample_time_us(m, 0) - pos_last_t <= options.max_gap_us))
      return Relation::continues;
    return Relation::jump;
  }

  template <class Message, class Sink>
  [[gnu::always_inline]] inline bool take_own(const Message& m, std::size_t n, std::int64_t recv_us, Sink& sink) {
    // The stream's own quantity code again (nearly always): nothing to check.
    if (!quantity_known || m.quantity != quantity_code) [[unlikely]] {
      if (!check_quantity(m, n, sink)) return false;
    }
    if (n == 0) [[unlikely]]
      return true;  // nothing to take, and an empty message does not move the stream
    if (have_seq) [[likely]] {
      const Relation r = relation(m, n, next_seq, epoch, last_t_us);
      if (r != Relation::continues || m.seq != next_seq || !waiting_.empty() || jump_.active) [[unlikely]]
        return take_out_of_order(m, n, recv_us, r, sink);
    } else if (m.seq > 0 || starting_) [[unlikely]] {
      return take_before_start(m, n, recv_us, sink);
    }
    accept(m, n, sink, false);
    return true;
  }

  // The stream first heard past its sequence number 0: what comes waits, in order, for what the
  // network delayed behind it (ReorderWindow::start), then the stream begins at the first waiting.
  template <class Message, class Sink>
  bool take_before_start(const Message& m, std::size_t n, std::int64_t recv_us, Sink& sink) {
    const auto count = static_cast<std::int64_t>(n);
    if (waiting_.holds(m.seq, count)) {
      say_repeated(m.seq, count, sink);
      return false;
    }
    starting_ = true;
    waiting_.insert(m.seq, count, recv_us, hold(m, n));
    begin_stream(recv_us, sink);
    return true;
  }
  template <class Sink>
  void begin_stream(std::int64_t now_us, Sink& sink) {
    if (!waiting_.start(next_seq, now_us, options.reorder)) return;
    starting_ = false;
    have_seq = true;
    release_waiting(now_us, sink);
  }

  // Anything but the next message in order: a repeat, a late one, one past a gap, a far jump.
  template <class Message, class Sink>
  bool take_out_of_order(const Message& m, std::size_t n, std::int64_t recv_us, Relation r, Sink& sink) {
    const auto count = static_cast<std::int64_t>(n);
    if (r == Relation::repeated) {
      if (const auto called = waiting_.take_lost(m.seq, count)) {
        sink.problem(SampleProblem::late, count,
                     fmt::format("samples {} to {} arrived {:.1f} s after they were counted lost (a gap waits {:g} s "
                                 "for late messages); not used",
                                 m.seq, m.seq + count - 1, 1e-6 * double(recv_us - *called),
                                 1e-6 * double(options.reorder.window_us)));
        return false;
      }
      say_repeated(m.seq, count, sink);
      return false;
    }
    if (r == Relation::jump && !waiting_.empty() &&
        relation(m, n, waiting_.end_seq(), epoch, waiting_.back().item.t_us.back()) == Relation::continues)
      r = Relation::continues;  // it continues what waits past a gap
    if (r == Relation::jump) return take_far(m, n, recv_us, sink);
    if (jump_.active) drop_jump(m, sink);  // the old position went on: what was held was not the stream
    if (waiting_.holds(m.seq, count)) {
      say_repeated(m.seq, count, sink);
      return false;
    }
    if (m.seq == next_seq)  // the gap's first message: taken, then what waited behind it
      accept(m, n, sink, false);
    else
      waiting_.insert(m.seq, count, recv_us, hold(m, n));
    release_waiting(recv_us, sink);
    return true;
  }

  template <class Sink>
  void say_repeated(std::int64_t seq, std::int64_t count, Sink& sink) {
    sink.problem(SampleProblem::repeated, count,
                 fmt::format("samples {} to {} were already received (repeated message); skipped", seq,
                             seq + count - 1));
  }

  // What waits past a gap, in order, while it continues the stream or its gap has waited long
  // enough (now_us = max: everything, at the end or when the stream moves elsewhere).
  template <class Sink>
  void release_waiting(std::int64_t now_us, Sink& sink) {
    waiting_.release(next_seq, now_us, options.reorder, [&](const auto& e) {
      if constexpr (requires { sink.origin(std::int64_t{}); }) sink.origin(e.item.origin);
      accept(e.item, e.item.t_us.size(), sink, false);  // says the samples lost before it, moves next_seq
    });
  }

  template <class Message, class Sink>
  bool check_quantity(const Message& m, std::size_t n, Sink& sink) {
    const auto q = quantity_from_samples_code(m.quantity);
    if (!q) {
      sink.problem(SampleProblem::unknown_quantity, static_cast<std::int64_t>(n),
                   fmt::format("unknown quantity code {} at seq {}; message of {} samples skipped", int(m.quantity),
                               m.seq, n));
      return false;
    }
    if (!quantity_known) {
      quantity = *q;
      quantity_code = m.quantity;
      quantity_known = true;
    } else if (*q != quantity) {
      sink.problem(SampleProblem::quantity_change, static_cast<std::int64_t>(n),
                   fmt::format("quantity changes from {} to {} at seq {}; message of {} samples skipped",
                               quantity_unit(quantity), quantity_unit(*q), m.seq, n));
      return false;
    }
    return true;
  }

  // The message moves the stream. forced: a jump that was confirmed (or an unnamed source's
  // restart) — the sequence and the clock may start again here.
  template <class Message, class Sink>
  [[gnu::always_inline]] inline void accept(const Message& m, std::size_t n, Sink& sink, bool forced) {
    const auto count = static_cast<std::int64_t>(n);
    bool restart = have_epoch && m.clock_epoch != epoch;
    if (have_seq && m.seq != next_seq) [[unlikely]] {
      if (m.seq > next_seq) {
        sink.problem(SampleProblem::samples_lost, m.seq - next_seq,
                     fmt::format("{} samples lost: sequence number jumps from {} to {}", m.seq - next_seq,
                                 next_seq - 1, m.seq));
      } else {
        sink.problem(SampleProblem::sequence_restart, 0,
                     fmt::format("sequence number restarts from {} at {} (bridge restarted?)", next_seq, m.seq));
        if (n > 0 && sample_time_us(m, 0) <= last_t_us) restart = true;
      }
    }
    if (forced && !restart && n > 0 && last_t_us != std::numeric_limits<std::int64_t>::min() &&
        sample_time_us(m, 0) <= last_t_us)
      restart = true;  // times that start again, confirmed by what followed
    have_seq = true;
    next_seq = m.seq + count;
    if (restart) [[unlikely]] {
      sink.problem(SampleProblem::clock_restart, 0,
                   have_epoch && m.clock_epoch != epoch
                       ? fmt::format("device clock restarted (clock epoch {} -> {}); a new timeline starts here and "
                                     "no run spans it",
                                     epoch, m.clock_epoch)
                       : std::string("device clock restarted (times start again); a new timeline starts here and "
                                     "no run spans it"));
      last_t_us = std::numeric_limits<std::int64_t>::min();
    }
    have_epoch = true;
    epoch = m.clock_epoch;

    for (std::size_t i = 0; i < n; ++i) {
      const std::int64_t t = sample_time_us(m, i);
      const double v = sample_value(m, i);
      const std::int64_t seq = m.seq + static_cast<std::int64_t>(i);
      if (!std::isfinite(v)) [[unlikely]] {
        sink.problem(SampleProblem::bad_value, 1, fmt::format("sample {}: value is NaN or infinite; skipped", seq));
        continue;
      }
      if (t <= last_t_us) [[unlikely]] {
        sink.problem(SampleProblem::time_backwards, 1,
                     fmt::format("sample {}: device time {} µs does not advance (previous {} µs); skipped", seq, t,
                                 last_t_us));
        continue;
      }
      last_t_us = t;
      sink.sample(seq, t, v);
    }
  }

  // A message far from the stream.
  template <class Message, class Sink>
  bool take_far(const Message& m, std::size_t n, std::int64_t recv_us, Sink& sink) {
    const Relation to_held = jump_.active ? relation(m, n, jump_.next_seq, jump_.epoch, jump_.last_t_us) : Relation::jump;
    if (to_held == Relation::repeated) {  // a copy of a held message
      sink.problem(SampleProblem::repeated, static_cast<std::int64_t>(n),
                   fmt::format("samples {} to {} were already received (repeated message); skipped", m.seq,
                               m.seq + static_cast<std::int64_t>(n) - 1));
      return false;
    }
    if (to_held == Relation::continues) {
      keep_held(jump_.held, jump_.held_samples, m, n, sink);
      jump_.next_seq = m.seq + static_cast<std::int64_t>(n);
      if (n > 0) jump_.last_t_us = std::max(jump_.last_t_us, sample_time_us(m, n - 1));
      if (recv_us - jump_.first_recv_us >= static_cast<std::int64_t>(options.confirm_s * 1e6))
        adopt_jump(recv_us, sink);
      return false;
    }
    if (jump_.active) drop_jump(m, sink);
    jump_.active = true;
    jump_.first_recv_us = recv_us;
    jump_.next_seq = m.seq + static_cast<std::int64_t>(n);
    jump_.epoch = m.clock_epoch;
    jump_.last_t_us = n > 0 ? sample_time_us(m, n - 1) : std::numeric_limits<std::int64_t>::min();
    keep_held(jump_.held, jump_.held_samples, m, n, sink);
    return false;
  }

  template <class Message, class Sink>
  void keep_held(std::vector<HeldSamples>& held, std::int64_t& held_samples, const Message& m, std::size_t n,
                 Sink& sink) {
    if (static_cast<std::size_t>(held_samples) + n > options.max_held_samples) {
      sink.problem(SampleProblem::other_source, static_cast<std::int64_t>(n),
                   fmt::format("samples {} to {} not held: more than {} samples are waiting; refused", m.seq,
                               m.seq + static_cast<std::int64_t>(n) - 1, options.max_held_samples));
      return;
    }
    held.push_back(hold(m, n));
    held_samples += static_cast<std::int64_t>(n);
  }

  // What was held did not continue the stream: dropped, and said.
  template <class Message, class Sink>
  void drop_jump(const Message& m, Sink& sink) {
    if (!jump_.active) return;
    const HeldSamples& first = jump_.held.empty() ? HeldSamples{} : jump_.held.front();
    sink.problem(SampleProblem::jump, jump_.held_samples,
                 fmt::format("{} sample(s) from seq {} (clock epoch {}{}) did not continue the stream (at seq {}, "
                             "epoch {}{}), which went on where it was (seq {}): forged or damaged; not used",
                             jump_.held_samples, first.seq, first.clock_epoch,
                             first.t_us.empty() ? std::string() : fmt::format(", device time {:.3f} s", 1e-6 * double(first.t_us[0])),
                             next_seq, epoch,
                             last_t_us == std::numeric_limits<std::int64_t>::min()
                                 ? std::string()
                                 : fmt::format(", device time {:.3f} s", 1e-6 * double(last_t_us)),
                             m.seq));
    jump_ = Jump{};
  }

  // The held position is the stream's from now: its messages are taken in order.
  template <class Sink>
  void adopt_jump(std::int64_t, Sink& sink) {
    release_waiting(std::numeric_limits<std::int64_t>::max(), sink);  // the old position's, first
    std::vector<HeldSamples> held = std::move(jump_.held);
    jump_ = Jump{};
    bool first = true;
    for (const HeldSamples& h : held) {
      if (!quantity_known || h.quantity != quantity_code)
        if (!check_quantity(h, h.t_us.size(), sink)) continue;
      accept(h, h.t_us.size(), sink, first);
      first = false;
    }
  }

  // The stream's source sent again: a source waiting to take over is a second one alive.
  template <class Sink>
  void source_heard(Sink& sink) {
    for (Other& o : others_) {
      if (o.role != Role::candidate) continue;
      o.role = Role::second;
      name_two_sources(o, sink);
      if (o.held_samples > 0)
        sink.problem(SampleProblem::other_source, o.held_samples,
                     fmt::format("{} held sample(s) of {} refused: {} still sends", o.held_samples,
                                 source_words(o.session, o.host), source_words(session, host)));
      o.held.clear();
      o.held_samples = 0;
    }
  }

  template <class Sink>
  void name_two_sources(Other& o, Sink& sink) {
    if (o.named) return;
    o.named = true;
    sink.problem(SampleProblem::two_sources, 0,
                 fmt::format("has two sources: {} and {}, sending at the same time (two bridges with one bench id: two "
                             "labs on one group and port? give each lab its own --lab, group and port, "
                             "docs/lab-setup.md; or a forger); the samples of {} are not used",
                             source_words(session, host), source_words(o.session, o.host),
                             source_words(o.session, o.host)));
  }

  template <class Message, class Sink>
  bool take_other(const Message& m, std::size_t n, std::int64_t recv_us, Sink& sink) {
    const std::uint64_t s = sample_session(m);
    Other* o = nullptr;
    for (Other& x : others_)
      if (x.session == s && x.host == m.source_host) o = &x;
    if (!o) {
      if (others_.size() >= options.max_sources) {  // forget the least recently heard
        auto oldest = std::min_element(others_.begin(), others_.end(),
                                       [](const Other& a, const Other& b) { return a.last_recv_us < b.last_recv_us; });
        others_.erase(oldest);
      }
      others_.push_back(Other{s, std::string(m.source_host), Role::candidate, recv_us, recv_us, 0, false, {}, 0});
      o = &others_.back();
    }
    o->last_recv_us = recv_us;
    const auto count = static_cast<std::int64_t>(n);
    if (o->role == Role::retired) {
      if (m.seq < o->high_seq) {
        sink.problem(SampleProblem::repeated, count,
                     fmt::format("samples {} to {} of the earlier source {} were already received (repeated "
                                 "message); skipped",
                                 m.seq, m.seq + count - 1, source_words(o->session, o->host)));
        return false;
      }
      o->role = Role::second;  // it went on: alive at the same time as the stream's source
      name_two_sources(*o, sink);
    }
    const bool quiet = recv_us - last_recv_us >= static_cast<std::int64_t>(options.takeover_s * 1e6);
    if (quiet) return take_over(*o, m, n, recv_us, sink);
    if (o->role == Role::second) {
      name_two_sources(*o, sink);
      sink.problem(SampleProblem::other_source, count,
                   fmt::format("samples {} to {} of {} refused: {} is the stream's source", m.seq, m.seq + count - 1,
                               source_words(o->session, o->host), source_words(session, host)));
      return false;
    }
    keep_held(o->held, o->held_samples, m, n, sink);
    return false;
  }

  // The stream's source went quiet and o sends: a new stream, with o's held messages first.
  template <class Message, class Sink>
  bool take_over(Other& o, const Message& m, std::size_t n, std::int64_t recv_us, Sink& sink) {
    if (jump_.active) adopt_jump(recv_us, sink);
    if (starting_) begin_stream(std::numeric_limits<std::int64_t>::max(), sink);  // the old one's start
    release_waiting(std::numeric_limits<std::int64_t>::max(), sink);  // the old stream's, to its end
    waiting_.clear();  // and its losses: the new source numbers its own
    starting_ = false;
    sink.problem(SampleProblem::new_source, 0,
                 fmt::format("a new source: {} after {} went quiet {:.1f} s ago (the bridge restarted or the board was "
                             "replugged); a new stream starts here and no run spans it",
                             source_words(o.session, o.host), source_words(session, host),
                             1e-6 * double(recv_us - last_recv_us)));
    Other old{session, host, Role::retired, last_recv_us, last_recv_us, have_seq ? next_seq : 0, o.named, {}, 0};
    std::vector<HeldSamples> held = std::move(o.held);
    const std::uint64_t new_session = o.session;
    const std::string new_host = o.host;
    others_.erase(others_.begin() + (&o - others_.data()));
    others_.push_back(std::move(old));
    // A new stream: nothing of the old one's position or quantity carries over.
    quantity_known = false;
    have_seq = have_epoch = false;
    next_seq = 0;
    epoch = 0;
    last_t_us = std::numeric_limits<std::int64_t>::min();
    adopt_source(new_session, new_host, recv_us);
    for (const HeldSamples& h : held) take_own(h, h.t_us.size(), recv_us, sink);
    take_own(m, n, recv_us, sink);
    return true;
  }

  std::vector<Other> others_;
  Jump jump_;
  ReorderWindow<HeldSamples> waiting_;  // the stream's messages past a gap
  std::int64_t origin_ = 0;             // of the message being taken
};

}  // namespace spindown
