#include "spindown/run_detector.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#include <fmt/format.h>
#include <utility>

namespace spindown {

namespace {

// Seconds of lead-in searched for the cut before the window that confirmed the coast.
constexpr double back_search_s = 2.0;
// Seconds of lead-in kept while idle.
constexpr double idle_keep_s = 40.0;
// Samples searched at least, for slow loops.
constexpr std::size_t back_search_min_samples = 16;
// A coast is confirmed by a decline this many standard errors strong …
constexpr double confirm_t_stat = 6.0;
// … whose residual roughness is at most this fraction of its level (rejects a floating pin).
constexpr double confirm_max_roughness = 0.05;
// Standstill: slope within this many standard errors of zero.
constexpr double flat_t_stat = 3.0;
// Standstill must be below this fraction of the reading at the cut.
constexpr double standstill_max_fraction = 0.3;
// A real stop arrives with a finite slope: the last quarter of the amplitude is crossed at
// least this fast relative to the coast's mean rate (Coulomb ≈ 1, lab's combined ≈ 0.8,
// pure viscous ≈ 0.3–0.45, depending on the noise that decides "flat").
constexpr double stop_min_end_rate = 0.5;
// … or the last stop_hold_s before the stop still falls with this t-statistic (an exponential
// that has become "flat" shows ~3–6 there, a Coulomb stop tens).
constexpr double stop_min_approach_t = 10.0;
// A 1 s hold window decides alone when its slope error is this fraction of the mean rate.
constexpr double slope_resolution = 0.05;
// In the tail, a hold-window mean this fraction of the amplitude below the zero level retracts
// the stop.
constexpr double retract_fraction = 0.01;
// The spread of a reading rounded to steps of 1, as uniform rounding error: 1/sqrt(12).
constexpr double step_sd = 0.2886751345948129;
// The long hold window spans at least this fraction of the coast before it.
constexpr double long_hold_fraction = 0.03;
// Recompute sliding sums from scratch this often (rounding drift).
constexpr unsigned refresh_every = 4096;

std::string fmt_s(double t) { return fmt::format("{:.3f} s", t); }

}  // namespace

// A silence inside a coast (from the sample at prev to the one at t, the coast cut at t_cut) that
// ends it: longer than half a minute and than the coast seen before it, so the samples after it
// would be a coast the fit barely knew the way to. A shorter one is samples lost (or a clock
// that jumped), said by warn_of_gap_in_coast, and the coast goes on.
[[gnu::always_inline]] inline bool long_silence(double prev, double t, double t_cut) {
  return t - prev > 30.0 && t - prev > prev - t_cut;
}

// ---- sliding least-squares line ----------------------------------------------------------

void RunDetector::WindowFit::clear(std::size_t at, double t_origin) {
  first = end = at;
  t0 = t_origin;
  n = stv = 0;
  s1 = s2 = WindowFit::Pair{};
  updates = 0;
}

double RunDetector::duration(const WindowFit& w) const {
  return w.end > w.first ? t(w.end - 1) - t(w.first) : 0.0;
}

RunDetector::WindowFit RunDetector::window_over(const Sample* ring, std::size_t mask, double span, std::size_t from,
                                                std::size_t to) {
  WindowFit w;
  w.span_s = span;
  w.clear(from, from < to ? ring[from & mask].t : 0.0);
  for (std::size_t k = from; k < to; ++k) w.add(ring[k & mask].t, ring[k & mask].v);
  w.end = to;
  w.updates = 0;
  return w;
}

void RunDetector::rebuild(WindowFit& w, std::size_t from, std::size_t to) {
  w = window_over(ring_.get(), mask_, w.span_s, from, to);
}

void RunDetector::reset_window(WindowFit& w, std::size_t lo, std::size_t end) {
  lo = std::max(lo, base_);
  if (lo >= end) {
    w.clear(end, 0.0);
    return;
  }
  std::size_t from = lo;
  while (from + 1 < end && t(end - 1) - t(from) > w.span_s) ++from;
  rebuild(w, from, end);
}

// Per sample for every live window, so inlined into its callers; the usual step (sample i
// follows the window's last, exactly one old sample expires) is one slide(). s is sample i,
// passed in so that it is not reloaded from the ring after the stores to the sums.
[[gnu::always_inline]] inline void RunDetector::advance(WindowFit& w, const Sample* ring, const std::size_t mask,
                                                       std::size_t i, Sample s) {
  // w.n always equals w.end - w.first: an empty window contiguous with i has first == i.
  if (w.end != i || w.first == i) [[unlikely]] {
    if (w.end != i) w.clear(i, s.t);  // not contiguous (after a reset): start again from i
    w.t0 = s.t;
  }
  // Add sample i, then drop the oldest while the window is longer than its span (keeping at
  // least 3). At a steady rate exactly one drops: that add and remove are one slide().
  std::size_t first = w.first;
  const double span = w.span_s;
  const auto expired = [&](std::size_t k) { return i + 1 - k > 2 && s.t - ring[k & mask].t > span; };
  if (expired(first)) [[likely]] {
    const Sample old = ring[first & mask];
    w.slide(s.t, s.v, old.t, old.v);
    ++first;
    while (expired(first)) [[unlikely]] {
      const Sample o = ring[first & mask];
      w.remove(o.t, o.v);
      ++first;
    }
  } else {
    w.add(s.t, s.v);
  }
  w.first = first;
  w.end = i + 1;
  if (w.updates > refresh_every) [[unlikely]] w = window_over(ring, mask, span, w.first, w.end);
}

[[gnu::always_inline]] inline void RunDetector::advance(WindowFit& w, std::size_t i, Sample s) {
  advance(w, ring_.get(), mask_, i, s);
}

[[gnu::always_inline]] inline void RunDetector::coast_step(std::size_t i, Sample s, double prev_t) {
  advance(hold_, i, s);
  if (hold_long_live_) [[unlikely]] advance(hold_long_, i, s);
  if (long_silence(prev_t, s.t, run_.t_cut_s)) [[unlikely]] {
    coast_too_long(i);
    return;
  }
  coast_checks(i, s);
}

// Per coasting sample; kept small (the rare outcomes are the caller's calls) since it runs for
// every sample. s is sample i, and h (hold_, or push_many's copy of it) ends at i; level_min and
// rising are the coast's lowest level and rise count, updated here.
[[gnu::always_inline]] inline RunDetector::CoastVerdict RunDetector::coast_verdict(std::size_t i, Sample s,
                                                                                 const WindowFit& h,
                                                                                 double& level_min,
                                                                                 int& rising, const CoastLimits& c) {
  const double t_i = s.t;
  // i + 1 - base is buffered() after sample i.
  if (i + 1 - c.base > c.max_buffer || t_i - c.t_cut_s > c.max_coast_s) [[unlikely]] return {CoastVerdict::too_long};
  if (h.n < 3 || h.first < c.cut_index) return {};
  const double dur = t_i - c.ring[h.first & c.mask].t;  // duration(h), its last sample being i
  const double mu = h.sv() / h.n;                        // h.mean(), n being at least 3

  // Power back before standstill: the reading climbs well above the coast's lowest level.
  if (dur >= c.hold_half_s) level_min = std::min(level_min, mu);
  if (s.v > level_min + c.rise_jump) [[unlikely]] {
    if (rising++ == 0) rise_start_ = i;
    if (rising >= 3) return {CoastVerdict::power_back};
  } else {
    rising = 0;
  }

  // Standstill: the hold window is flat and low.
  if (dur < c.hold_full_s) return {};
  if (mu > c.standstill_ceiling) return {};  // still high: the usual case, cheap
  // Low: while the coast still falls the hold window is not level, and nothing else is to do.
  if (clearly_sloped(h, c.v0, mu)) return {};  // most low samples: no division, no square root
  CoastVerdict v{CoastVerdict::level, mu};
  if (!level(h, dur, mu, c.v0, v.sxx, v.e)) return {};
  return v;
}

// What a verdict asks for; the state it read must be the detector's own again.
void RunDetector::act_on(const CoastVerdict& v, std::size_t i, bool at_end) {
  switch (v.what) {
    case CoastVerdict::go_on: break;
    case CoastVerdict::too_long: coast_too_long(i); break;
    case CoastVerdict::power_back: power_back(); break;
    case CoastVerdict::level: standstill_checks(i, at_end, v.mu, v.sxx, v.e); break;
  }
}

[[gnu::always_inline]] inline void RunDetector::coast_checks(std::size_t i, Sample s, bool at_end) {
  const CoastVerdict v = coast_verdict(i, s, hold_, level_min_, rising_, coast_limits());
  if (v.what != CoastVerdict::go_on) [[unlikely]] act_on(v, i, at_end);
}

// ---- detector ----------------------------------------------------------------------------

RunDetector::RunDetector(RunOptions opt, std::string source) : opt_(std::move(opt)), source_(std::move(source)) {
  hold_.span_s = opt_.stop_hold_s;
  hold_long_.span_s = 3.0 * opt_.stop_hold_s;
  hold_half_s_ = 0.5 * hold_.span_s;
  hold_full_s_ = 0.9 * hold_.span_s;
  ring_ = std::make_unique_for_overwrite<Sample[]>(initial_ring_size);
  mask_ = initial_ring_size - 1;
}

void RunDetector::grow_ring() {
  // Keep [base_, next_index_) at the same positions modulo the new, doubled size.
  const std::size_t size = 2 * ring_size();
  auto bigger = std::make_unique_for_overwrite<Sample[]>(size);
  const std::size_t mask = size - 1;
  for (std::size_t k = base_; k + 1 < next_index_; ++k) bigger[k & mask] = ring_[k & mask_];
  ring_ = std::move(bigger);
  mask_ = mask;
}

std::vector<RunEvent> RunDetector::take_events() {
  std::vector<RunEvent> out;
  out.swap(events_);
  return out;
}

void RunDetector::emit_diag(Diagnostic::Severity sev, std::string msg) {
  RunEvent e;
  e.kind = RunEvent::Kind::diagnostic;
  e.diagnostic = {sev, source_, 0, std::move(msg)};
  e.has_diagnostic = true;
  events_.push_back(std::move(e));
}

double* RunDetector::scratch(std::size_t size) {
  if (size > scratch_size_) {
    scratch_size_ = std::max(size, 2 * scratch_size_);
    scratch_ = std::make_unique_for_overwrite<double[]>(scratch_size_);
  }
  return scratch_.get();
}

double RunDetector::median_of(std::size_t from, std::size_t to) {
  if (to <= from) return 0.0;
  const std::size_t n = to - from;
  double* x = scratch(n);
  for (std::size_t k = from; k < to; ++k) x[k - from] = v(k);
  double* mid = x + n / 2;
  std::nth_element(x, mid, x + n);
  double m = *mid;
  if (n % 2 == 0) m = 0.5 * (m + *std::max_element(x, mid));
  return m;
}

double RunDetector::median_period(std::size_t from, std::size_t to) {
  const std::size_t n = to - from - 1, h = n / 2;
  // A steady clock gives few distinct periods (timestamps on a grid, rounded), one of them most
  // of the time, so the median of a few periods spread over the coast usually is the median of
  // all. It is exactly when fewer than h + 1 periods are below it and more than h at or below it:
  // one counting pass, instead of copying and partially sorting them all.
  constexpr std::size_t probes = 9;
  if (n >= probes) {
    double probe[probes];
    for (std::size_t j = 0; j < probes; ++j) {
      const std::size_t k = from + (n - 1) * j / (probes - 1);
      probe[j] = t(k + 1) - t(k);
    }
    std::nth_element(probe, probe + probes / 2, probe + probes);
    const double guess = probe[probes / 2];
    std::size_t below = 0, at_or_below = 0;
    double prev = t(from);
    // Over the ring in stretches that do not wrap, so the loop needs no index masking, and of at
    // most `chunk` periods: the counts only grow, so the answer is often known before the end -
    // guess is the median once h + 1 periods are at or below it and n - h at or above it, and is
    // not once h + 1 are below it.
    constexpr std::size_t chunk = 256;
    for (std::size_t k = from + 1; k < to;) {
      const std::size_t stretch_end = std::min({to, (k | mask_) + 1, k + chunk});
      count_periods(ring_.get() + (k & mask_), stretch_end - k, guess, prev, below, at_or_below);
      k = stretch_end;
      const std::size_t counted = k - from - 1, at_or_above = counted - below;
      if (h < below) break;
      if (h < at_or_below && at_or_above >= n - h) return guess;
    }
    if (below <= h && h < at_or_below) return guess;
  }
  double* dt = scratch(n);
  for (std::size_t k = 0; k < n; ++k) dt[k] = t(from + 1 + k) - t(from + k);
  std::nth_element(dt, dt + h, dt + n);
  return dt[h];
}

void RunDetector::count_periods(const Sample* p, std::size_t m, double guess, double& prev, std::size_t& below,
                                std::size_t& at_or_below) {
  std::size_t j = 0;
#if defined(__SSE2__)  // elsewhere (arm64 benches) the plain loop below counts them all
  // Two periods per step in SSE2 lanes (t(j) - t(j-1) and t(j+1) - t(j), the same subtractions
  // and comparisons as one at a time); a true comparison is an all-ones lane, -1 when counted.
  const __m128d g = _mm_set1_pd(guess);
  __m128d last = _mm_set1_pd(prev);  // high lane: the time before p[j]
  __m128i n_below = _mm_setzero_si128(), n_at_or_below = _mm_setzero_si128();
  const auto count = [&](__m128d now) {  // now: t(j), t(j+1)
    const __m128d d = _mm_sub_pd(now, _mm_shuffle_pd(last, now, 1));  // minus t(j-1), t(j)
    n_below = _mm_sub_epi64(n_below, _mm_castpd_si128(_mm_cmplt_pd(d, g)));
    n_at_or_below = _mm_sub_epi64(n_at_or_below, _mm_castpd_si128(_mm_cmple_pd(d, g)));
    last = now;
  };
  for (; j + 4 <= m; j += 4) {  // two pairs per step: half the loop overhead
    count(_mm_loadh_pd(_mm_load_sd(&p[j].t), &p[j + 1].t));
    count(_mm_loadh_pd(_mm_load_sd(&p[j + 2].t), &p[j + 3].t));
  }
  if (j + 2 <= m) {
    count(_mm_loadh_pd(_mm_load_sd(&p[j].t), &p[j + 1].t));
    j += 2;
  }
  alignas(16) std::uint64_t lanes[2];
  _mm_store_si128(reinterpret_cast<__m128i*>(lanes), n_below);
  below += lanes[0] + lanes[1];
  _mm_store_si128(reinterpret_cast<__m128i*>(lanes), n_at_or_below);
  at_or_below += lanes[0] + lanes[1];
  if (j > 0) prev = p[j - 1].t;
#endif
  for (; j < m; ++j) {
    const double d = p[j].t - prev;
    below += d < guess;
    at_or_below += d <= guess;
    prev = p[j].t;
  }
}

// Track readings pinned at one positive value (a clipped converter) so the lead-in before a
// long clip is still buffered when the coast leaves it. last_v is v(i - 1) when i > base_, NaN
// when i == base_ (so a new reading there starts a run of its own). A changed reading is a run
// of one: only a repeated one can make a plateau.
[[gnu::always_inline]] inline void RunDetector::track_repeats(std::size_t i, double value, std::size_t& same_start,
                                                              double& last_v) {
  if (value != last_v) {
    same_start = i;
    last_v = value;
  } else if (value > 0 && i + 1 - same_start >= 5) {
    plateau_start_ = same_start;
    plateau_end_ = i;
    have_plateau_ = true;
  }
}

void RunDetector::push(double t_s, double value) {
  if (!std::isfinite(t_s) || !std::isfinite(value)) [[unlikely]] {
    ++non_finite_;  // reported by finish(); not a sample, so it takes no index
    return;
  }
  if (t_s < last_t_) [[unlikely]] time_went_back(t_s);  // never for the first sample: last_t_ is -inf
  const double prev_t = last_t_;  // -inf for a stream's first sample
  last_t_ = t_s;
  const std::size_t i = next_index_++;
  if (next_index_ - base_ > ring_size()) [[unlikely]] grow_ring();
  const Sample s{t_s, value};
  ring_[i & mask_] = s;
  track_repeats(i, value, same_start_, last_v_);
  switch (state_) {
    case State::idle: idle_step(i, s, prev_t); break;
    case State::coasting: coast_step(i, s, prev_t); break;
    case State::tail: tail_step(i, s); break;
  }
}

void RunDetector::push_many(const double* t_s, const double* value, std::size_t n) {
  std::size_t k = 0;
  while (k < n) {
    if (state_ == State::coasting) {
      const std::size_t next = coast_run(t_s, value, k, n);
      if (next != k) {
        k = next;
        continue;
      }
    }
    push(t_s[k], value[k]);
    ++k;
  }
}

// push() and coast_step() for one coasting sample after another, the same calls in the same
// order, on local copies of the state push() would read and write for them, put back into the
// detector once instead of through its members per sample. A sample push() would treat
// otherwise (not finite, time going back, the ring full) is left to push().
std::size_t RunDetector::coast_run(const double* t_s, const double* value, std::size_t k, const std::size_t n) {
  return hold_long_live_ ? coast_loop<true>(t_s, value, k, n) : coast_loop<false>(t_s, value, k, n);
}

// The loop for a coast with (LongLive) or without the long hold window: without it, the loop
// has no trace of that window, and fewer values compete for registers.
template <bool LongLive>
std::size_t RunDetector::coast_loop(const double* t_s, const double* value, std::size_t k, const std::size_t n) {
  const CoastLimits c = coast_limits();
  Sample* const ring = ring_.get();  // c.ring, writable: the loop stores each sample
  const std::size_t mask = c.mask, capacity = ring_size();
  std::size_t i = next_index_, same_start = same_start_;
  double last_t = last_t_, last_v = last_v_, level_min = level_min_;
  int rising = rising_;
  WindowFit h = hold_;
  WindowFit hl;
  if constexpr (LongLive) hl = hold_long_;
  const auto put_back = [&] {
    next_index_ = i;
    same_start_ = same_start;
    last_t_ = last_t;
    last_v_ = last_v;
    level_min_ = level_min;
    rising_ = rising;
    hold_ = h;
    if constexpr (LongLive) hold_long_ = hl;
  };
  for (; k < n; ++k) {
    const Sample s{t_s[k], value[k]};
    // push() takes a sample that is not finite, goes back in time or follows a silence of over 2 s.
    if (!std::isfinite(s.t) || !std::isfinite(s.v) || s.t < last_t || s.t - last_t > 2.0 || i + 1 - c.base > capacity)
      break;
    last_t = s.t;
    ring[i & mask] = s;
    track_repeats(i, s.v, same_start, last_v);
    advance(h, ring, mask, i, s);
    if constexpr (LongLive) advance(hl, ring, mask, i, s);
    const std::size_t at = i++;
    const CoastVerdict v = coast_verdict(at, s, h, level_min, rising, c);
    if (v.what != CoastVerdict::go_on) [[unlikely]] {
      put_back();
      act_on(v, at, false);
      return k + 1;
    }
  }
  put_back();
  return k;
}

// Out of line and cold: formatting the note inside push() would cost every sample a stack frame.
[[gnu::cold, gnu::noinline]] void RunDetector::time_went_back(double t_s) {
  emit_diag(Diagnostic::Severity::note,
            fmt::format("time went back from {} to {} at sample {}: taken as a clock restart", fmt_s(last_t_),
                        fmt_s(t_s), next_index_));
  clock_restart();
}

void RunDetector::clock_restart() {
  restarted_mid_coast_ = state_ == State::coasting;
  if (state_ == State::coasting) {
    run_note_severity_ = Diagnostic::Severity::warning;  // the run is cut short: it changes the result
    close_unstopped(next_index_,
                    "the device clock restarted mid-coast (an Arduino reset?): the coast is cut short there",
                    Run::End::clock_restart);
  }
  else if (state_ == State::tail) complete_run(next_index_);
  base_ = next_index_;
  time_cursor_ = next_index_;
  have_plateau_ = false;
  need_rise_ = false;
  stream_start_ = next_index_;
  resume_index_ = 0;
  last_t_ = -std::numeric_limits<double>::infinity();
  last_v_ = std::numeric_limits<double>::quiet_NaN();
  state_ = State::idle;
  lo_ = next_index_;
  need_quiet_ = false;
  short_.clear(next_index_, 0.0);
  long_.clear(next_index_, 0.0);
  vlong_.clear(next_index_, 0.0);
  hold_long_.clear(next_index_, 0.0);
  quiet_until_s_ = -std::numeric_limits<double>::infinity();
  hold_.clear(next_index_, 0.0);
}

void RunDetector::finish() {
  // A recording that ends soon after the stop: the hold window alone decides.
  if (state_ == State::coasting && next_index_ > base_)
    coast_checks(next_index_ - 1, ring_[(next_index_ - 1) & mask_], true);
  if (state_ == State::coasting) close_unstopped(next_index_, "the recording ends mid-coast (never reached standstill)", Run::End::end_of_data);
  else if (state_ == State::tail) complete_run(next_index_);
  if (state_ != State::idle) to_idle(next_index_, false);
  if (non_finite_ > 0) {
    emit_diag(Diagnostic::Severity::warning,
              fmt::format("{} non-finite sample(s) (NaN/inf time or value) ignored", non_finite_));
    non_finite_ = 0;
  }
}

void RunDetector::went_silent(double silent_s) {
  if (state_ == State::coasting && next_index_ > base_) coast_checks(next_index_ - 1, ring_[(next_index_ - 1) & mask_], true);
  if (state_ == State::coasting) {
    run_note_severity_ = Diagnostic::Severity::warning;
    close_unstopped(next_index_,
                    fmt::format("no samples for {:g} s: the bench went silent mid-coast; fitted to its last sample, "
                                "and samples after the silence are not in this run",
                                silent_s),
                    Run::End::silent);
    to_idle(next_index_, false);
    // What comes after is found afresh: a coast going on is partial, from its first sample.
    resume_index_ = next_index_;
    resume_pause_s_ = silent_s;
  } else if (state_ == State::tail) {
    complete_run(next_index_);
    to_idle(next_index_, false);
  }
}

void RunDetector::to_idle(std::size_t lo, bool need_quiet) {
  // After a stop, a new coast must start above the standstill: a slow coast's last creep
  // after a premature stop is not a new run.
  need_rise_ = state_ == State::tail && run_.stopped;
  block_band_ = 0;
  rise_level_ = run_.zero_level + depart_band_;
  state_ = State::idle;
  lo_ = lo;
  need_quiet_ = need_quiet;
  rising_ = departing_ = 0;
  reset_window(short_, lo, next_index_);
  reset_window(long_, lo, next_index_);
  reset_window(vlong_, lo, next_index_);
  trim_idle();
}

void RunDetector::trim_idle() {
  if (next_index_ == base_) return;
  // Enough for the longest window and a few doublings of the back-search.
  const double keep_s = idle_keep_s;
  const double t_now = t(next_index_ - 1);
  // The first sample within keep_s only moves forward: amortized O(1) per sample.
  time_cursor_ = std::max({time_cursor_, lo_, base_});
  while (time_cursor_ + 1 < next_index_ && t_now - t(time_cursor_) > keep_s) ++time_cursor_;
  std::size_t keep_from = time_cursor_;
  // Keep enough samples for a slow loop's back-search, and what the windows still use.
  const std::size_t min_keep = back_search_min_samples + 16;
  if (next_index_ - keep_from < min_keep) keep_from = next_index_ > min_keep ? next_index_ - min_keep : 0;
  keep_from = std::max(keep_from, base_);
  keep_from = std::min({keep_from, short_.first, long_.first, vlong_.first});
  // A recent pinned stretch shorter than keep_s may be a clip the coast has yet to leave.
  if (have_plateau_ && plateau_end_ >= base_ && plateau_start_ >= base_ && t_now - t(plateau_end_) <= keep_s &&
      t(plateau_end_) - t(plateau_start_) <= keep_s)
    keep_from = std::min(keep_from, std::max(base_, plateau_start_ >= back_search_min_samples
                                                        ? plateau_start_ - back_search_min_samples
                                                        : std::size_t{0}));
  // Bounded memory whatever the timing.
  if (next_index_ - keep_from > opt_.max_buffer) keep_from = next_index_ - opt_.max_buffer;
  base_ = std::max(base_, keep_from);
  if (short_.first < base_) reset_window(short_, base_, next_index_);
  if (long_.first < base_) reset_window(long_, base_, next_index_);
  if (vlong_.first < base_) reset_window(vlong_, base_, next_index_);
}

[[gnu::always_inline]] inline bool RunDetector::confirms_decline(const WindowFit& w) const {
  // Cheapest tests first: an idle lead-in (zeros, a steady supply) fails one of them.
  if (w.n < 6 || w.first < lo_) return false;
  // The slope's sign is Sxy's (Sxx > 0, else the slope is 0): a level or rising window, half of
  // an idle lead-in, is out before the divisions.
  if (!(w.stv - w.st() * w.sv() / w.n < 0)) return false;
  const double mu = w.mean();
  if (!(mu > 0)) return false;
  const double dur = duration(w);
  if (dur < 0.8 * w.span_s) return false;
  const double s = w.slope();
  if (!(s < 0)) return false;
  const double sd = w.resid_sd();
  if (sd > confirm_max_roughness * mu) return false;
  if (-s * dur < 0.002 * mu) return false;
  return -s * std::sqrt(w.sxx()) >= confirm_t_stat * sd;
}

void RunDetector::idle_step(std::size_t i, Sample s, double prev_t) {
  // A coast closed before its stop (cap, signal lost) blocks new runs until the reading rises
  // well above the lowest it has shown since: a new spin-up does, the rest of that coast never.
  if (block_band_ > 0) [[unlikely]]
    rise_level_ = std::min(rise_level_, s.v + block_band_);
  // A pause in the recording (over 2 s): what follows may be a coast whose cut it hid.
  if (s.t - prev_t > 2.0) [[unlikely]] {
    resume_index_ = i;
    resume_pause_s_ = s.t - prev_t;
  }
  advance(short_, i, s);
  advance(long_, i, s);
  advance(vlong_, i, s);
  if (need_quiet_) {
    // After a coast closed without a stop the decline may go on: wait for it to pause.
    const bool full = long_.n >= 8 && duration(long_) >= 0.8 * long_.span_s;
    if (full) {
      const double sd = long_.resid_sd();
      const double s = long_.slope();
      const bool declining = s < 0 && -s * std::sqrt(long_.sxx()) > 2.0 * sd;
      if (!declining) need_quiet_ = false;
    }
    trim_idle();
    return;
  }
  if (t(i) >= quiet_until_s_) {
    bool tried = false;
    for (const WindowFit* w : {&short_, &long_, &vlong_}) {
      if (confirms_decline(*w)) {
        tried = true;
        if (try_start_coast(i, *w)) return;
      }
    }
    if (tried) quiet_until_s_ = t(i) + 2.0 * short_.span_s;  // look again once the windows moved on
  }
  trim_idle();
}

RunDetector::CutSplit RunDetector::split_at_cut(std::size_t a, std::size_t b, const WindowFit& w) {
  const std::size_t lower = std::max(lo_, base_);
  CutSplit sp;
  sp.a = a;

  // A reading pinned at its maximum and left without a step: the converter's top.
  double m = v(a);
  for (std::size_t k = a; k <= b; ++k) m = std::max(m, v(k));
  std::size_t p = b + 1;  // last pinned sample
  for (std::size_t k = b; k >= a + 2 && k <= b; --k) {
    if (v(k) == m && v(k - 1) == m && v(k - 2) == m) {
      p = k;
      break;
    }
  }
  if (p < b) {
    std::size_t q = p;  // first pinned sample
    while (q > lower && v(q - 1) == m) --q;
    // Quantized data plateaus too; a clipped reading is pinned much longer than the longest
    // plateau of the coast after it.
    std::size_t longest = 1, cur = 1;
    for (std::size_t k = p + 2; k <= b; ++k) {
      cur = v(k) == v(k - 1) ? cur + 1 : 1;
      longest = std::max(longest, cur);
    }
    const std::size_t pinned = p - q + 1;
    const double leave = m - v(p + 1);
    // … and much longer than one step of the reading lasts at the coast's start: a heavy
    // flywheel's coast holds its first printed value for a second, unclipped.
    const double slope = w.slope(), step = std::max(reading_step(p + 1, b + 1), leave);
    const double period = b > p + 1 ? (t(b) - t(p + 1)) / double(b - p - 1) : 0.0;
    const double step_lasts = slope < 0 && period > 0 && step > 0 ? step / -slope / period : 0.0;
    if (q > lower && pinned >= 5 && pinned >= 3 * longest && pinned >= 3.0 * step_lasts && leave > 0 &&
        leave <= 0.02 * std::abs(m) + 3.0 * w.resid_sd()) {
      sp.clipped = true;
      sp.pin_first = q;
      sp.pin_last = p;
      sp.pin_level = m;
      sp.a = std::max(lower, std::min(a, q >= back_search_min_samples ? q - back_search_min_samples : 0));
      sp.cut_index = p + 1;
      sp.t_cut_s = 0.5 * (t(q - 1) + t(q));
      sp.pre_end = q;
      sp.v0 = m;
      sp.sd_post = w.resid_sd();
    }
  }

  if (!sp.clipped) {
    // Two-segment least squares over [a, b]: constant lead-in [a, c), linear coast [c, b].
    const std::size_t n = b - a + 1;
    double* pv = scratch(6 * (n + 1));  // prefix Σv, Σv² of [a, a+k)
    double* pvv = pv + (n + 1);
    double* ss = pvv + (n + 1);  // suffix Σt, Σt², Σv, Σtv of [a+k, b] (t relative to t(b))
    double* stt_ = ss + (n + 1);
    double* sv_ = stt_ + (n + 1);
    double* stv_ = sv_ + (n + 1);
    pv[0] = pvv[0] = 0.0;
    ss[n] = stt_[n] = sv_[n] = stv_[n] = 0.0;
    for (std::size_t k = 0; k < n; ++k) {
      const double x = v(a + k);
      pv[k + 1] = pv[k] + x;
      pvv[k + 1] = pvv[k] + x * x;
    }
    const double tr = t(b);
    for (std::size_t k = n; k-- > 0;) {
      const double tt = t(a + k) - tr, x = v(a + k);
      ss[k] = ss[k + 1] + tt;
      stt_[k] = stt_[k + 1] + tt * tt;
      sv_[k] = sv_[k + 1] + x;
      stv_[k] = stv_[k + 1] + tt * x;
    }
    const double svv_all = pvv[n];
    struct Line {
      double v0 = 0, slope = 0, sd = 0;
    };
    auto post_line = [&](std::size_t k) {
      const double np = double(n - k);
      const double sxx = stt_[k] - ss[k] * ss[k] / np;
      const double sxy = stv_[k] - ss[k] * sv_[k] / np;
      const double syy = (svv_all - pvv[k]) - sv_[k] * sv_[k] / np;
      Line l;
      l.slope = sxx > 0 ? sxy / sxx : 0.0;
      l.v0 = sv_[k] / np + l.slope * ((t(a + k) - tr) - ss[k] / np);
      l.sd = np > 2 ? std::sqrt(std::max(syy - l.slope * sxy, 0.0) / (np - 2)) : 0.0;
      return l;
    };
    // Best split with the lead-in starting at kb. The confirming window may straddle a small
    // step (supply → back-EMF), so the split may fall anywhere that leaves a few samples for
    // the line.
    auto best_split = [&](std::size_t kb) {
      double best = std::numeric_limits<double>::infinity();
      std::size_t best_k = kb;
      for (std::size_t k = kb; k + 3 <= n; ++k) {
        const double m = double(k - kb);
        const double sp_ = pv[k] - pv[kb];
        const double sse_pre = k > kb ? (pvv[k] - pvv[kb]) - sp_ * sp_ / m : 0.0;
        const double np = double(n - k);
        const double sxx = stt_[k] - ss[k] * ss[k] / np;
        const double sxy = stv_[k] - ss[k] * sv_[k] / np;
        const double syy = (svv_all - pvv[k]) - sv_[k] * sv_[k] / np;
        const double sse_post = sxx > 0 ? syy - sxy * sxy / sxx : syy;
        const double sse = std::max(sse_pre, 0.0) + std::max(sse_post, 0.0);
        if (sse < best) {
          best = sse;
          best_k = k;
        }
      }
      return best_k;
    };
    std::size_t kb = 0;
    std::size_t k = best_split(0);
    // Two steps in reach (zeros → supply → back-EMF): the coast follows the later one, taken
    // when it splits a flat plateau from the coast by a clear step.
    for (int again = 0; again < 3; ++again) {
      const std::size_t k2 = best_split(k);
      if (k2 < k + 3) break;
      const double m = double(k2 - k);
      const double mean = (pv[k2] - pv[k]) / m;
      const double sd = std::sqrt(std::max((pvv[k2] - pvv[k]) / m - mean * mean, 0.0));
      const Line l = post_line(k2);
      const double scale = std::abs(l.v0);
      if (std::abs(l.v0 - mean) <= std::max(5.0 * l.sd, 0.03 * scale) || sd > std::max(3.0 * l.sd, 0.02 * scale))
        break;
      kb = k;
      k = k2;
    }
    const Line l = post_line(k);
    const std::size_t c = a + k;
    sp.a = a + kb;
    sp.v0 = l.v0;
    sp.post_slope = l.slope;
    sp.sd_post = l.sd;
    sp.cut_index = c;
    sp.pre_end = c;
    const bool sample_before = c > base_ && c > stream_start_ && c - 1 >= lo_;
    sp.t_cut_s = sample_before ? 0.5 * (t(c - 1) + t(c)) : t(c);
  }

  // The lead-in [a, pre_end): level, roughness, maximum and trend.
  sp.npre = sp.pre_end - sp.a;
  if (sp.npre >= 3) {
    WindowFit f;
    f.clear(sp.a, t(sp.a));
    sp.pre_max = v(sp.a);
    for (std::size_t k = sp.a; k < sp.pre_end; ++k) {
      f.add(t(k), v(k));
      sp.pre_max = std::max(sp.pre_max, v(k));
    }
    sp.pre_mean = f.mean();
    sp.pre_sd = std::sqrt(std::max(f.svv() / f.n - sp.pre_mean * sp.pre_mean, 0.0));
    // A lead-in falling at a good part of the coast's own rate is more coast: the cut lies
    // further back.
    const double s = f.slope(), sd = f.resid_sd();
    const double s_err = f.sxx() > 0 ? sd / std::sqrt(f.sxx()) : 0.0;
    const bool smooth = sd <= std::max(3.0 * sp.sd_post, 0.02 * std::abs(sp.v0));  // not a wandering pin
    sp.pre_declining = sp.npre >= 8 && smooth && s < 0 && -s > 3.0 * s_err &&
                       (sp.clipped || sp.post_slope >= 0 || s <= 0.3 * sp.post_slope);
    sp.pre_flat = sp.npre >= 8 && std::abs(s) + 2.0 * s_err <= 0.3 * std::abs(sp.post_slope);
  }
  return sp;
}

double RunDetector::smoothed(std::size_t k, std::size_t lo, std::size_t hi) const {
  const std::size_t from = k > lo ? k - 1 : k, to = std::min(k + 2, hi + 1);
  double sum = 0;
  for (std::size_t j = from; j < to; ++j) sum += v(j);
  return sum / double(to - from);
}

bool RunDetector::at_peak(CutSplit& sp, std::size_t b) {
  if (sp.clipped || b < sp.cut_index + 3) return false;
  const double thr = std::max(4.0 * sp.sd_post, 0.02 * std::abs(sp.v0));
  // The highest reading (a 3-sample mean, so one noisy sample does not make the peak) from the
  // cut found to the newest sample.
  std::size_t p = sp.cut_index;
  double top3 = 3.0 * smoothed(p, sp.cut_index, b);  // three times the mean: sums compared, no division
  for (std::size_t k = sp.cut_index + 1; k < b; ++k) {
    const double m3 = v(k - 1) + v(k) + v(k + 1);
    if (m3 > top3) top3 = m3, p = k;
  }
  const double top = top3 / 3.0;
  if (top > smoothed(sp.cut_index, sp.cut_index, b) + thr && p < b) {
    // A rise after the cut found: the coast starts at its peak, and what came before is the rise.
    sp.pre_end = p;
    sp.cut_index = p;
    sp.t_cut_s = t(p);
    sp.v0 = top;
    sp.npre = p - sp.a;
    sp.pre_declining = false;
    WindowFit coast;  // the coast's line and noise from the peak on (the rise is not its noise)
    coast.clear(p, t(p));
    for (std::size_t k = p; k <= b; ++k) coast.add(t(k), v(k));
    sp.post_slope = coast.slope();
    sp.sd_post = coast.resid_sd();
    return true;
  }
  // A lead-in that climbs into the cut: its last samples rise to the coast's start.
  const std::size_t c = sp.cut_index;
  if (c < sp.a + 6) return false;
  const double before = smoothed(c - 5, sp.a, b), last = smoothed(c - 2, sp.a, b);
  return last > before + thr && last >= sp.v0 - thr && before < sp.v0 - 2.0 * thr;
}

std::string RunDetector::start_not_seen(CutSplit& sp) {
  const std::size_t c = sp.cut_index;
  // The first sample after the stream's start or the last pause, whichever came last.
  const bool after_pause = resume_index_ > stream_start_;
  const std::size_t seen_from = after_pause ? resume_index_ : stream_start_;
  if (c < seen_from || std::max(sp.a, base_) > seen_from) return {};
  // From there to the cut found, a "lead-in" that lies on the coast's line is more coast.
  const std::size_t a = seen_from;
  if (c > a) {
    const double tol = std::max(4.0 * sp.sd_post, 0.01 * std::abs(sp.v0));
    double sse = 0;
    for (std::size_t k = a; k < c; ++k) {
      const double r = v(k) - (sp.v0 + sp.post_slope * (t(k) - t(c)));
      sse += r * r;
    }
    if (sp.post_slope >= 0 || std::sqrt(sse / double(c - a)) > tol) return {};
    // … and is not clearly flatter than the coast (a noisy plateau within the tolerance is a
    // lead-in, its step hidden in the noise).
    if (c - a >= 5) {
      const WindowFit pre = window_over(ring_.get(), mask_, 1e300, a, c);
      // A quantized reading can repeat one value over a few samples of a coast: its spread is at
      // least the step's.
      const double e = std::max(pre.resid_sd(), reading_step(a, c + 1) * step_sd);
      const double s = pre.slope(), se = pre.sxx() > 0 ? e / std::sqrt(pre.sxx()) : 0.0;
      if (s - sp.post_slope > 3.0 * se && s > 0.5 * sp.post_slope) return {};
    }
  }
  sp.cut_index = a;
  sp.pre_end = a;
  sp.npre = 0;
  sp.t_cut_s = t(a);
  sp.v0 = sp.v0 + sp.post_slope * (t(a) - t(c));
  if (after_pause)
    return fmt::format("the recording paused for {:.3g} s (until {}) right before this coast: its cut was not "
                       "recorded, so the coast is taken from the first sample after the pause",
                       resume_pause_s_, fmt_s(t(a)));
  return fmt::format("the recording starts mid-coast at {}: the cut was not recorded, so the coast is partial",
                     fmt_s(t(a)));
}

std::string RunDetector::classify_lead_in(const CutSplit& sp) const {
  if (sp.npre < 3) return "none";
  const double scale = std::abs(sp.v0);
  const double step = sp.v0 - sp.pre_mean;
  // No step beyond the noise of either side: a powered motor whose speed is the reading.
  if (std::abs(step) <= std::max({3.0 * sp.sd_post, 4.0 * sp.pre_sd, 0.01 * scale})) return "powered";
  if (step < 0) return "supply";
  if (sp.pre_sd > std::max(0.02 * scale, 3.0 * sp.sd_post)) return "floating";
  if (std::abs(sp.pre_mean) <= 0.1 * scale) return "zeros";
  return "floating";
}

bool RunDetector::try_start_coast(std::size_t i, const WindowFit& w) {
  const std::size_t b = i;
  const std::size_t w0 = w.first;
  const std::size_t lower = std::max(lo_, base_);
  double span = std::max(back_search_s, 2.0 * w.span_s);
  CutSplit sp;
  std::string lead;
  for (int attempt = 0;; ++attempt) {
    std::size_t a = w0;
    while (a > lower && t(w0) - t(a - 1) <= span) --a;
    if (w0 - a < back_search_min_samples) a = w0 - std::min(w0 - lower, back_search_min_samples);
    sp = split_at_cut(a, b, w);
    lead = classify_lead_in(sp);
    // Search further back when the lead-in seen is too short to judge, is itself part of the
    // decline, or is a "plateau" not shown to be flatter than the coast.
    const bool unsure = sp.npre < 8 || sp.pre_declining || (lead == "powered" && !sp.pre_flat);
    if (unsure && a > lower && attempt < 5) {
      span *= 2;
      continue;
    }
    break;
  }

  // The coast begins at the peak, never before a rise: a motor's ramp or a hand's push straight
  // into the peak (a speed sensor's reading) is the powered phase, not the coast.
  const bool spin_up = at_peak(sp, b);
  if (spin_up) lead = "spin-up";
  // A coast whose start was not recorded: the recording (or the stream after a clock restart)
  // begins on it, or resumes on it after a pause. Its cut is not known: the coast is partial and
  // taken from its first sample, never given an invented cut in the pause or a lead-in.
  std::string unseen;
  if (!spin_up && !sp.clipped) unseen = start_not_seen(sp);
  if (!unseen.empty()) lead = "none";

  // Whether this is a cut at all.
  bool plausible = sp.v0 > 0;
  const double scale = std::abs(sp.v0);
  if (lead == "none") plausible = plausible && !unseen.empty();  // a stream that starts mid-coast, or a pause
  if (lead == "powered" && sp.pre_sd > 0.05 * scale) plausible = false;  // a rough "plateau"
  if ((lead == "zeros" || lead == "floating") && sp.v0 < 1.5 * sp.pre_max) plausible = false;
  if (spin_up && sp.pre_declining) sp.pre_declining = false;  // the rise's own end, not a decline
  if (sp.pre_declining) plausible = false;  // a decline with no cut in reach
  // A cut without a step (a kink, or a stream that starts mid-coast) rests on the slope alone:
  // a quarter-second window of noise can fake it, so it needs a window of a second or more.
  if ((lead == "powered" || lead == "none") && w.span_s < 1.0) plausible = false;
  if (need_rise_ && sp.v0 < rise_level_) plausible = false;  // the last coast, still creeping down
  if (!plausible) return false;

  run_ = Run{};
  run_.number = accepted_ + 1;
  run_.cut_index = sp.cut_index;
  run_.t_cut_s = sp.t_cut_s;
  run_.lead_in = lead;
  run_note_.clear();
  run_note_severity_ = Diagnostic::Severity::note;
  fragment_ = restarted_mid_coast_ && sp.cut_index == stream_start_;
  restarted_mid_coast_ = false;
  if (!unseen.empty() && !fragment_) {
    run_note_ = unseen;
    run_note_severity_ = Diagnostic::Severity::warning;
  }
  if (sp.clipped) {
    emit_diag(Diagnostic::Severity::warning,
              fmt::format("run {}: reading pinned at {:g} (converter's top?) from {} to {} ({} samples): "
                          "the coast is taken from where it leaves it",
                          run_.number, sp.pin_level, fmt_s(t(sp.pin_first)), fmt_s(t(sp.pin_last)),
                          sp.pin_last - sp.pin_first + 1));
  }
  v0_ = sp.v0;
  standstill_ceiling_ = v0_ > 0 ? standstill_max_fraction * v0_ : std::numeric_limits<double>::infinity();
  coast_sd_ = sp.sd_post;
  coast_step_ = reading_step(sp.cut_index, i + 1);
  lead_in_zero_ = lead == "zeros" ? sp.pre_mean : std::numeric_limits<double>::quiet_NaN();
  rise_jump_ = std::max(0.1 * std::abs(v0_), 8.0 * coast_sd_);
  level_min_ = std::numeric_limits<double>::infinity();
  rising_ = 0;
  state_ = State::coasting;
  {
    RunEvent e;
    e.kind = RunEvent::Kind::cut;
    e.run = run_;
    events_.push_back(std::move(e));
  }
  reset_window(hold_, run_.cut_index, i + 1);
  hold_long_live_ = false;  // built when the coast gets low (saves work on the way down)
  creeping_ = false;
  coast_checks(i, ring_[i & mask_]);
  return true;
}

void RunDetector::coast_too_long(std::size_t i) {
  if (buffered() > opt_.max_buffer) {
    RunEvent e;
    e.kind = RunEvent::Kind::ignored;
    e.run = run_;
    e.has_diagnostic = true;
    e.diagnostic = {Diagnostic::Severity::warning, source_, 0,
                    fmt::format("run cut at {}: coast longer than max_buffer ({} samples) abandoned",
                                fmt_s(run_.t_cut_s), opt_.max_buffer)};
    events_.push_back(std::move(e));
    to_idle(i + 1, true);
    return;
  }
  // The coast was within max_coast_s until one step jumped past it: a gap in the recording
  // (logging paused, the device clock jumped), not a coast that went on too long. The sample
  // after the gap is not this coast's, and the user must hear that the coast was cut short.
  if (i > run_.cut_index && t(i - 1) - run_.t_cut_s <= opt_.max_coast_s && long_silence(t(i - 1), t(i), run_.t_cut_s)) {
    run_note_severity_ = Diagnostic::Severity::warning;
    close_unstopped(i,
                    fmt::format("{}: the coast is cut short there and fitted as never stopped; the samples "
                                "after the gap are not in this run",
                                gap_before(i)),
                    Run::End::gap);
    to_idle(i, false);
    // What follows is found afresh: a coast going on after it is partial, from its first sample.
    resume_index_ = i;
    resume_pause_s_ = t(i) - t(i - 1);
    return;
  }
  run_note_severity_ = Diagnostic::Severity::warning;
  close_unstopped(i + 1,
                  fmt::format("no standstill within max_coast_s ({:g} s): closed there as never stopped; the rest of "
                              "this coast is not a run",
                              opt_.max_coast_s),
                  Run::End::cap);
  to_idle(i + 1, true);
  // The coast goes on: no new run until the reading rises above where it was closed, or has come
  // down to the motor's zero (stopped) first.
  block_until_rise(v(i));
}

void RunDetector::power_back() {
  const std::size_t at = rise_start_;
  close_unstopped(at, fmt::format("the reading rose again at {} before standstill (power restored?)", fmt_s(t(at))),
                  Run::End::power_back);
  to_idle(at, false);
}

void RunDetector::standstill_checks(std::size_t i, bool at_end, double mu, double sxx, double e) {
  // The hold window is flat and low (coast_checks has shown it: mu is its mean, sxx and e its
  // Sxx and residual sd), and either its slope is resolved well below the coast's mean rate or
  // a three times longer window is flat too (noisy, slow coasts).
  bool resolved = at_end;
  if (!at_end) {
    const double mean_rate = (v0_ - mu) / std::max(t(i) - run_.t_cut_s, 1e-9);
    // A quantized reading can sit on one value for the whole window (e = 0) while the motor still
    // turns: its resolution is at best the step's uniform spread. A coast so slow that its first
    // samples showed no step yet learns it here, once.
    if (coast_step_ == 0) coast_step_ = reading_step(run_.cut_index, i + 1);
    const double e_eff = std::max(e, coast_step_ * step_sd);
    resolved = sxx > 0 && e_eff / std::sqrt(sxx) <= slope_resolution * mean_rate;
  }
  if (creeping_ && !at_end) resolved = false;  // an asymptotic coast ends when the long window is flat
  if (!resolved) {
    if (!hold_long_live_) {
      // Three hold windows, or 3 % of the coast so far if longer: a heavy flywheel's coast falls a
      // few mV a second near its end, which a 3 s window of noisy readings can take for level.
      hold_long_.span_s = std::max(3.0 * opt_.stop_hold_s, long_hold_fraction * (t(i) - run_.t_cut_s));
      reset_window(hold_long_, run_.cut_index, i + 1);
      hold_long_live_ = true;
    }
    if (!flat(hold_long_)) return;
  }
  found_standstill(i, at_end);
}

bool RunDetector::flat(const WindowFit& w) const {
  if (w.n < 3 || w.first < run_.cut_index) return false;
  const double d = duration(w);
  if (d < 0.9 * w.span_s) return false;
  double sxx = 0, e = 0;
  return level(w, d, w.mean(), v0_, sxx, e);
}

namespace {
// level()'s allowance for rounding, in the reading's unit.
inline double level_tiny(double v0, double m) {
  const double scale = std::max(std::abs(v0), std::abs(m));
  return 1e-12 * (scale > 0 ? scale : 1.0);
}
}  // namespace

// With T = flat_t_stat: level() needs |s|·√Sxx ≤ T·e + tiny, so R = Sxy²/Sxx ≤ (T·e + tiny)² ≤
// 2T²·e² + 2·tiny², e² = (Syy − R)/(n − 2). Multiplied through by n·Sxx·(n − 2), with n·Sxx = n·Σt²
// − (Σt)² and so on, that bound needs no division: a window above it is certainly not level.
// Each of n·Sxx, n·Sxy, n·Syy is taken at the end of its rounding band least favourable to that
// (10⁻⁹ of the terms it is the difference of, and of the coast's scale: a constant reading's n·Syy
// rounds to ±10⁻¹², not 0), and a further 10⁻⁴ is asked for, so it never turns away a window
// level() would accept. A coast still falling (t ≫ 4) it turns away: most of the low samples.
[[gnu::always_inline]] inline bool RunDetector::clearly_sloped(const WindowFit& w, double v0, double m) {
  constexpr double band = 1e-9;
  const double n = w.n;
  const double st = w.st(), stt = w.stt(), sv = w.sv(), svv = w.svv(), stv = w.stv;
  const double nsxx = n * stt - st * st, nsxy = n * stv - st * sv, nsyy = n * svv - sv * sv;
  if (!(nsxx > 0)) return false;  // level() takes the slope as 0 then
  // Sliding sums keep the rounding of readings long gone: a window of zeros after a coast from
  // v0 can hold Σv² = −10⁻¹³. So the bands also count readings of the coast's scale.
  const double scale = std::max(std::abs(v0), std::abs(m));
  const double nsxx_hi = nsxx + band * (n * stt + st * st);
  const double nsyy_hi = std::max(0.0, nsyy + band * (n * std::abs(svv) + sv * sv + n * n * scale * scale));
  const double nsxy_lo =
      std::max(0.0, std::abs(nsxy) - band * (n * std::abs(stv) + std::abs(st * sv) + n * std::abs(st) * scale));
  const double two_t2 = 2 * flat_t_stat * flat_t_stat, tiny = level_tiny(v0, m);
  const double lhs = (n - 2 + two_t2) * nsxy_lo * nsxy_lo;
  const double rhs = (two_t2 * nsyy_hi + 2 * tiny * tiny * n * (n - 2)) * nsxx_hi;
  return lhs > rhs * (1 + 1e-4);
}

[[gnu::always_inline]] inline bool RunDetector::level(const WindowFit& w, double d, double m, const double v0, double& sxx,
                                                      double& e) {
  const bool low = v0 > 0 ? m <= standstill_max_fraction * v0 : true;
  if (!low) return false;
  // w.slope() and w.resid_sd() (n >= 3), sharing Sxx and Sxy: the same operations, done once.
  sxx = w.sxx();
  const double sxy = w.stv - w.st() * w.sv() / w.n;
  const double s = sxx > 0 ? sxy / sxx : 0.0;
  const double syy = w.svv() - w.sv() * w.sv() / w.n;
  const double sse = sxx > 0 ? syy - sxy * sxy / sxx : syy;
  e = std::sqrt(std::max(sse, 0.0) / (w.n - 2));
  const double tiny = level_tiny(v0, m);
  const bool no_slope = std::abs(s) * std::sqrt(sxx) <= flat_t_stat * e + tiny;
  const bool small_drop = std::abs(s) * d <= std::max(3.0 * e, 0.01 * std::abs(v0)) + tiny;
  return no_slope && small_drop;
}

double RunDetector::reading_step(std::size_t from, std::size_t to) const {
  double step = std::numeric_limits<double>::infinity();
  for (std::size_t k = from + 1; k < to; ++k) {
    const double d = std::abs(v(k) - v(k - 1));
    if (d > 0) step = std::min(step, d);
  }
  return std::isfinite(step) ? step : 0.0;
}

void RunDetector::found_standstill(std::size_t i, bool at_end) {
  const std::size_t h0 = hold_.first;
  const double z = median_of(h0, i + 1);
  double var = 0;
  for (std::size_t k = h0; k <= i; ++k) var += (v(k) - z) * (v(k) - z);
  const double sd_z = std::sqrt(var / double(i + 1 - h0));
  const double amp = v0_ - z;
  const double band = std::max(3.0 * sd_z, 1e-9 * std::max(std::abs(amp), 1e-300));

  // First sample of the standstill that contains the hold window (an isolated sample outside
  // the band is noise; two in a row are the coast).
  std::size_t first_in = i + 1;
  while (first_in > run_.cut_index + 1) {
    if (std::abs(v(first_in - 1) - z) <= band) {
      --first_in;
    } else if (first_in - 1 > run_.cut_index + 1 && std::abs(v(first_in - 2) - z) <= band && first_in - 1 < i + 1) {
      first_in -= 2;  // lone outlier
    } else {
      break;
    }
  }
  first_in = std::min(first_in, i);
  if (signal_lost(i, first_in, z, amp)) return;

  // Where the coast crossed the last quarter of its amplitude.
  const double quarter = z + 0.25 * amp;
  std::size_t k = first_in;
  while (k > run_.cut_index && v(k - 1) <= quarter) --k;
  double t_quarter = t(k);
  if (k > run_.cut_index) {
    const double va = v(k - 1), vb = v(k);
    t_quarter = va > vb ? t(k - 1) + (t(k) - t(k - 1)) * (va - quarter) / (va - vb) : t(k);
  }

  // Stop time: the approach line (the last ≤2 s above the band) meets the zero level.
  double t_hit = t(first_in);
  {
    std::size_t from = first_in;
    while (from > k && t(first_in) - t(from - 1) <= 2.0) --from;
    if (first_in >= from + 3) {
      WindowFit f;
      f.clear(from, t(from));
      for (std::size_t j = from; j < first_in; ++j) f.add(t(j), v(j));
      const double sl = f.slope();
      if (sl < 0) {
        const double tb = f.st() / f.n, vb = f.mean();
        const double th = f.t0 + tb + (z - vb) / sl;
        if (std::isfinite(th)) t_hit = std::clamp(th, t_quarter, t(i));
      }
    }
  }
  // The first sample at or after t_hit (times never decrease within a stream), at most i.
  std::size_t lo = run_.cut_index + 1, hi = std::max(lo, i);
  while (lo < hi) {
    const std::size_t mid = lo + (hi - lo) / 2;
    if (t(mid) < t_hit) lo = mid + 1;
    else hi = mid;
  }
  const std::size_t stop = lo;
  // A stop that falls in a pause of the recording is known only to lie in it.
  if (stop > run_.cut_index + 2) {
    const double pause = t(stop) - t(stop - 1);
    const double period = (t(stop - 1) - t(run_.cut_index)) / double(stop - 1 - run_.cut_index);
    if (pause > 1.0 && pause > 25.0 * period) {
      run_note_ = fmt::format("the stop falls in a pause of the recording ({:.3g} s, from {} to {}): it lies somewhere "
                              "in it, and the stop time is the pause's end",
                              pause, fmt_s(t(stop - 1)), fmt_s(t(stop)));
      run_note_severity_ = Diagnostic::Severity::warning;
    }
  }

  // A real stop arrives with a finite slope; an exponential creeps in.
  const double t_stop = t(stop);
  const double coast = t_stop - run_.t_cut_s;
  const double last_quarter = t_stop - t_quarter;
  const double end_rate = last_quarter > 0 ? 0.25 * coast / last_quarter : std::numeric_limits<double>::infinity();

  run_.zero_level = z;
  run_.noise_level = sd_z;
  // … and right before it the reading still falls clearly (an exponential has flattened).
  double approach_t = std::numeric_limits<double>::infinity();
  {
    std::size_t from = stop;
    while (from > run_.cut_index && t_stop - t(from - 1) <= opt_.stop_hold_s) --from;
    if (stop >= from + 3) {
      WindowFit f;
      f.clear(from, t(from));
      for (std::size_t j = from; j < stop; ++j) f.add(t(j), v(j));
      const double e = f.resid_sd();
      approach_t = e > 0 ? -f.slope() * std::sqrt(f.sxx()) / e : (f.slope() < 0 ? approach_t : 0.0);
    }
  }
  if (end_rate >= stop_min_end_rate || approach_t >= stop_min_approach_t || amp <= 0) {
    run_.stopped = true;
    run_.stop_index = stop;
    run_.t_stop_s = t_stop;
    depart_band_ = std::max(6.0 * sd_z, 0.05 * std::abs(amp));
    departing_ = 0;
    state_ = State::tail;
    RunEvent e;
    e.kind = RunEvent::Kind::stop;
    e.run = run_;
    events_.push_back(std::move(e));
    tail_ends_by_time(i);
  } else if (!creeping_ && !at_end) {
    // Keep the coast until the decay is lost in the noise even over the long window: the
    // exponential's tail still carries information for the fit.
    creeping_ = true;
  } else {
    // The floor an asymptotic coast shows is where its decay was lost in the noise or the print,
    // not where it is heading (an exponential heads for the true zero): 0.01 V on the lab's
    // 2-decimal print long before the motor stops, and subtracting that from every reading
    // bends the viscous curve into Coulomb friction that is not there. A floor the detector's
    // own flatness test cannot tell from the lead-in's zero (the motor at rest, read before the
    // run) gives way to that zero: within 3 noise sd, 1 % of the cut's reading (level()'s
    // allowance for a flat window's drop) or one reading step. A floor clearly above it (an
    // offset only the coasting reading has) is kept.
    std::string floor_said;
    const double band = std::max({3.0 * sd_z, 0.01 * std::abs(v0_), reading_step(hold_.first, i + 1)});
    if (std::isfinite(lead_in_zero_) && std::abs(z - lead_in_zero_) <= band * (1 + 1e-9) && z != lead_in_zero_) {
      run_.zero_level = lead_in_zero_;
      floor_said = fmt::format(", not to be told from the lead-in's zero, so zero level {:g}", lead_in_zero_);
    }
    run_note_ = fmt::format(
        "run cut at {}: the coast approaches its floor ({:g}{}) asymptotically (last quarter {:.2f}x slower than "
        "the mean rate), as pure viscous friction does: treated as never stopped, coast closed at {}",
        fmt_s(run_.t_cut_s), z, floor_said, end_rate > 0 ? 1.0 / end_rate : 0.0, fmt_s(t(i)));
    run_.stopped = false;
    run_.end = Run::End::asymptotic;
    complete_run(i + 1);
    to_idle(i + 1, true);
  }
}

void RunDetector::block_until_rise(double level) {
  need_rise_ = true;
  block_band_ = rise_jump_;  // as far above as power coming back
  rise_level_ = level + block_band_;
}

bool RunDetector::signal_lost(std::size_t i, std::size_t first_in, double z, double amp) {
  if (first_in < run_.cut_index + 8 || !(amp > 0)) return false;
  const double zero = motor_zero();
  // The coast's last reading before the standstill, and the first sample that held it.
  const std::size_t last = first_in - 1;
  std::size_t held = last;
  while (held > run_.cut_index && v(held - 1) == v(last)) --held;
  // The most friction lets the reading fall in one sample: the coast's slope over the second
  // before the held value, per period.
  std::size_t from = held;  // the second before the held value, found from its end
  while (from > run_.cut_index && t(held) - t(from - 1) <= 1.0) --from;
  WindowFit f = window_over(ring_.get(), mask_, 1.0, from, held);
  if (f.n < 5) return false;  // too few samples to know how fast friction lets it fall
  // A sensor that gives up reads zero (the motor's, when the lead-in showed it) after it.
  if (std::abs(z - zero) > 0.05 * amp) return false;
  const double period = t(first_in) - t(last);
  const double fall = f.n >= 5 ? std::max(-f.slope(), 0.0) * period : 0.0;
  const double drop = v(last) - z;
  // A collapse: a fall far beyond the coast's, from a reading held longer than the coast allows
  // (friction would have moved it two steps), or beyond any fall the coast showed. A lab stop's
  // last printed values (0.02, 0.01 on the 2-decimal print) are neither.
  const double held_for = double(first_in - held);
  const bool big_drop = drop > std::max({10.0 * fall, 6.0 * f.resid_sd(), 3.0 * coast_step_, 0.005 * amp});
  const bool long_hold = held_for * fall > std::max(2.0 * coast_step_, 3.0 * f.resid_sd());
  const bool collapse = big_drop && (long_hold || drop > 30.0 * fall);
  if (!collapse) return false;
  const double level = v(held);
  run_note_severity_ = Diagnostic::Severity::warning;
  close_unstopped(held + 1,
                  fmt::format("signal lost below {:g} at {}: {} where friction lets it fall about {:.2g} a sample; a "
                              "sensor that gives up at low speed (per-revolution pulses, an encoder, a display)? "
                              "Fitted up to there, as never stopped",
                              level, fmt_s(t(held)),
                              fmt::format("the reading fell from {:g} to {:g} in one sample", v(last), z),
                              fall > 1e-9 * amp ? fall : 0.0),
                  Run::End::signal_lost);
  to_idle(i + 1, true);
  // No new run until the reading rises above what the sensor last showed (or after a standstill).
  block_until_rise(std::max(level, z));
  return true;
}

void RunDetector::tail_ends_by_time(std::size_t upto) {
  const double t_end = run_.t_stop_s + opt_.tail_s;
  for (std::size_t e = run_.stop_index + 1; e <= upto; ++e) {
    if (t(e) >= t_end) {
      complete_run(e);
      to_idle(e, false);
      return;
    }
  }
}

void RunDetector::tail_step(std::size_t i, Sample s) {
  if (buffered() > opt_.max_buffer) {
    complete_run(i);
    to_idle(i, false);
    return;
  }
  // Still falling: the "standstill" was a noisy stretch of a slow coast. Retract the stop and
  // keep coasting (the stop event was provisional; only complete runs are final).
  advance(hold_, i, s);
  if (hold_long_live_) advance(hold_long_, i, s);
  if (hold_.n >= 3 && hold_.first >= run_.stop_index) {
    const double drop = run_.zero_level - hold_.mean();
    // drop <= 0 never exceeds the band (its first term is >= 0): the usual case, without a sqrt.
    if (drop > 0 &&
        drop > std::max(4.0 * run_.noise_level / std::sqrt(hold_.n), retract_fraction * (v0_ - run_.zero_level))) {
      retract_stop(i, s);
      return;
    }
  }
  // A new spin-up (the next run's lead-in) ends the tail.
  if (s.v - run_.zero_level > depart_band_) {
    if (departing_++ == 0) depart_start_ = i;
    if (departing_ >= 2) {
      const std::size_t at = depart_start_;
      complete_run(at);
      to_idle(at, false);
      return;
    }
  } else {
    departing_ = 0;
  }
  if (s.t >= run_.t_stop_s + opt_.tail_s) {
    if (still_falling(i)) {
      retract_stop(i, s);
      return;
    }
    const std::size_t end = departing_ > 0 ? depart_start_ : i;
    complete_run(end);
    to_idle(end, false);
  }
}

bool RunDetector::still_falling(std::size_t i) const {
  // Over the whole tail, a slope many standard errors below zero, lower than the quantization
  // allows a level reading, and at least a third of the approach's: the "standstill" was a slow
  // exponential's stretch (a viscous coast at a fraction of its start), not a stop.
  if (i < run_.stop_index + 8) return false;
  const WindowFit w = window_over(ring_.get(), mask_, 1e300, run_.stop_index, i + 1);
  const double sxx = w.sxx();
  if (!(sxx > 0)) return false;
  const double slope = w.slope();
  const double e = std::max(w.resid_sd(), coast_step_ * step_sd);
  const double mean_rate = (v0_ - run_.zero_level) / std::max(run_.t_stop_s - run_.t_cut_s, 1e-9);
  return slope < 0 && -slope * std::sqrt(sxx) > 6.0 * e && -slope > 0.1 * mean_rate;
}

void RunDetector::retract_stop(std::size_t i, Sample s) {
  emit_diag(Diagnostic::Severity::note,
            fmt::format("run cut at {}: standstill at {} retracted, the reading kept falling", fmt_s(run_.t_cut_s),
                        fmt_s(run_.t_stop_s)));
  run_.stopped = false;
  run_.t_stop_s = std::numeric_limits<double>::quiet_NaN();
  state_ = State::coasting;
  level_min_ = std::numeric_limits<double>::infinity();
  rising_ = 0;
  coast_checks(i, s);
}

void RunDetector::close_unstopped(std::size_t end, const std::string& why, Run::End reason) {
  run_.stopped = false;
  run_.end = reason;
  run_.zero_level = 0;
  run_.noise_level = coast_sd_;
  run_note_ = fmt::format("run cut at {}: {}", fmt_s(run_.t_cut_s), why);
  complete_run(end);
}

// A long silence inside a fitted coast. Samples lost while the motor coasted on leave the
// reading lower after the gap by about the coast's slope times the gap, and the fit is right to
// take the times as given (a note). A device clock that jumped while the readings went on
// leaves the reading where it was: the fit's times are then wrong by the jump, and so is its
// friction (a warning). Said once per run, for the longest gap.
void RunDetector::warn_of_gap_in_coast(int number, std::size_t from, std::size_t at, double longest, double period_s) {
  if (at == 0 || !(longest > std::max(1.0, 25.0 * period_s))) return;
  WindowFit before{1.0};  // the coast's slope over the second before the gap
  reset_window(before, from, at);
  const double expected = before.n >= 5 ? -before.slope() * longest : 0.0;
  const double fell = v(at - 1) - v(at);
  const std::string gap = fmt::format("run {}: {}", number, gap_before(at));
  if (expected > 6.0 * before.resid_sd() && expected > 0 && fell < 0.5 * expected)
    emit_diag(Diagnostic::Severity::warning,
              fmt::format("{}: the device clock jumped? The reading fell {:.3g} across it where the coast would "
                          "have fallen {:.3g}; the fit takes the times as given, so its friction is wrong by the jump",
                          gap, fell, expected));
  else
    emit_diag(Diagnostic::Severity::note,
              fmt::format("{}: the reading fell across it as the coast would, taken as samples lost", gap));
}

void RunDetector::scan_coast(Run& r, std::size_t coast_end) {
  // One pass over the coast for its longest silence and its outliers. An outlier is a single
  // sample far off its two neighbours' midpoint, which agree with each other (|b - a| well
  // below the offset, so the time interpolation differs little from the midpoint): a dropout
  // (a loose wire reads 0) or a glitch (a missed pulse halves a speed), not the motor, which
  // cannot leave its course for one sample and come back.
  std::size_t gap_at = 0;
  double longest = 0;
  const double said = std::max(1.0, 25.0 * r.period_s);  // a shorter silence is not said: not looked for
  const double floor = std::max(10.0 * coast_sd_, 5.0 * coast_step_);
  const Sample* ring = ring_.get();
  std::string where;
  std::size_t shown = 0;
  const auto outlier = [&](std::size_t k, double a, double c, double b, double tk) {
    const double expected = 0.5 * (a + b), off = std::abs(c - expected);
    if (off > floor && off > 0.1 * std::abs(expected) && std::abs(b - a) < 0.5 * off) {
      r.outliers.push_back(k);
      if (shown++ < 10) where += fmt::format("{}{} at {} (expected {:.3g})", shown > 1 ? ", " : "", c, fmt_s(tk), expected);
    }
  };
  // Samples k of [cut + 1, coast_end - 1), over the ring in stretches whose triples (k - 1, k,
  // k + 1) do not wrap, each scanned first without a branch for any sample off by more than the
  // floor (the usual answer: none).
  std::size_t k = r.cut_index + 1;
  while (k + 1 < coast_end) {
    const std::size_t at = (k - 1) & mask_;
    const std::size_t n = std::min(coast_end - 1 - k, ring_size() - 2 - std::min(at, ring_size() - 2));
    if (n == 0) {  // the triple wraps: one sample the slow way
      if (t(k) - t(k - 1) > std::max(longest, said)) longest = t(k) - t(k - 1), gap_at = k;
      outlier(k, v(k - 1), v(k), v(k + 1), t(k));
      ++k;
      continue;
    }
    const Sample* p = ring + at;
    double widest = 0;  // the stretch's longest period (its place found only if it matters)
    bool any = false;
    std::size_t j = 0;
#if defined(__SSE2__)  // elsewhere (arm64 benches) the plain loop below does them all
    // Two samples per step in SSE2 lanes: each Sample is one (t, v) register; the periods
    // t(k) - t(k-1) and the offsets from the neighbours' midpoint are the plain loop's.
    {
      const __m128d half = _mm_set1_pd(0.5), fl = _mm_set1_pd(floor), sign = _mm_set1_pd(-0.0);
      __m128d wmax = _mm_setzero_pd(), over = _mm_setzero_pd();
      __m128d x0 = _mm_loadu_pd(&p[0].t), x1 = _mm_loadu_pd(&p[1].t);
      for (; j + 2 < n; j += 2) {  // reads p[j + 3]: j + 3 <= n + 1, within the stretch
        const __m128d x2 = _mm_loadu_pd(&p[j + 2].t), x3 = _mm_loadu_pd(&p[j + 3].t);
        wmax = _mm_max_pd(wmax, _mm_sub_pd(_mm_unpacklo_pd(x1, x2), _mm_unpacklo_pd(x0, x1)));
        const __m128d a = _mm_unpackhi_pd(x0, x1), c = _mm_unpackhi_pd(x1, x2), b = _mm_unpackhi_pd(x2, x3);
        const __m128d off = _mm_andnot_pd(sign, _mm_sub_pd(c, _mm_mul_pd(half, _mm_add_pd(a, b))));
        over = _mm_or_pd(over, _mm_cmpgt_pd(off, fl));
        x0 = x2, x1 = x3;
      }
      alignas(16) double w[2];
      _mm_store_pd(w, wmax);
      widest = std::max(w[0], w[1]);
      any = _mm_movemask_pd(over) != 0;
    }
#endif
    for (; j < n; ++j) {
      widest = std::max(widest, p[j + 1].t - p[j].t);
      any |= std::abs(p[j + 1].v - 0.5 * (p[j].v + p[j + 2].v)) > floor;
    }
    if (widest > std::max(longest, said)) [[unlikely]]
      for (std::size_t m = 0; m < n; ++m)
        if (p[m + 1].t - p[m].t > std::max(longest, said)) longest = p[m + 1].t - p[m].t, gap_at = k + m;
    if (any) [[unlikely]]
      for (std::size_t m = 0; m < n; ++m) outlier(k + m, p[m].v, p[m + 1].v, p[m + 2].v, p[m + 1].t);
    k += n;
  }
  if (k < coast_end && k > r.cut_index && t(k) - t(k - 1) > std::max(longest, said))
    longest = t(k) - t(k - 1), gap_at = k;
  warn_of_gap_in_coast(r.number, r.cut_index, gap_at, longest, r.period_s);
  if (r.outliers.empty()) return;
  emit_diag(Diagnostic::Severity::warning,
            fmt::format("run {}: {} single-sample outlier(s) left out of the fit (dropouts or glitches): {}{}", r.number,
                        r.outliers.size(), where, r.outliers.size() > 10 ? ", …" : ""));
}

std::string RunDetector::gap_before(std::size_t i) const {
  return fmt::format("no samples for {:.3g} s mid-coast (from {} to {})", t(i) - t(i - 1), fmt_s(t(i - 1)),
                     fmt_s(t(i)));
}

std::string RunDetector::fragment_reason(const Run& r, double amp, double coast_s) const {
  // How far the reading fell in this coast, against what the reading can resolve and against the
  // runs already found in this stream (a nudge, a few samples at a crawl, a piece of a coast).
  if (amp < 3.0 * coast_step_)
    return fmt::format("it falls {:.3g}, under 3 of the reading's steps ({:.2g})", amp, coast_step_);
  // Beside the runs before it, only a coast seen to stop is judged: one cut short (end of data, a
  // gap) may have fallen little so far for reasons that are no fault of its own.
  if (accepted_ == 0 || !r.stopped) return {};
  return small_beside(amp, coast_s, largest_amp_, longest_coast_s_);
}

std::string RunDetector::small_beside(double amp, double coast_s, double largest_amp, double longest_s) {
  if (amp < 0.03 * largest_amp)
    return fmt::format("it falls {:.3g}, under 3 % of the largest run's {:.3g}", amp, largest_amp);
  if (coast_s < 0.25 * longest_s && amp < 0.1 * largest_amp)
    return fmt::format("{:.3g} s and a fall of {:.3g}, beside runs of up to {:.3g} s and {:.3g}", coast_s, amp,
                       longest_s, largest_amp);
  return {};
}

void RunDetector::warn_of_held_standstill(const Run& r) {
  // A standstill that reads one value exactly, well above the motor's zero, held far longer than
  // any value of the coast before it: what a sensor that keeps its last reading shows (an rpm
  // counter whose pulses stopped). A real offset is reached a reading step at a time, and a
  // sensor's freeze cannot be told from a stop for sure: said, not decided.
  if (r.end_index < r.stop_index + 10 || r.stop_index < r.cut_index + 10) return;
  // The standstill's last value, and where it began (the stop's first samples may still be the
  // coast's last values).
  const double z = v(r.end_index - 1);
  std::size_t held_from = r.end_index - 1;
  while (held_from > r.cut_index && v(held_from - 1) == z) --held_from;
  const std::size_t held = r.end_index - held_from;
  if (held < 10 || 5 * held < 4 * (r.end_index - r.stop_index)) return;  // most of the standstill
  const double zero = motor_zero();
  if (!(z - zero > std::max(0.02 * (v0_ - zero), 3.0 * coast_step_))) return;
  // Reached by a jump of many reading steps (an rpm counter's last update), not by the one step
  // a coarse reading takes onto a real offset.
  if (!(v(held_from - 1) - z > 10.0 * coast_step_)) return;
  std::size_t from = held_from, longest = 1, cur = 1;
  while (from > r.cut_index && t(held_from) - t(from - 1) <= 2.0) --from;
  for (std::size_t k = from + 1; k < held_from; ++k) {
    cur = v(k) == v(k - 1) ? cur + 1 : 1;
    longest = std::max(longest, cur);
  }
  if (held < 5 * longest || held_from < from + 3) return;
  // The reading's resolution there (the smallest gap between the values it took): a level of a
  // step or two above zero is a coarse reading's offset, not a frozen one.
  double* x = scratch(held_from - from);
  for (std::size_t k = from; k < held_from; ++k) x[k - from] = v(k);
  std::sort(x, x + (held_from - from));
  double resolution = std::numeric_limits<double>::infinity();
  for (std::size_t k = 1; k < held_from - from; ++k)
    if (x[k] > x[k - 1]) resolution = std::min(resolution, x[k] - x[k - 1]);
  if (!(z - zero > 3.0 * resolution)) return;
  emit_diag(Diagnostic::Severity::warning,
            fmt::format("run {}: the standstill reads exactly {:g} for its last {} samples, {:.1f} % of the reading at "
                        "the cut, where no value of the coast before it lasted more than {}: a sensor holding its "
                        "last value? If the motor went on to 0, the zero level and the fits are wrong",
                        r.number, z, held, 100.0 * (z - zero) / (v0_ - zero), longest));
}

void RunDetector::warn_of_earlier_fragments(const Run& r, double amp, double coast_s) {
  // A nudge before the real spin was a run when it came (nothing larger was known): it stays one,
  // live and offline alike, but the user hears what it looks like now.
  for (Earlier& e : earlier_) {
    if (e.warned || !e.stopped) continue;
    const std::string why = small_beside(e.amp, e.coast_s, amp, coast_s);
    if (why.empty()) continue;
    e.warned = true;
    emit_diag(Diagnostic::Severity::warning,
              fmt::format("run {} (cut at {}) looks like a fragment beside run {} ({}): a nudge before the real "
                          "spin? It stays a run, since it came first; leave it out of your results if so",
                          e.number, fmt_s(e.t_cut_s), r.number, why));
  }
  if (earlier_.size() == max_earlier) earlier_.erase(earlier_.begin());
  earlier_.push_back({r.number, r.t_cut_s, amp, coast_s, r.stopped, false});
}

void RunDetector::complete_run(std::size_t end) {
  Run r = run_;
  end = std::max(end, r.cut_index);
  r.end_index = end;
  if (r.stopped) r.end = Run::End::stopped;
  r.t_end_s = end > r.cut_index ? t(end - 1) : r.t_cut_s;
  if (r.stopped) {
    r.stop_index = std::min(r.stop_index, end);
    if (end > r.stop_index) {
      r.zero_level = median_of(r.stop_index, end);
      double var = 0;
      for (std::size_t k = r.stop_index; k < end; ++k) var += (v(k) - r.zero_level) * (v(k) - r.zero_level);
      r.noise_level = std::sqrt(var / double(end - r.stop_index));
    }
  } else {
    r.stop_index = end;
    r.t_stop_s = std::numeric_limits<double>::quiet_NaN();
  }
  const std::size_t coast_end = r.stopped ? r.stop_index : end;
  if (coast_end > r.cut_index + 1) r.period_s = median_period(r.cut_index, coast_end);
  const std::size_t coast_n = coast_end - r.cut_index;
  const double coast_s = (r.stopped ? r.t_stop_s : (end > r.cut_index ? t(end - 1) : r.t_cut_s)) - r.t_cut_s;

  // How far the reading fell: to the standstill, or to the coast's last sample.
  const double amp = v0_ - (r.stopped || coast_n == 0 ? r.zero_level : v(coast_end - 1));

  RunEvent e;
  e.run = r;
  if (fragment_) {
    e.kind = RunEvent::Kind::ignored;
    e.has_diagnostic = true;
    // Fragments are said in the default output: the user sees what was left out and why.
    e.diagnostic = {Diagnostic::Severity::warning, source_, 0,
                    fmt::format("coast from {} to {} (on the restarted clock) ignored: the rest of a coast after the "
                                "device clock restarted "
                                "(reset, reconnect); its cut was not seen",
                                fmt_s(r.t_cut_s), fmt_s(r.t_end_s))};
    fragment_ = false;
  } else if (coast_s < opt_.min_coast_s || coast_n < opt_.min_samples) {
    e.kind = RunEvent::Kind::ignored;
    e.has_diagnostic = true;
    e.diagnostic = {Diagnostic::Severity::note, source_, 0,
                    fmt::format("coast cut at {} ignored: {} and {} samples (need {:g} s and {})", fmt_s(r.t_cut_s),
                                fmt_s(coast_s), coast_n, opt_.min_coast_s, opt_.min_samples)};
  } else if (const std::string why = fragment_reason(r, amp, coast_s); !why.empty()) {
    e.kind = RunEvent::Kind::ignored;
    e.has_diagnostic = true;
    e.diagnostic = {Diagnostic::Severity::warning, source_, 0,
                    fmt::format("coast cut at {} ignored as a fragment, not a run: {}", fmt_s(r.t_cut_s), why)};
  } else {
    e.kind = RunEvent::Kind::complete;
    e.run.number = ++accepted_;
    if (r.stopped) {
      warn_of_earlier_fragments(e.run, amp, coast_s);
      warn_of_held_standstill(e.run);
    }
    largest_amp_ = std::max(largest_amp_, amp);
    longest_coast_s_ = std::max(longest_coast_s_, coast_s);
    scan_coast(e.run, coast_end);
    if (!run_note_.empty()) {
      e.has_diagnostic = true;
      e.diagnostic = {run_note_severity_, source_, 0, fmt::format("run {}: {}", e.run.number, run_note_)};
    }
  }
  events_.push_back(std::move(e));
  run_note_.clear();
  run_note_severity_ = Diagnostic::Severity::note;
}

}  // namespace spindown
