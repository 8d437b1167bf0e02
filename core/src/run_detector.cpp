#include "spindown/run_detector.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <utility>

namespace spindown {

namespace {

// Seconds of lead-in searched for the cut before the window that confirmed the coast.
constexpr double back_search_s = 2.0;
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
constexpr double stop_min_end_rate = 0.6;
// In the tail, a hold-window mean this fraction of the amplitude below the zero level retracts
// the stop.
constexpr double retract_fraction = 0.02;
// Recompute sliding sums from scratch this often (rounding drift).
constexpr unsigned refresh_every = 4096;

std::string fmt_s(double t) { return fmt::format("{:.3f} s", t); }

}  // namespace

// ---- sliding least-squares line ----------------------------------------------------------

void RunDetector::WindowFit::clear(std::size_t at, double t_origin) {
  first = end = at;
  t0 = t_origin;
  n = st = stt = sv = svv = stv = 0;
  updates = 0;
}

void RunDetector::WindowFit::add(double t, double v) {
  t -= t0;
  n += 1;
  st += t;
  stt += t * t;
  sv += v;
  svv += v * v;
  stv += t * v;
  ++updates;
}

void RunDetector::WindowFit::remove(double t, double v) {
  t -= t0;
  n -= 1;
  st -= t;
  stt -= t * t;
  sv -= v;
  svv -= v * v;
  stv -= t * v;
  ++updates;
}

double RunDetector::WindowFit::slope() const {
  if (n < 2) return 0.0;
  const double sxx_ = sxx();
  if (!(sxx_ > 0)) return 0.0;
  return (stv - st * sv / n) / sxx_;
}

double RunDetector::WindowFit::resid_sd() const {
  if (n < 3) return 0.0;
  const double syy = svv - sv * sv / n;
  const double sxy = stv - st * sv / n;
  const double sxx_ = sxx();
  const double sse = sxx_ > 0 ? syy - sxy * sxy / sxx_ : syy;
  return std::sqrt(std::max(sse, 0.0) / (n - 2));
}

double RunDetector::duration(const WindowFit& w) const {
  return w.end > w.first ? t(w.end - 1) - t(w.first) : 0.0;
}

void RunDetector::rebuild(WindowFit& w, std::size_t from, std::size_t to) {
  w.clear(from, from < to ? t(from) : 0.0);
  for (std::size_t k = from; k < to; ++k) w.add(t(k), v(k));
  w.end = to;
  w.updates = 0;
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

void RunDetector::advance(WindowFit& w, std::size_t i) {
  if (w.end != i) {  // not contiguous (after a reset): start again from i
    w.clear(i, t(i));
  }
  if (w.n == 0) w.t0 = t(i);
  w.add(t(i), v(i));
  w.end = i + 1;
  while (w.end - w.first > 2 && t(i) - t(w.first) > w.span_s) {
    w.remove(t(w.first), v(w.first));
    ++w.first;
  }
  if (w.updates > refresh_every) rebuild(w, w.first, w.end);
}

// ---- detector ----------------------------------------------------------------------------

RunDetector::RunDetector(RunOptions opt, std::string source) : opt_(std::move(opt)), source_(std::move(source)) {
  hold_.span_s = opt_.stop_hold_s;
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

double RunDetector::median_of(std::size_t from, std::size_t to) {
  scratch_.clear();
  for (std::size_t k = from; k < to; ++k) scratch_.push_back(v(k));
  if (scratch_.empty()) return 0.0;
  auto mid = scratch_.begin() + scratch_.size() / 2;
  std::nth_element(scratch_.begin(), mid, scratch_.end());
  double m = *mid;
  if (scratch_.size() % 2 == 0) m = 0.5 * (m + *std::max_element(scratch_.begin(), mid));
  return m;
}

void RunDetector::push(double t_s, double value) {
  if (!std::isfinite(t_s) || !std::isfinite(value)) {
    ++non_finite_;  // reported by finish(); not a sample, so it takes no index
    return;
  }
  if (have_last_t_ && t_s < last_t_) {
    emit_diag(Diagnostic::Severity::note,
              fmt::format("time went back from {} to {} at sample {}: taken as a clock restart", fmt_s(last_t_),
                          fmt_s(t_s), next_index_));
    clock_restart();
  }
  have_last_t_ = true;
  last_t_ = t_s;
  const std::size_t i = next_index_++;
  bt_.push_back(t_s);
  bv_.push_back(value);
  // Track readings pinned at one positive value (a clipped converter) so the lead-in before
  // a long clip is still buffered when the coast leaves it.
  if (i == base_ || v(i) != v(i - 1)) same_start_ = i;
  if (value > 0 && i + 1 - same_start_ >= 5) {
    plateau_start_ = same_start_;
    plateau_end_ = i;
    have_plateau_ = true;
  }
  switch (state_) {
    case State::idle: idle_step(i); break;
    case State::coasting: coast_step(i); break;
    case State::tail: tail_step(i); break;
  }
}

void RunDetector::clock_restart() {
  if (state_ == State::coasting) close_unstopped(next_index_, "the device clock restarted mid-coast");
  else if (state_ == State::tail) complete_run(next_index_);
  bt_.clear();
  bv_.clear();
  base_ = next_index_;
  have_plateau_ = false;
  stream_start_ = next_index_;
  have_last_t_ = false;
  state_ = State::idle;
  lo_ = next_index_;
  need_quiet_ = false;
  short_.clear(next_index_, 0.0);
  long_.clear(next_index_, 0.0);
  hold_.clear(next_index_, 0.0);
}

void RunDetector::finish() {
  if (state_ == State::coasting) close_unstopped(next_index_, "the recording ends mid-coast (never reached standstill)");
  else if (state_ == State::tail) complete_run(next_index_);
  if (state_ != State::idle) to_idle(next_index_, false);
  if (non_finite_ > 0) {
    emit_diag(Diagnostic::Severity::warning,
              fmt::format("{} non-finite sample(s) (NaN/inf time or value) ignored", non_finite_));
    non_finite_ = 0;
  }
}

void RunDetector::to_idle(std::size_t lo, bool need_quiet) {
  state_ = State::idle;
  lo_ = lo;
  need_quiet_ = need_quiet;
  rising_ = departing_ = 0;
  reset_window(short_, lo, next_index_);
  reset_window(long_, lo, next_index_);
  trim_idle();
}

void RunDetector::trim_idle() {
  if (bt_.empty()) return;
  const double keep_s = long_.span_s + back_search_s + 0.5;
  const double t_now = bt_.back();
  std::size_t keep_from = std::max(lo_, base_);
  while (keep_from < next_index_ && t_now - t(keep_from) > keep_s) ++keep_from;
  // Keep enough samples for a slow loop's back-search, and what the windows still use.
  const std::size_t min_keep = back_search_min_samples + 16;
  if (next_index_ - keep_from < min_keep) keep_from = next_index_ > min_keep ? next_index_ - min_keep : 0;
  keep_from = std::max(keep_from, base_);
  keep_from = std::min({keep_from, short_.first, long_.first});
  if (have_plateau_ && plateau_end_ >= base_ && t_now - t(plateau_end_) <= keep_s)
    keep_from = std::min(keep_from, std::max(base_, plateau_start_ >= back_search_min_samples
                                                        ? plateau_start_ - back_search_min_samples
                                                        : std::size_t{0}));
  // Bounded memory whatever the timing.
  if (next_index_ - keep_from > opt_.max_buffer) keep_from = next_index_ - opt_.max_buffer;
  while (base_ < keep_from) {
    bt_.pop_front();
    bv_.pop_front();
    ++base_;
  }
  if (short_.first < base_) reset_window(short_, base_, next_index_);
  if (long_.first < base_) reset_window(long_, base_, next_index_);
}

bool RunDetector::confirms_decline(const WindowFit& w) const {
  if (w.n < 6 || w.first < lo_) return false;
  const double dur = duration(w);
  if (dur < 0.8 * w.span_s) return false;
  const double mu = w.mean();
  const double s = w.slope();
  if (!(mu > 0) || !(s < 0)) return false;
  const double sd = w.resid_sd();
  if (sd > confirm_max_roughness * mu) return false;
  if (-s * dur < 0.002 * mu) return false;
  return -s * std::sqrt(w.sxx()) >= confirm_t_stat * sd;
}

void RunDetector::idle_step(std::size_t i) {
  advance(short_, i);
  advance(long_, i);
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
  if (confirms_decline(short_)) start_coast(i, short_);
  else if (confirms_decline(long_)) start_coast(i, long_);
  else trim_idle();
}

void RunDetector::start_coast(std::size_t i, const WindowFit& w) {
  const std::size_t b = i;
  const std::size_t w0 = w.first;
  const std::size_t lower = std::max(lo_, base_);
  std::size_t a = w0;
  while (a > lower && t(w0) - t(a - 1) <= back_search_s) --a;
  if (w0 - a < back_search_min_samples) a = w0 - std::min(w0 - lower, back_search_min_samples);

  run_ = Run{};
  run_.number = accepted_ + 1;
  run_note_.clear();

  // A reading pinned at its maximum for 3+ samples and left without a step: ADC top.
  double m = v(a);
  for (std::size_t k = a; k <= b; ++k) m = std::max(m, v(k));
  std::size_t p = b + 1;  // last pinned sample
  for (std::size_t k = b; k >= a + 2 && k <= b; --k) {
    if (v(k) == m && v(k - 1) == m && v(k - 2) == m) {
      p = k;
      break;
    }
  }
  bool clipped = false;
  std::size_t q = 0;  // first pinned sample
  if (p < b) {
    q = p;
    while (q > lower && v(q - 1) == m) --q;
    // Longest stretch of equal readings in the coast after it: quantized data plateaus too,
    // a clipped reading is pinned much longer than that.
    std::size_t longest = 1, cur = 1;
    for (std::size_t k = p + 2; k <= b; ++k) {
      cur = v(k) == v(k - 1) ? cur + 1 : 1;
      longest = std::max(longest, cur);
    }
    const std::size_t pinned = p - q + 1;
    const double leave = m - v(p + 1);
    if (q > lower && pinned >= 5 && pinned >= 3 * longest && leave > 0 &&
        leave <= 0.02 * std::abs(m) + 3.0 * w.resid_sd())
      clipped = true;
    if (clipped) a = std::max(lower, std::min(a, q >= back_search_min_samples ? q - back_search_min_samples : 0));
  }

  std::size_t pre_end = 0;  // the lead-in is [a, pre_end)
  double v0 = 0, sd_post = 0;
  if (clipped) {
    run_.cut_index = p + 1;
    run_.t_cut_s = 0.5 * (t(q - 1) + t(q));
    pre_end = q;
    v0 = m;
    sd_post = w.resid_sd();
    RunEvent e;
    e.kind = RunEvent::Kind::diagnostic;
    e.has_diagnostic = true;
    e.diagnostic = {Diagnostic::Severity::warning, source_, 0,
                    fmt::format("run {}: reading pinned at {:g} (converter's top?) from {} to {} ({} samples): "
                                "the coast is taken from where it leaves it",
                                run_.number, m, fmt_s(t(q)), fmt_s(t(p)), p - q + 1)};
    events_.push_back(std::move(e));
  } else {
    // Two-segment least squares over [a, b]: constant lead-in [a, c), linear coast [c, b].
    const std::size_t n = b - a + 1;
    scratch_.assign(6 * (n + 1), 0.0);
    double* pv = scratch_.data();         // prefix Σv, Σv² of [a, a+k)
    double* pvv = pv + (n + 1);
    double* ss = pvv + (n + 1);           // suffix sums of [a+k, b]: n, Σt, Σt², Σv, Σv², Σtv
    double* stt_ = ss + (n + 1);
    double* sv_ = stt_ + (n + 1);
    double* stv_ = sv_ + (n + 1);
    for (std::size_t k = 0; k < n; ++k) {
      const double x = v(a + k);
      pv[k + 1] = pv[k] + x;
      pvv[k + 1] = pvv[k] + x * x;
    }
    const double tr = t(b);
    // suffix: Σt, Σt², Σv, Σtv; Σv² recovered from prefixes.
    for (std::size_t k = n; k-- > 0;) {
      const double tt = t(a + k) - tr, x = v(a + k);
      ss[k] = ss[k + 1] + tt;
      stt_[k] = stt_[k + 1] + tt * tt;
      sv_[k] = sv_[k + 1] + x;
      stv_[k] = stv_[k + 1] + tt * x;
    }
    const double svv_all = pvv[n];
    double best = std::numeric_limits<double>::infinity();
    // The confirming window may straddle a small step (supply → back-EMF), so the split may
    // fall anywhere that leaves a few samples for the line.
    std::size_t best_k = w0 - a;
    for (std::size_t k = 0; k + 3 <= n; ++k) {
      const double npre = double(k);
      const double sse_pre = k > 0 ? pvv[k] - pv[k] * pv[k] / npre : 0.0;
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
    const std::size_t k = best_k;
    const double np = double(n - k);
    const double sxx = stt_[k] - ss[k] * ss[k] / np;
    const double sxy = stv_[k] - ss[k] * sv_[k] / np;
    const double syy = (svv_all - pvv[k]) - sv_[k] * sv_[k] / np;
    const double beta = sxx > 0 ? sxy / sxx : 0.0;
    const double tbar = ss[k] / np, vbar = sv_[k] / np;
    const std::size_t c = a + k;
    v0 = vbar + beta * ((t(c) - tr) - tbar);
    sd_post = np > 2 ? std::sqrt(std::max(syy - beta * sxy, 0.0) / (np - 2)) : 0.0;
    run_.cut_index = c;
    pre_end = c;
    const bool sample_before = c > base_ && c > stream_start_ && c - 1 >= lo_;
    run_.t_cut_s = sample_before ? 0.5 * (t(c - 1) + t(c)) : t(c);
  }

  // What the reading did before the cut.
  const std::size_t npre = pre_end - a;
  if (npre < 3) {
    run_.lead_in = "none";
  } else {
    double mu = 0;
    for (std::size_t k = a; k < pre_end; ++k) mu += v(k);
    mu /= double(npre);
    double var = 0;
    for (std::size_t k = a; k < pre_end; ++k) var += (v(k) - mu) * (v(k) - mu);
    const double sd_pre = std::sqrt(var / double(npre));
    const double scale = std::abs(v0);
    const double step = v0 - mu;
    if (std::abs(step) <= std::max(5.0 * sd_post, 0.03 * scale)) run_.lead_in = "powered";
    else if (step < 0) run_.lead_in = "supply";
    else if (sd_pre > std::max(0.02 * scale, 3.0 * sd_post)) run_.lead_in = "floating";
    else if (std::abs(mu) <= 0.1 * scale) run_.lead_in = "zeros";
    else run_.lead_in = "floating";
  }

  v0_ = v0;
  coast_sd_ = sd_post;
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
  coast_checks(i);
}

void RunDetector::coast_step(std::size_t i) {
  advance(hold_, i);
  coast_checks(i);
}

void RunDetector::coast_checks(std::size_t i) {
  if (bt_.size() > opt_.max_buffer) {
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
  if (t(i) - run_.t_cut_s > opt_.max_coast_s) {
    close_unstopped(i + 1, fmt::format("no standstill within max_coast_s ({:g} s): closed as never stopped",
                                       opt_.max_coast_s));
    to_idle(i + 1, true);
    return;
  }
  if (hold_.n < 3 || hold_.first < run_.cut_index) return;
  const double dur = duration(hold_);
  const double mu = hold_.mean();
  const double sd = hold_.resid_sd();

  // Power back before standstill: the reading climbs well above the coast's lowest level.
  if (dur >= 0.5 * hold_.span_s) level_min_ = std::min(level_min_, mu);
  const double jump = std::max(0.1 * std::abs(v0_), 8.0 * coast_sd_);
  if (v(i) > level_min_ + jump) {
    if (rising_++ == 0) rise_start_ = i;
    if (rising_ >= 3) {
      const std::size_t at = rise_start_;
      close_unstopped(at, fmt::format("the reading rose again at {} before standstill (power restored?)", fmt_s(t(at))));
      to_idle(at, false);
      return;
    }
  } else {
    rising_ = 0;
  }

  if (dur < 0.9 * hold_.span_s) return;
  const double s = hold_.slope();
  const double scale = std::max(std::abs(v0_), std::abs(mu));
  const double tiny = 1e-12 * (scale > 0 ? scale : 1.0);
  const bool no_slope = std::abs(s) * std::sqrt(hold_.sxx()) <= flat_t_stat * sd + tiny;
  const bool small_drop = std::abs(s) * dur <= std::max(3.0 * sd, 0.01 * std::abs(v0_)) + tiny;
  const bool low = v0_ > 0 ? mu <= standstill_max_fraction * v0_ : true;
  if (no_slope && small_drop && low) found_standstill(i);
}

void RunDetector::found_standstill(std::size_t i) {
  const std::size_t h0 = hold_.first;
  const double z = median_of(h0, i + 1);
  double var = 0;
  for (std::size_t k = h0; k <= i; ++k) var += (v(k) - z) * (v(k) - z);
  const double sd_z = std::sqrt(var / double(i + 1 - h0));
  const double amp = v0_ - z;
  const double band = std::max(3.0 * sd_z, 1e-9 * std::max(std::abs(amp), 1e-300));

  // First sample of the standstill run that contains the hold window.
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
        const double tb = f.st / f.n, vb = f.mean();
        const double th = f.t0 + tb + (z - vb) / sl;
        if (std::isfinite(th)) t_hit = std::clamp(th, t_quarter, t(i));
      }
    }
  }
  std::size_t stop = run_.cut_index + 1;
  while (stop < i && t(stop) < t_hit) ++stop;

  // A real stop arrives with a finite slope; an exponential creeps in.
  const double t_stop = t(stop);
  const double coast = t_stop - run_.t_cut_s;
  const double last_quarter = t_stop - t_quarter;
  const double end_rate = last_quarter > 0 ? 0.25 * coast / last_quarter : std::numeric_limits<double>::infinity();

  run_.zero_level = z;
  run_.noise_level = sd_z;
  if (end_rate >= stop_min_end_rate || amp <= 0) {
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
  } else {
    run_note_ = fmt::format(
        "run cut at {}: the coast approaches its floor ({:g}) asymptotically (last quarter {:.2f}x slower than "
        "the mean rate), as pure viscous friction does: treated as never stopped, coast closed at {}",
        fmt_s(run_.t_cut_s), z, end_rate > 0 ? 1.0 / end_rate : 0.0, fmt_s(t(i)));
    run_.stopped = false;
    complete_run(i + 1);
    to_idle(i + 1, true);
  }
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

void RunDetector::tail_step(std::size_t i) {
  if (bt_.size() > opt_.max_buffer) {
    complete_run(i);
    to_idle(i, false);
    return;
  }
  // Still falling: the "standstill" was a noisy stretch of a slow coast. Retract the stop and
  // keep coasting (the stop event was provisional; only complete runs are final).
  advance(hold_, i);
  if (hold_.n >= 3 && hold_.first >= run_.stop_index) {
    const double drop = run_.zero_level - hold_.mean();
    if (drop > std::max(4.0 * run_.noise_level / std::sqrt(hold_.n), retract_fraction * (v0_ - run_.zero_level))) {
      emit_diag(Diagnostic::Severity::note,
                fmt::format("run cut at {}: standstill at {} retracted, the reading kept falling", fmt_s(run_.t_cut_s),
                            fmt_s(run_.t_stop_s)));
      run_.stopped = false;
      run_.t_stop_s = std::numeric_limits<double>::quiet_NaN();
      state_ = State::coasting;
      level_min_ = std::numeric_limits<double>::infinity();
      rising_ = 0;
      coast_checks(i);
      return;
    }
  }
  // A new spin-up (the next run's lead-in) ends the tail.
  if (v(i) - run_.zero_level > depart_band_) {
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
  if (t(i) >= run_.t_stop_s + opt_.tail_s) {
    const std::size_t end = departing_ > 0 ? depart_start_ : i;
    complete_run(end);
    to_idle(end, false);
  }
}

void RunDetector::close_unstopped(std::size_t end, const std::string& why) {
  run_.stopped = false;
  run_.zero_level = 0;
  run_.noise_level = coast_sd_;
  run_note_ = fmt::format("run cut at {}: {}", fmt_s(run_.t_cut_s), why);
  complete_run(end);
}

void RunDetector::complete_run(std::size_t end) {
  Run r = run_;
  end = std::max(end, r.cut_index);
  r.end_index = end;
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
  // Median sample period within the coast.
  scratch_.clear();
  for (std::size_t k = r.cut_index + 1; k < coast_end; ++k) scratch_.push_back(t(k) - t(k - 1));
  if (!scratch_.empty()) {
    auto mid = scratch_.begin() + scratch_.size() / 2;
    std::nth_element(scratch_.begin(), mid, scratch_.end());
    r.period_s = *mid;
  }
  const std::size_t coast_n = coast_end - r.cut_index;
  const double coast_s = (r.stopped ? r.t_stop_s : (end > r.cut_index ? t(end - 1) : r.t_cut_s)) - r.t_cut_s;

  RunEvent e;
  e.run = r;
  if (coast_s < opt_.min_coast_s || coast_n < opt_.min_samples) {
    e.kind = RunEvent::Kind::ignored;
    e.has_diagnostic = true;
    e.diagnostic = {Diagnostic::Severity::note, source_, 0,
                    fmt::format("coast cut at {} ignored: {} and {} samples (need {:g} s and {})", fmt_s(r.t_cut_s),
                                fmt_s(coast_s), coast_n, opt_.min_coast_s, opt_.min_samples)};
  } else {
    e.kind = RunEvent::Kind::complete;
    e.run.number = ++accepted_;
    if (!run_note_.empty()) {
      e.has_diagnostic = true;
      e.diagnostic = {Diagnostic::Severity::note, source_, 0, fmt::format("run {}: {}", e.run.number, run_note_)};
    }
  }
  events_.push_back(std::move(e));
  run_note_.clear();
}

}  // namespace spindown
