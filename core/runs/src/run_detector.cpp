#include "run_detector_impl.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#include <fmt/format.h>
#include <utility>

#include "run_detector_tuning.hpp"
#include "spindown/stop_shape.hpp"

namespace spindown {

using namespace detector_tuning;

// ---- sliding least-squares line ----------------------------------------------------------

double RunDetector::Impl::duration(const WindowFit& w) const {
  return w.end > w.first ? t(w.end - 1) - t(w.first) : 0.0;
}

void RunDetector::Impl::rebuild(WindowFit& w, std::size_t from, std::size_t to) {
  w = window_over(store_.data(), store_.mask(), w.span_s, from, to);
}

void RunDetector::Impl::reset_window(WindowFit& w, std::size_t lo, std::size_t end) {
  lo = std::max(lo, store_.base());
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
[[gnu::always_inline]] inline void RunDetector::Impl::advance(WindowFit& w, const Sample* ring, const std::size_t mask,
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

[[gnu::always_inline]] inline void RunDetector::Impl::advance(WindowFit& w, std::size_t i, Sample s) {
  advance(w, store_.data(), store_.mask(), i, s);
}

[[gnu::always_inline]] inline void RunDetector::Impl::coast_step(std::size_t i, Sample s, double prev_t) {
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
[[gnu::always_inline]] inline RunDetector::Impl::CoastVerdict RunDetector::Impl::coast_verdict(std::size_t i, Sample s,
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
  if (mu > c.standstill_ceiling) {  // still high: the usual case, cheap
    // Now and then: has the "coast" held a plateau up there (a powered step, not a coast)?
    if (t_i >= c.plateau_check_t) [[unlikely]] return {CoastVerdict::plateau};
    return {};
  }
  // Low: while the coast still falls the hold window is not level, and nothing else is to do.
  if (clearly_sloped(h, c.v0, mu)) return {};  // most low samples: no division, no square root
  CoastVerdict v{CoastVerdict::level, mu};
  if (!level(h, dur, mu, c.v0, v.sxx, v.e)) return {};
  return v;
}

// What a verdict asks for; the state it read must be the detector's own again.
void RunDetector::Impl::act_on(const CoastVerdict& v, std::size_t i, bool at_end) {
  switch (v.what) {
    case CoastVerdict::go_on: break;
    case CoastVerdict::too_long: coast_too_long(i); break;
    case CoastVerdict::power_back: power_back(); break;
    case CoastVerdict::level: standstill_checks(i, at_end, v.mu, v.sxx, v.e); break;
    case CoastVerdict::plateau: held_plateau(i); break;
  }
}

[[gnu::always_inline]] inline void RunDetector::Impl::coast_checks(std::size_t i, Sample s, bool at_end) {
  const CoastVerdict v = coast_verdict(i, s, hold_, level_min_, rising_, coast_limits());
  if (v.what != CoastVerdict::go_on) [[unlikely]] act_on(v, i, at_end);
}

// ---- detector ----------------------------------------------------------------------------

RunDetector::Impl::Impl(RunOptions opt, std::string source) : opt_(std::move(opt)), source_(std::move(source)) {
  set_spans(0.0);
}

// The windows' spans for a stream sampled every period_s (0: fast enough for the spans in seconds):
// each holds its least number of samples, n of them spanning n − 1 periods. A tenth more keeps
// them when the clock jitters by up to that, and still lets them count as full (a window is
// judged once it spans 0.9 of its span, a confirming one 0.8); it keeps no more for n < 11.
void RunDetector::Impl::set_spans(double period_s) {
  const auto periods = [](std::size_t samples) { return 1.1 * double(samples - 1); };
  vlong_.span_s = std::max(4.0, periods(confirm_min_samples) * period_s);
  hold_.span_s = std::max(opt_.stop_hold_s, periods(hold_min_samples) * period_s);
  hold_long_.span_s = 3.0 * hold_.span_s;
  hold_half_s_ = 0.5 * hold_.span_s;
  hold_full_s_ = 0.9 * hold_.span_s;
  // The shortest period that would widen a window.
  slow_period_ = std::min(vlong_.span_s / periods(confirm_min_samples), hold_.span_s / periods(hold_min_samples));
}

void RunDetector::Impl::follow_slow_period(std::size_t i, double dt) {
  if (slow_last_ + 1 != i) slow_count_ = 0, slow_longest_ = 0;  // a new run of slow periods
  slow_last_ = i;
  slow_longest_ = std::max(slow_longest_, dt);
  // A single late sample (a fast logger's hiccup, samples lost) is no rate: a run of them is.
  if (++slow_count_ >= confirm_min_samples) set_spans(slow_longest_);
}

double RunDetector::Impl::shortest_period(const WindowFit& w) const {
  double p = std::numeric_limits<double>::infinity();
  for (std::size_t k = w.first + 1; k < w.end; ++k) p = std::min(p, t(k) - t(k - 1));
  return std::isfinite(p) ? p : 0.0;
}

std::vector<RunEvent> RunDetector::Impl::take_events() {
  std::vector<RunEvent> out;
  out.swap(events_);
  return out;
}

void RunDetector::Impl::emit_run_event(RunEvent::Kind kind) {
  RunEvent e;
  e.kind = kind;
  e.run = run_;
  events_.push_back(std::move(e));
}

void RunDetector::Impl::emit_diag(Diagnostic::Severity sev, std::string msg) {
  RunEvent e;
  e.kind = RunEvent::Kind::diagnostic;
  e.diagnostic = {sev, source_, 0, std::move(msg)};
  e.has_diagnostic = true;
  events_.push_back(std::move(e));
}

double* RunDetector::Impl::scratch(std::size_t size) {
  if (size > scratch_size_) {
    scratch_size_ = std::max(size, 2 * scratch_size_);
    scratch_ = std::make_unique_for_overwrite<double[]>(scratch_size_);
  }
  return scratch_.get();
}

double RunDetector::Impl::median_of(std::size_t from, std::size_t to) {
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

double RunDetector::Impl::median_period(std::size_t from, std::size_t to) {
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
      const std::size_t stretch_end = std::min({to, (k | store_.mask()) + 1, k + chunk});
      count_periods(store_.data() + (k & store_.mask()), stretch_end - k, guess, prev, below, at_or_below);
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

void RunDetector::Impl::count_periods(const Sample* p, std::size_t m, double guess, double& prev, std::size_t& below,
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
// long clip is still buffered when the coast leaves it. last_v is v(i - 1) when i > store_.base(), NaN
// when i == store_.base() (so a new reading there starts a run of its own). A changed reading is a run
// of one: only a repeated one can make a plateau.
[[gnu::always_inline]] inline void RunDetector::Impl::track_repeats(std::size_t i, double value, std::size_t& same_start,
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

void RunDetector::Impl::push(double t_s, double value) {
  if (!std::isfinite(t_s) || !std::isfinite(value)) [[unlikely]] {
    ++non_finite_;  // reported by finish(); not a sample, so it takes no index
    return;
  }
  if (t_s < last_t_) [[unlikely]] time_went_back(t_s);  // never for the first sample: last_t_ is -inf
  const double prev_t = last_t_;  // -inf for a stream's first sample
  last_t_ = t_s;
  const Sample s{t_s, value};
  const std::size_t i = store_.push(s);
  track_repeats(i, value, same_start_, last_v_);
  switch (state_) {
    case State::idle: idle_step(i, s, prev_t); break;
    case State::coasting: coast_step(i, s, prev_t); break;
    case State::tail: tail_step(i, s); break;
  }
}

void RunDetector::Impl::push_many(const double* t_s, const double* value, std::size_t n) {
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
std::size_t RunDetector::Impl::coast_run(const double* t_s, const double* value, std::size_t k, const std::size_t n) {
  return hold_long_live_ ? coast_loop<true>(t_s, value, k, n) : coast_loop<false>(t_s, value, k, n);
}

// The loop for a coast with (LongLive) or without the long hold window: without it, the loop
// has no trace of that window, and fewer values compete for registers.
template <bool LongLive>
std::size_t RunDetector::Impl::coast_loop(const double* t_s, const double* value, std::size_t k, const std::size_t n) {
  const CoastLimits c = coast_limits();
  Sample* const ring = store_.data();  // c.ring, writable: the loop stores each sample
  const std::size_t mask = c.mask, capacity = store_.capacity();
  std::size_t i = store_.end(), same_start = same_start_;
  double last_t = last_t_, last_v = last_v_, level_min = level_min_;
  int rising = rising_;
  WindowFit h = hold_;
  WindowFit hl;
  if constexpr (LongLive) hl = hold_long_;
  const auto put_back = [&] {
    store_.set_end(i);
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
[[gnu::cold, gnu::noinline]] void RunDetector::Impl::time_went_back(double t_s) {
  emit_diag(Diagnostic::Severity::note,
            fmt::format("time went back from {} to {} at sample {}: taken as a clock restart", fmt_s(last_t_),
                        fmt_s(t_s), store_.end()));
  clock_restart();
}

void RunDetector::Impl::clock_restart() {
  restart_stream("the device clock restarted mid-coast (an Arduino reset?): the coast is cut short there",
                 Run::End::clock_restart);
}

void RunDetector::Impl::new_source(const std::string& why) {
  restart_stream(why + ": the coast is cut short there", Run::End::new_source);
}

void RunDetector::Impl::restart_stream(const std::string& why, Run::End reason) {
  // The stream so far ends here. A coast whose reading had come down to the motor's zero, or that
  // a sensor held on its last value for longer than the coast's own fall allows (it gave up), may
  // have stopped before the restart: the hold window decides, as at a recording's end. Any other
  // is cut short.
  if (state_ == State::coasting && store_.end() > run_.cut_index + 2) {
    const std::size_t last = store_.end() - 1;
    const double band = std::max({4.0 * coast_sd_, 3.0 * coast_step_, 1e-9 * std::abs(v0_)});
    if (std::abs(v(last) - motor_zero()) <= band || held_into(store_, run_.cut_index, store_.end(), coast_step_) < store_.end())
      coast_checks(last, store_.at(last), true);
  }
  restarted_mid_coast_ = state_ == State::coasting;
  after_silence_ = false;  // a new timeline: nothing on it continues the silenced coast
  if (state_ == State::coasting) {
    run_note_severity_ = Diagnostic::Severity::warning;  // the run is cut short: it changes the result
    close_unstopped(store_.end(), why, reason);
  }
  else if (state_ == State::tail) complete_run(store_.end());
  store_.drop_before(store_.end());
  time_cursor_ = store_.end();
  have_plateau_ = false;
  need_rise_ = false;
  stream_start_ = store_.end();
  stream_after_restart_ = reason == Run::End::clock_restart;
  resume_index_ = 0;
  last_t_ = -std::numeric_limits<double>::infinity();
  last_v_ = std::numeric_limits<double>::quiet_NaN();
  state_ = State::idle;
  lo_ = search_lo_ = store_.end();
  rest_level_ = std::numeric_limits<double>::infinity();
  need_quiet_ = false;
  short_.clear(store_.end(), 0.0);
  long_.clear(store_.end(), 0.0);
  vlong_.clear(store_.end(), 0.0);
  hold_long_.clear(store_.end(), 0.0);
  set_spans(0.0);  // a new stream: its rate is learnt afresh
  slow_last_ = SIZE_MAX;
  quiet_until_s_ = -std::numeric_limits<double>::infinity();
  hold_.clear(store_.end(), 0.0);
}

void RunDetector::Impl::finish() {
  // A recording that ends soon after the stop: the hold window alone decides.
  if (state_ == State::coasting && store_.end() > store_.base())
    coast_checks(store_.end() - 1, store_.at((store_.end() - 1)), true);
  if (state_ == State::coasting) close_unstopped(store_.end(), "the recording ends mid-coast (never reached standstill)", Run::End::end_of_data);
  else if (state_ == State::tail) complete_run(store_.end());
  if (state_ != State::idle) to_idle(store_.end(), false);
  if (non_finite_ > 0) {
    emit_diag(Diagnostic::Severity::warning,
              fmt::format("{} non-finite sample(s) (NaN/inf time or value) ignored", non_finite_));
    non_finite_ = 0;
  }
}

void RunDetector::Impl::went_silent(double silent_s) {
  if (state_ == State::coasting && store_.end() > store_.base()) coast_checks(store_.end() - 1, store_.at((store_.end() - 1)), true);
  if (state_ == State::coasting) {
    // Where the coast was when the samples stopped: what resumes below it is the same coast.
    after_silence_ = true;
    silenced_run_ = run_.number;
    silence_s_ = silent_s;
    silence_level_ = store_.end() > store_.base() ? v(store_.end() - 1) : v0_;
    silence_band_ = std::max({4.0 * coast_sd_, 3.0 * coast_step_, 0.02 * std::abs(v0_)});
    run_note_severity_ = Diagnostic::Severity::warning;
    close_unstopped(store_.end(),
                    fmt::format("no samples for {:g} s: the bench went silent mid-coast; fitted to its last sample, "
                                "and samples after the silence are not in this run",
                                silent_s),
                    Run::End::silent);
    to_idle(store_.end(), false);
    // What comes after is found afresh: a coast going on is partial, from its first sample.
    resume_index_ = store_.end();
    resume_pause_s_ = silent_s;
  } else if (state_ == State::tail) {
    complete_run(store_.end());
    to_idle(store_.end(), false);
  }
}

void RunDetector::Impl::watch_after_silence(double v) {
  // A rise above where the silence began: the motor was powered again (a new run's lead-in).
  if (v > silence_level_ + silence_band_) {
    after_silence_ = false;
    return;
  }
  // A standstill: a second of readings, low beside that level, with no significant slope.
  if (long_.n >= 8 && duration(long_) >= 0.8 * long_.span_s && long_.mean() < standstill_max_fraction * silence_level_) {
    const double sd = long_.resid_sd(), slope = long_.slope();
    if (!(slope < 0 && -slope * std::sqrt(long_.sxx()) > 2.0 * sd)) after_silence_ = false;
  }
}

void RunDetector::Impl::to_idle(std::size_t lo, bool need_quiet, std::size_t search_from) {
  // After a stop, a new coast must start above the standstill: a slow coast's last creep
  // after a premature stop is not a new run.
  need_rise_ = state_ == State::tail && run_.stopped;
  block_band_ = 0;
  rise_level_ = run_.zero_level + depart_band_;
  state_ = State::idle;
  lo_ = lo;
  search_lo_ = std::max(std::min(search_from, lo), store_.base());
  need_quiet_ = need_quiet;
  rising_ = departing_ = 0;
  reset_window(short_, lo, store_.end());
  reset_window(long_, lo, store_.end());
  reset_window(vlong_, lo, store_.end());
  trim_idle();
}

void RunDetector::Impl::trim_idle() {
  if (store_.end() == store_.base()) return;
  // Enough for the longest window and a few doublings of the back-search.
  const double keep_s = idle_keep_s;
  const double t_now = t(store_.end() - 1);
  // The first sample within keep_s only moves forward: amortized O(1) per sample.
  time_cursor_ = std::max({time_cursor_, search_lo_, store_.base()});
  while (time_cursor_ + 1 < store_.end() && t_now - t(time_cursor_) > keep_s) ++time_cursor_;
  std::size_t keep_from = time_cursor_;
  // Keep enough samples for a slow loop's back-search, and what the windows still use.
  const std::size_t min_keep = back_search_min_samples + 16;
  if (store_.end() - keep_from < min_keep) keep_from = store_.end() > min_keep ? store_.end() - min_keep : 0;
  keep_from = std::max(keep_from, store_.base());
  keep_from = std::min({keep_from, short_.first, long_.first, vlong_.first});
  // A recent pinned stretch shorter than keep_s may be a clip the coast has yet to leave.
  if (have_plateau_ && plateau_end_ >= store_.base() && plateau_start_ >= store_.base() && t_now - t(plateau_end_) <= keep_s &&
      t(plateau_end_) - t(plateau_start_) <= keep_s)
    keep_from = std::min(keep_from, std::max(store_.base(), plateau_start_ >= back_search_min_samples
                                                        ? plateau_start_ - back_search_min_samples
                                                        : std::size_t{0}));
  // Bounded memory whatever the timing.
  if (store_.end() - keep_from > opt_.max_buffer) keep_from = store_.end() - opt_.max_buffer;
  store_.drop_before(keep_from);
  if (short_.first < store_.base()) reset_window(short_, store_.base(), store_.end());
  if (long_.first < store_.base()) reset_window(long_, store_.base(), store_.end());
  if (vlong_.first < store_.base()) reset_window(vlong_, store_.base(), store_.end());
}

[[gnu::always_inline]] inline bool RunDetector::Impl::confirms_decline(const WindowFit& w) const {
  // Cheapest tests first: an idle lead-in (zeros, a steady supply) fails one of them.
  if (w.n < double(confirm_min_samples) || w.first < lo_) return false;
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
  if (-s * dur < 0.002 * mu) return false;
  if (!(-s * std::sqrt(w.sxx()) >= confirm_t_stat * sd)) return false;
  // Rough about a line: an open pin's hum, or a short fast coast's own curve (rare, so out of line).
  return sd <= confirm_max_roughness * mu || smooth_curve(w, mu, -s * dur);
}

bool RunDetector::Impl::smooth_curve(const WindowFit& w, double mu, double drop) const {
  // A fast coast (a propeller's, a fan's: windage) bends within a window of a few coarse readings,
  // so a line misses it by more than a twentieth of its level while each reading follows the curve:
  // its sample-to-sample noise (second differences cancel the bend) is small beside what it fell.
  // An open pin's hum is rough from sample to sample.
  // Only a window of a second or more (a shorter one of a coarse counter is a few readings, whose
  // bend - the cut's kink - the cut search needs more of the coast to place) that holds few
  // readings (a slow logger, a coarse 20 Hz propeller log: 8-32 over the second): with more, a
  // line follows a coast's bend within the window closely enough, and a powered nudge's fall
  // would pass for a coast (the truth corpus's 'nudge before a run': 2 more invented at 64).
  return w.n >= 8 && w.n <= 32 && w.span_s >= 1.0 &&
         rough_sd(store_, w.first, w.end) <= confirm_max_roughness * std::max(mu, drop);
}

void RunDetector::Impl::idle_step(std::size_t i, Sample s, double prev_t) {
  // A coast closed before its stop (cap, signal lost) blocks new runs until the reading rises
  // well above the lowest it has shown since: a new spin-up does, the rest of that coast never.
  if (block_band_ > 0) [[unlikely]]
    rise_level_ = std::min(rise_level_, s.v + block_band_);
  // A pause in the recording (over 2 s): what follows may be a coast whose cut it hid.
  if (s.t - prev_t > pause_s) [[unlikely]] {
    resume_index_ = i;
    resume_pause_s_ = s.t - prev_t;
  } else if (s.t - prev_t > slow_period_) [[unlikely]] {
    follow_slow_period(i, s.t - prev_t);
  }
  advance(short_, i, s);
  advance(long_, i, s);
  advance(vlong_, i, s);
  // The motor's reading at rest: the lowest level a full long window has held while idle.
  if (long_.n >= 8 && long_.mean() < rest_level_ && duration(long_) >= 0.8 * long_.span_s) [[unlikely]] {
    const double sd = long_.resid_sd(), slope = long_.slope();
    if (std::abs(slope) * std::sqrt(long_.sxx()) <= 2.0 * sd + 1e-12 * std::max(1.0, std::abs(long_.mean())))
      rest_level_ = long_.mean();
  }
  if (after_silence_) [[unlikely]]
    watch_after_silence(s.v);
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

bool RunDetector::Impl::flat(const WindowFit& w) const {
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
[[gnu::always_inline]] inline bool RunDetector::Impl::clearly_sloped(const WindowFit& w, double v0, double m) {
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

[[gnu::always_inline]] inline bool RunDetector::Impl::level(const WindowFit& w, double d, double m, const double v0, double& sxx,
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

bool RunDetector::Impl::rises_steadily(std::size_t from, std::size_t to) const {
  // A line through [from, to) rising by confirm_t_stat of its standard errors, the samples about it
  // no rougher from sample to sample than about the line (a swing of an open pin's hum is not).
  if (to < from + 8) return false;
  const WindowFit f = window_over(store_.data(), store_.mask(), 1e300, from, to);
  const double e = f.resid_sd();
  return f.sxx() > 0 && e > 0 && f.slope() * std::sqrt(f.sxx()) > confirm_t_stat * e && rough_sd(store_, from, to) <= e;
}

// ---- calls of the per-sample path from the cut and the stop (inlined here) ----------------

void RunDetector::Impl::tail_step(std::size_t i, Sample s) {
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
    // A quiet, quantized reading that sat on one value above the rest's and now holds a step
    // lower: an exponential's slow steps down the print, not a standstill.
    if (floor_doubt_ && drop >= 0.5 * coast_step_) {
      retract_stop(i, s);
      return;
    }
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
  if (s.t >= tail_until_s_) {
    if (still_falling(i)) {
      retract_stop(i, s);
      return;
    }
    const std::size_t end = departing_ > 0 ? depart_start_ : i;
    complete_run(end);
    to_idle(end, false);
  }
}

void RunDetector::Impl::retract_stop(std::size_t i, Sample s) {
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

bool RunDetector::Impl::try_start_coast(std::size_t i, const WindowFit& w) {
  const std::size_t b = i;
  const std::size_t w0 = w.first;
  const std::size_t lower = std::max(search_lo_, store_.base());
  double span = std::max(back_search_s, 2.0 * w.span_s);
  CutSplit sp;
  std::string lead;
  bool rising_lead = false;
  for (int attempt = 0;; ++attempt) {
    std::size_t a = w0;
    while (a > lower && t(w0) - t(a - 1) <= span) --a;
    if (w0 - a < back_search_min_samples) a = w0 - std::min(w0 - lower, back_search_min_samples);
    const CutSplit before = sp;
    const std::string lead_before = lead;
    sp = split_at_cut(a, b, w);
    lead = classify_lead_in(sp);
    // A further search, made because a powered lead-in was not shown flat (it may be a rise into
    // the cut: a recording that begins in a spin-up), that reached the stream's start and found a
    // lead-in too short to judge, is no better than the one before it.
    if (attempt > 0 && a <= lower && sp.npre < min_lead_samples && before.npre >= min_lead_samples && !before.pre_declining &&
        lead_before == "powered" && !sp.clipped && rises_steadily(before.a, before.pre_end)) {
      sp = before;
      lead = lead_before;
      rising_lead = true;
      break;
    }
    // Search further back when the lead-in seen is too short to judge, is itself part of the
    // decline, or is a "plateau" not shown to be flatter than the coast.
    const bool unsure = sp.npre < min_lead_samples || sp.pre_declining || (lead == "powered" && !sp.pre_flat);
    if (unsure && a > lower && attempt < 5) {
      span *= 2;
      continue;
    }
    break;
  }

  // The coast begins at the peak, never before a rise: a motor's ramp or a hand's push straight
  // into the peak (a speed sensor's reading) is the powered phase, not the coast.
  // (An open pin's hum rising into the connection is no spin-up: its lead-in is rough, the rise's smooth.)
  const bool spin_up = lead != "floating" && at_peak(sp, b, rising_lead);
  if (spin_up) lead = "spin-up";
  // A coast whose start was not recorded: the recording (or the stream after a clock restart)
  // begins on it, or resumes on it after a pause. Its cut is not known: the coast is partial and
  // taken from its first sample, never given an invented cut in the pause or a lead-in.
  std::string unseen;
  if (after_silence_) {
    unseen = rest_after_silence(sp);
  } else if (!spin_up && !sp.clipped) {
    unseen = start_not_seen(sp);
  }
  if (!unseen.empty()) lead = "none";
  bounce_.clear();
  if (!spin_up && unseen.empty()) take_bounce(sp, w);

  // Whether this is a cut at all.
  bool plausible = sp.v0 > 0;
  const double scale = std::abs(sp.v0);
  if (lead == "none") plausible = plausible && !unseen.empty();  // a stream that starts mid-coast, or a pause
  // A rough "plateau" is no motor's (a twentieth of the reading), unless the reading only flickers
  // within three of its own printed steps: a per-pulse tachometer's whole-millisecond periods.
  if (lead == "powered" && sp.pre_sd > 0.05 * scale && !flickers(store_, sp.a, sp.pre_end)) plausible = false;
  // A coast from a motor at rest starts well above the zeros it leaves. A floating pin (the
  // handout's step 6: A0 is connected only after the cut) reads anywhere in 0.5–2.5 V, above or
  // below the back-EMF it is connected to: its coast needs no step, only the smooth decline the
  // open pin's hum never keeps up (a swing of the hum taken for a coast is set aside when it rises
  // again: swing_reason).
  if (lead == "zeros" && sp.v0 < 1.5 * sp.pre_max) plausible = false;
  if (spin_up && sp.pre_declining) sp.pre_declining = false;  // the rise's own end, not a decline
  if (sp.pre_declining) plausible = false;  // a decline with no cut in reach
  // A cut without a step (a kink, or a stream that starts mid-coast) rests on the slope alone:
  // a quarter-second window of noise can fake it, so it needs a window of a second or more.
  if ((lead == "powered" || lead == "none") && w.span_s < 1.0) plausible = false;
  if (need_rise_ && sp.v0 < rise_level_) plausible = false;  // the last coast, still creeping down
  if (!plausible) return false;
  pin_level_ = std::numeric_limits<double>::quiet_NaN();
  const bool pinned_lead = lead == "powered" && !sp.clipped && pinned_lead_in(sp, i);
  if (lead == "powered" && sp.pre_flat && !sp.clipped && !pinned_lead && bounce_.empty()) refine_plateau_cut(sp, i);

  run_ = Run{};
  run_.number = accepted_ + 1;
  run_.cut_index = sp.cut_index;
  run_.t_cut_s = sp.t_cut_s;
  run_.lead_in = lead;
  run_note_.clear();
  run_note_severity_ = Diagnostic::Severity::note;
  fragment_ = restarted_mid_coast_ && sp.cut_index == stream_start_;
  restarted_mid_coast_ = false;
  after_silence_ = false;
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
  if (pinned_lead) {
    emit_diag(Diagnostic::Severity::warning,
              fmt::format("run {}: the powered reading sat at its highest value, {:g}, until {}: the converter's top (a "
                          "supply above its range), so the power-off may lie anywhere before that, hidden under it; "
                          "the coast is taken from where the reading first comes down, and its readings at the top "
                          "are left out of the fit",
                          run_.number, pin_level_, fmt_s(run_.t_cut_s)));
  } else if (!sp.clipped) {
    find_pinned_start(i);
  }
  v0_ = sp.v0;
  standstill_ceiling_ = v0_ > 0 ? standstill_max_fraction * v0_ : std::numeric_limits<double>::infinity();
  coast_sd_ = sp.sd_post;
  coast_step_ = reading_step(store_, sp.cut_index, i + 1);
  lead_in_zero_ = lead == "zeros" ? sp.pre_mean : std::numeric_limits<double>::quiet_NaN();
  rise_jump_ = std::max(0.1 * std::abs(v0_), 8.0 * coast_sd_);
  level_min_ = std::numeric_limits<double>::infinity();
  rising_ = 0;
  state_ = State::coasting;
  emit_run_event(RunEvent::Kind::cut);
  // The coast's hold windows follow its own sample rate (a stream may change its rate between runs).
  set_spans(shortest_period(w));  // lost samples only lengthen periods: the shortest is the rate
  reset_window(hold_, run_.cut_index, i + 1);
  plateau_.start(run_.cut_index, run_.t_cut_s + 2.0 * hold_.span_s);  // once the hold window is clear of the first one
  hold_long_live_ = false;  // built when the coast gets low (saves work on the way down)
  creeping_ = false;
  coast_checks(i, store_.at(i));
  return true;
}

// ---- the contract, forwarded ---------------------------------------------------------------

RunDetector::RunDetector(RunOptions opt, std::string source)
    : impl_(std::make_unique<Impl>(std::move(opt), std::move(source))) {}
RunDetector::~RunDetector() = default;
RunDetector::RunDetector(RunDetector&&) noexcept = default;
RunDetector& RunDetector::operator=(RunDetector&&) noexcept = default;
void RunDetector::push(double t_s, double value) { impl_->push(t_s, value); }
void RunDetector::push_many(const double* t_s, const double* value, std::size_t n) { impl_->push_many(t_s, value, n); }
void RunDetector::clock_restart() { impl_->clock_restart(); }
void RunDetector::new_source(const std::string& why) { impl_->new_source(why); }
void RunDetector::finish() { impl_->finish(); }
void RunDetector::went_silent(double silent_s) { impl_->went_silent(silent_s); }
void RunDetector::joined_stream() { impl_->joined_stream(); }
void RunDetector::set_quantity(Quantity q) { impl_->set_quantity(q); }
std::vector<RunEvent> RunDetector::take_events() { return impl_->take_events(); }
bool RunDetector::has_events() const { return impl_->has_events(); }
RunDetector::State RunDetector::state() const { return impl_->state(); }
std::size_t RunDetector::samples_seen() const { return impl_->samples_seen(); }
std::size_t RunDetector::buffered() const { return impl_->buffered(); }

}  // namespace spindown
