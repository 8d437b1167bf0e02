#pragma once
// A numbered stream put back in order (issue 42): a datagram network reorders (Wi-Fi retries, a
// power-saving access point that delivers a second of datagrams behind newer ones, jitter between
// two PCs), so a message past a gap in the sequence numbers is not yet a loss. It waits here until
// the gap fills, and the gap is called lost only when a message past it has waited `window_us` of
// receive time (or more than `max_samples` wait). A message that arrives after its gap was called
// lost is *late*, never "repeated": the last `remembered_losses` lost ranges are kept to tell.
//
// A stream first heard past sequence number 0 waits the same way for what it overtook (start()).
//
// Used by everyone who follows samples_t.seq: the fitter, refit, watch and the web page through
// SampleStream (which waits with the samples), the logger's loss counters (which wait with none).
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <limits>
#include <optional>
#include <utility>

namespace spindown {

struct ReorderOptions {
  std::int64_t window_us = 2'000'000;  // a gap is lost once a message past it waited this long
  std::int64_t max_samples = 8192;     // or once this many samples wait past it
};

template <class Item>
class ReorderWindow {
 public:
  struct Entry {
    std::int64_t seq = 0, n = 0, recv_us = 0;
    Item item{};
  };

  bool empty() const { return waiting_.empty(); }
  std::int64_t samples() const { return samples_; }
  // One past the last sequence number waiting (the stream's frontier while something waits).
  std::int64_t end_seq() const { return waiting_.empty() ? 0 : waiting_.back().seq + waiting_.back().n; }
  const Entry& front() const { return waiting_.front(); }
  const Entry& back() const { return waiting_.back(); }

  // Whether [seq, seq + n) overlaps a message already waiting (a copy of it).
  bool holds(std::int64_t seq, std::int64_t n) const {
    auto it = std::lower_bound(waiting_.begin(), waiting_.end(), seq,
                               [](const Entry& e, std::int64_t s) { return e.seq + std::max<std::int64_t>(e.n, 1) <= s; });
    return it != waiting_.end() && it->seq < seq + std::max<std::int64_t>(n, 1);
  }

  void insert(std::int64_t seq, std::int64_t n, std::int64_t recv_us, Item item) {
    auto it = std::upper_bound(waiting_.begin(), waiting_.end(), seq,
                               [](std::int64_t s, const Entry& e) { return s < e.seq; });
    if (waiting_.empty()) {
      oldest_ = recv_us;
      oldest_known_ = true;
    } else {
      oldest_ = std::min(oldest_, recv_us);  // (when not known, looked for again anyway)
    }
    waiting_.insert(it, Entry{seq, n, recv_us, std::move(item)});
    samples_ += n;
  }

  // Whether the first message waiting goes now, with the stream at next_seq at time now_us: it
  // continues the stream, or the gap before it has waited long enough to be called lost.
  bool ready(std::int64_t next_seq, std::int64_t now_us, const ReorderOptions& o) const {
    if (waiting_.empty()) return false;
    if (waiting_.front().seq <= next_seq || samples_ > o.max_samples) return true;
    return now_us - oldest() >= o.window_us;
  }

  // Each message that goes now, in order (ready() with the stream at next_seq, which take moves
  // on): a gap before it is remembered as lost (at now_us; at the end, now_us = max, when the
  // message came), then take(entry) takes it. One loop for every follower of a stream: the sample
  // stream accepts the message, the logger only counts.
  template <class Take>
  void release(const std::int64_t& next_seq, std::int64_t now_us, const ReorderOptions& o, Take&& take) {
    while (ready(next_seq, now_us, o)) {
      Entry e = pop();
      if (e.seq > next_seq)
        lost(next_seq, e.seq, now_us == std::numeric_limits<std::int64_t>::max() ? e.recv_us : now_us);
      take(e);
    }
  }

  // A stream first heard past its start (a bridge numbers from 0): what came first may have
  // overtaken what was sent before it, so it waits like a message past a gap. The stream starts
  // (true, next_seq set to the first waiting) once 0 has come, or once that wait is over (a
  // follower that joined a running stream), with nothing before it called lost.
  bool start(std::int64_t& next_seq, std::int64_t now_us, const ReorderOptions& o) const {
    if (!ready(0, now_us, o)) return false;
    next_seq = waiting_.front().seq;
    return true;
  }

  Entry pop() {
    Entry e = std::move(waiting_.front());
    waiting_.pop_front();
    samples_ -= e.n;
    if (e.recv_us == oldest_) oldest_known_ = false;  // found again when next asked
    return e;
  }

  void clear() {  // what waits and the losses remembered
    waiting_.clear();
    samples_ = 0;
    losses_.clear();
  }

  // Lost ranges, so that what comes after its gap was called lost is named late.
  void lost(std::int64_t from, std::int64_t to, std::int64_t recv_us) {
    if (to <= from) return;
    if (losses_.size() >= remembered_losses) losses_.pop_front();
    losses_.push_back({from, to, recv_us});
  }
  // When [seq, seq + n) lies in a range called lost: when it was called; those samples leave the
  // range (each is late once; a copy of a late message is a repeat).
  std::optional<std::int64_t> take_lost(std::int64_t seq, std::int64_t n) {
    for (auto it = losses_.begin(); it != losses_.end(); ++it) {
      if (seq < it->from || seq + n > it->to) continue;
      const Loss l = *it;
      losses_.erase(it);
      if (seq > l.from) losses_.push_back({l.from, seq, l.called_us});
      if (seq + n < l.to) losses_.push_back({seq + n, l.to, l.called_us});
      return l.called_us;
    }
    return std::nullopt;
  }

 private:
  // The earliest receive time of what waits: how long the oldest gap has been open. Kept on
  // insert, looked for again only after the oldest message left (a gap's wait is checked on every
  // message while one is open).
  std::int64_t oldest() const {
    if (!oldest_known_) {
      oldest_ = waiting_.front().recv_us;
      for (const Entry& e : waiting_) oldest_ = std::min(oldest_, e.recv_us);
      oldest_known_ = true;
    }
    return oldest_;
  }

  static constexpr std::size_t remembered_losses = 64;
  struct Loss {
    std::int64_t from, to, called_us;
  };
  std::deque<Entry> waiting_;
  std::int64_t samples_ = 0;
  mutable std::int64_t oldest_ = 0;
  mutable bool oldest_known_ = true;  // (nothing waits: insert sets it)
  std::deque<Loss> losses_;
};

}  // namespace spindown
