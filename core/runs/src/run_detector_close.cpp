// Closing a run: its scan (gaps, held values), the warnings a student sees, the run itself.
#include "run_detector_impl.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#include <fmt/format.h>
#include <string>

#include "run_detector_tuning.hpp"

namespace spindown {

using namespace detector_tuning;

// A long silence inside a fitted coast. Samples lost while the motor coasted on leave the
// reading lower after the gap by about the coast's slope times the gap, and the fit is right to
// take the times as given (a note). A device clock that jumped while the readings went on
// leaves the reading where it was: the fit's times are then wrong by the jump, and so is its
// friction (a warning). Said once per run, for the longest gap.
void RunDetector::Impl::warn_of_gap_in_coast(int number, std::size_t from, std::size_t at, double longest, double period_s) {
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

void RunDetector::Impl::scan_coast(Run& r, std::size_t coast_end) {
  // One pass over the coast for its longest silence and its outliers. An outlier is a single
  // sample far off its two neighbours' midpoint, which agree with each other (|b - a| well
  // below the offset, so the time interpolation differs little from the midpoint): a dropout
  // (a loose wire reads 0) or a glitch (a missed pulse halves a speed), not the motor, which
  // cannot leave its course for one sample and come back.
  std::size_t gap_at = 0;
  double longest = 0;
  const double said = std::max(1.0, 25.0 * r.period_s);  // a shorter silence is not said: not looked for
  const double floor = std::max(10.0 * coast_sd_, 5.0 * coast_step_);
  const Sample* ring = store_.data();
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
  const std::size_t before = r.outliers.size();  // the coast's bounce at its start, already out
  std::size_t k = before ? r.outliers.back() + 2 : r.cut_index + 1;
  while (k + 1 < coast_end) {
    const std::size_t at = (k - 1) & store_.mask();
    const std::size_t n = std::min(coast_end - 1 - k, store_.capacity() - 2 - std::min(at, store_.capacity() - 2));
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
  if (r.outliers.size() == before) return;
  emit_diag(Diagnostic::Severity::warning,
            fmt::format("run {}: {} single-sample outlier(s) left out of the fit (dropouts or glitches): {}{}", r.number,
                        r.outliers.size() - before, where, shown > 10 ? ", …" : ""));
}

std::string RunDetector::Impl::gap_before(std::size_t i) const {
  return fmt::format("no samples for {:.3g} s mid-coast (from {} to {})", t(i) - t(i - 1), fmt_s(t(i - 1)),
                     fmt_s(t(i)));
}

std::string RunDetector::Impl::fragment_reason(const Run& r, double amp, double coast_s) const {
  // How far the reading fell in this coast, against what the reading can resolve and against the
  // runs already found in this stream (a nudge, a few samples at a crawl, a piece of a coast).
  if (amp <= 0)
    return fmt::format("the reading does not fall: it ends {:.3g} higher than it began", -amp);
  if (amp < 3.0 * coast_step_)
    return fmt::format("it falls {:.3g}, under 3 of the reading's steps ({:.2g})", amp, coast_step_);
  // Beside the runs before it, only a coast seen to stop is judged: one cut short (end of data, a
  // gap) may have fallen little so far for reasons that are no fault of its own.
  if (accepted_ == 0 || !r.stopped) return {};
  return small_beside(amp, coast_s, largest_amp_, longest_coast_s_);
}

std::string RunDetector::Impl::small_beside(double amp, double coast_s, double largest_amp, double longest_s) {
  if (amp < 0.03 * largest_amp)
    return fmt::format("it falls {:.3g}, under 3 % of the largest run's {:.3g}", amp, largest_amp);
  if (coast_s < 0.25 * longest_s && amp < 0.1 * largest_amp)
    return fmt::format("{:.3g} s and a fall of {:.3g}, beside runs of up to {:.3g} s and {:.3g}", coast_s, amp,
                       longest_s, largest_amp);
  return {};
}

bool RunDetector::Impl::held_last_value(std::size_t cut, std::size_t end, std::size_t& held_from, std::size_t& longest,
                                  bool need_long) const {
  // The last value read up to end, held exactly, well above the motor's zero, reached by a jump of
  // several of the reading's steps (an rpm counter's last update, not the one step a coarse reading
  // takes onto a real offset), and (need_long) held five times longer than any value before it.
  const double z = v(end - 1);
  held_from = end - 1;
  while (held_from > cut && v(held_from - 1) == z) --held_from;
  const std::size_t held = end - held_from;
  longest = 1;
  if (held < 10 || held_from < cut + 10) return false;
  const double zero = motor_zero();
  if (!(z - zero > std::max(0.02 * (v0_ - zero), 3.0 * coast_step_))) return false;
  std::size_t from = held_from, cur = 1;
  while (from > cut && t(held_from) - t(from - 1) <= 2.0) --from;
  for (std::size_t k = from + 1; k < held_from; ++k) {
    cur = v(k) == v(k - 1) ? cur + 1 : 1;
    longest = std::max(longest, cur);
  }
  if ((need_long && held < 5 * longest) || held_from < from + 3) return false;
  // The reading's resolution over the coast (the smallest gap between the values it took; a
  // per-revolution reading's values lie far apart near the end, close together at speed): a level
  // of a step or two above zero is a coarse reading's offset, not a frozen one.
  constexpr std::size_t look = 5000;
  std::vector<double> x;
  for (std::size_t k = held_from > cut + look ? held_from - look : cut; k < held_from; ++k) x.push_back(v(k));
  std::sort(x.begin(), x.end());
  double resolution = std::numeric_limits<double>::infinity();
  for (std::size_t k = 1; k < x.size(); ++k)
    if (x[k] > x[k - 1]) resolution = std::min(resolution, x[k] - x[k - 1]);
  // Reached by a jump (a per-revolution counter's last update), not the one step a coarse reading
  // takes onto a real offset.
  return z - zero > 3.0 * resolution && v(held_from - 1) - z > 2.0 * resolution;
}

void RunDetector::Impl::warn_of_held_standstill(const Run& r) {
  // A standstill that reads one value exactly, well above the motor's zero, held far longer than
  // any value of the coast before it: what a sensor that keeps its last reading shows (an rpm
  // counter whose pulses stopped). A real offset is reached a reading step at a time, and a
  // sensor's freeze cannot be told from a stop for sure: said, not decided.
  if (r.end_index < r.stop_index + 10 || r.stop_index < r.cut_index + 10) return;
  std::size_t held_from = 0, longest = 1;
  if (!held_last_value(r.cut_index, r.end_index, held_from, longest, true)) return;
  // … reached by a jump of many of the coast's steps (said only then: a coarse reading's last
  // steps onto a value held at rest are no sign of a frozen sensor).
  if (!(v(held_from - 1) - v(r.end_index - 1) > 10.0 * coast_step_)) return;
  const std::size_t held = r.end_index - held_from;
  if (5 * held < 4 * (r.end_index - r.stop_index)) return;  // most of the standstill
  const double z = v(r.end_index - 1), zero = motor_zero();
  emit_diag(Diagnostic::Severity::warning,
            fmt::format("run {}: the standstill reads exactly {:g} for its last {} samples, {:.1f} % of the reading at "
                        "the cut, where no value of the coast before it lasted more than {}: a sensor holding its "
                        "last value? If the motor went on to 0, the zero level and the fits are wrong",
                        r.number, z, held, 100.0 * (z - zero) / (v0_ - zero), longest));
}

void RunDetector::Impl::warn_of_earlier_fragments(const Run& r, double amp, double coast_s) {
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

void RunDetector::Impl::complete_run(std::size_t end) {
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
  recut_coast(r, end);  // why a cut moved: run_detector_recut.cpp
  const std::size_t coast_end = r.stopped ? r.stop_index : end;
  if (coast_end > r.cut_index + 1) r.period_s = median_period(r.cut_index, coast_end);
  const std::size_t coast_n = coast_end - r.cut_index;
  const double coast_s = (r.stopped ? r.t_stop_s : (end > r.cut_index ? t(end - 1) : r.t_cut_s)) - r.t_cut_s;

  // How far the reading fell: to the standstill, or to the coast's last sample.
  const double amp = v0_ - (r.stopped || coast_n == 0 ? r.zero_level : v(coast_end - 1));

  RunEvent e;
  e.run = r;
  if (!not_coast_.empty()) {
    e.kind = RunEvent::Kind::ignored;
    e.has_diagnostic = true;
    e.diagnostic = {Diagnostic::Severity::warning, source_, 0,
                    fmt::format("decline from {} to {} ignored: {}", fmt_s(r.t_cut_s), fmt_s(r.t_end_s), not_coast_)};
    not_coast_.clear();
  } else if (fragment_) {
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
    if (!bounce_.empty()) {
      e.run.outliers = bounce_;
      emit_diag(Diagnostic::Severity::note,
                fmt::format("run {}: {} sample(s) of contact bounce at the coast's start left out of the fit (from {})",
                            e.run.number, bounce_.size(), fmt_s(t(bounce_.front()))));
    }
    if (std::isfinite(pin_level_)) {
      for (std::size_t k = r.cut_index; k < coast_end; ++k)
        if (v(k) == pin_level_) e.run.outliers.push_back(k);
      std::sort(e.run.outliers.begin(), e.run.outliers.end());
      e.run.outliers.erase(std::unique(e.run.outliers.begin(), e.run.outliers.end()), e.run.outliers.end());
    }
    scan_coast(e.run, coast_end);
    if (!run_note_.empty()) {
      e.has_diagnostic = true;
      e.diagnostic = {run_note_severity_, source_, 0, fmt::format("run {}: {}", e.run.number, run_note_)};
    }
  }
  events_.push_back(std::move(e));
  run_note_.clear();
  run_note_severity_ = Diagnostic::Severity::note;
  bounce_.clear();
  pin_level_ = std::numeric_limits<double>::quiet_NaN();
}

}  // namespace spindown
