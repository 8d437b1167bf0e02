// Finding a coast's cut: where the lead-in ends and the decline starts, and what came before it.
#include "run_detector_impl.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fmt/format.h>
#include <limits>
#include <string>
#include <vector>

#include "run_detector_tuning.hpp"
#include "spindown/lead_in.hpp"
#include "spindown/two_segment_split.hpp"

namespace spindown {

using namespace detector_tuning;

namespace {

constexpr double z_one_in_1000 = -3.090232306167813;  // the standard normal's 0.1 % quantile

}  // namespace

RunDetector::Impl::CutSplit RunDetector::Impl::split_at_cut(std::size_t a, std::size_t b, const WindowFit& w) {
  CutSplit sp;
  sp.a = a;
  if (!split_at_top(sp, a, b, w)) split_two_segments(sp, a, b, w);
  describe_lead_in(store_, sp);
  return sp;
}

bool RunDetector::Impl::split_at_top(CutSplit& sp, std::size_t a, std::size_t b, const WindowFit& w) {
  // A reading pinned at its maximum and left without a step: the converter's top.
  const std::size_t lower = std::max(search_lo_, store_.base());
  double m = v(a);
  for (std::size_t k = a; k <= b; ++k) m = std::max(m, v(k));
  std::size_t p = b + 1;  // last pinned sample
  for (std::size_t k = b; k >= a + 2 && k <= b; --k) {
    if (v(k) == m && v(k - 1) == m && v(k - 2) == m) {
      p = k;
      break;
    }
  }
  if (p >= b) return false;
  std::size_t q = p;  // first pinned sample
  while (q > lower && v(q - 1) == m) --q;
  // Quantized data plateaus too; a clipped reading is pinned much longer than the longest
  // plateau of the coast after it.
  const std::size_t longest = longest_hold(store_, p + 1, b);
  const std::size_t pinned = p - q + 1;
  const double leave = m - v(p + 1);
  // … and much longer than one step of the reading lasts at the coast's start: a heavy
  // flywheel's coast holds its first printed value for a second, unclipped.
  const double slope = w.slope(), step = std::max(reading_step(store_, p + 1, b + 1), leave);
  const double period = b > p + 1 ? (t(b) - t(p + 1)) / double(b - p - 1) : 0.0;
  const double step_lasts = slope < 0 && period > 0 && step > 0 ? step / -slope / period : 0.0;
  if (!(q > lower && pinned >= 5 && pinned >= 3 * longest && pinned >= 3.0 * step_lasts && leave > 0 &&
        leave <= 0.02 * std::abs(m) + 3.0 * w.resid_sd()))
    return false;
  // … and comes down from it as a coast does, never by a step within the next ten readings (a
  // supply read within the converter's range, flickering with the value below it, then the step
  // to the back-EMF at the cut: that step is the cut, as split_two_segments finds it).
  double drop = 0;
  for (std::size_t k = p + 1; k <= std::min(b, p + 10); ++k) drop = std::max(drop, v(k - 1) - v(k));
  if (drop > 4.0 * std::max(leave, step) && drop > 6.0 * w.resid_sd()) return false;
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
  return true;
}

bool RunDetector::Impl::pinned_lead_in(CutSplit& sp, std::size_t b) {
  // A powered lead-in held at the highest value of the search, exactly, for 9 in 10 of its readings,
  // without a break from where it reached it, and three times longer than any value of the coast
  // after it: a supply above the converter's range (A0 on the motor's terminal). The power-off is
  // hidden under it; the coast is taken from the first reading below the top after the last such
  // hold (a ripple may bring it back to the top for a few readings as it comes down).
  if (sp.npre < min_lead_samples || sp.pre_end > b) return false;
  double m = v(sp.a);
  for (std::size_t k = sp.a; k <= b; ++k) m = std::max(m, v(k));
  std::size_t at_top = 0;
  for (std::size_t k = sp.a; k < sp.pre_end; ++k) at_top += v(k) == m;
  if (10 * at_top < 9 * sp.npre) return false;
  const std::size_t hold = 3 * longest_hold(store_, sp.pre_end, b, m);
  std::size_t first = sp.a, run = 0;  // first: the first reading below the top after a hold
  for (std::size_t k = sp.a; k <= b; ++k) {
    if (v(k) == m) {
      ++run;
    } else {
      if (run >= hold) first = k;
      run = 0;
    }
  }
  if (first <= sp.a || first > b) return false;
  // A converter's top is a ceiling the reading never falls below while the signal is above it: from
  // the first reading at the top to the one that leaves it, every reading is exactly the top. A
  // supply read within the converter's range flickers with the value below it (its noise) all along.
  std::size_t q = sp.a;
  while (q < first && v(q) != m) ++q;
  for (std::size_t k = q; k < first; ++k)
    if (v(k) != m) return false;
  if (first < q + std::max<std::size_t>(hold, 8)) return false;
  sp.cut_index = sp.pre_end = first;
  sp.npre = first - sp.a;
  sp.t_cut_s = 0.5 * (t(first - 1) + t(first));
  pin_level_ = m;
  return true;
}

void RunDetector::Impl::find_pinned_start(std::size_t b) {
  // A coast that starts above the converter's top reads its top until it comes down through it:
  // mostly the same highest value (a ripple flickers it with values below as it comes down), held
  // far longer than any value of the coast after it and than one step of the reading lasts there.
  // Each reading at that top is a bound, not the motor's value: all are left out of the fit.
  const std::size_t c = run_.cut_index;
  if (b < c + 16) return;
  double m = v(c);
  for (std::size_t k = c; k <= b; ++k) m = std::max(m, v(k));
  std::size_t end = c, at_top = 0;  // [c, end): from the cut to the last reading at the top
  for (std::size_t k = c; k <= b; ++k)
    if (v(k) == m) end = k + 1, ++at_top;
  if (end > b || at_top < 5 || 2 * at_top < end - c || v(c) < m - 0.5 * (m - v(end))) return;
  const std::size_t longest = longest_hold(store_, end, b);
  const WindowFit after = window_over(store_.data(), store_.mask(), 1e300, end, b + 1);
  const double slope = after.slope(), step = reading_step(store_, c, b + 1);
  const double period = b > end ? (t(b) - t(end)) / double(b - end) : 0.0;
  const double step_lasts = slope < 0 && period > 0 && step > 0 ? step / -slope / period : 0.0;
  if (!(slope < 0) || at_top < 3 * longest || double(at_top) < 3.0 * step_lasts) return;
  pin_level_ = m;
  emit_diag(Diagnostic::Severity::warning,
            fmt::format("run {}: the reading sat at its highest value, {:g}, from {} to {} ({} readings at it), far "
                        "longer than the coast after it holds any value: the converter's top (a back-EMF above its "
                        "range) or a stuck reading, not the motor's value. Those readings are left out of the fit, "
                        "which takes the coast from the values below it; the cut stays at {}",
                        run_.number, m, fmt_s(t(c)), fmt_s(t(end - 1)), at_top, fmt_s(run_.t_cut_s)));
}

void RunDetector::Impl::split_two_segments(CutSplit& sp, std::size_t a, std::size_t b, const WindowFit& w) {
  const TwoSegmentSplit sums(store_, a, b, split_scratch_);
  std::size_t kb = 0;
  std::size_t k = sums.later_step(kb, sums.best_split(0));
  // A rough lead-in (an open pin's hum) fits the coast's line about as badly as a constant, so
  // the split may give the coast some of it. The coast itself is smooth, as the window that
  // confirmed it shows: its first sample is the earliest from which the readings keep to that
  // window's line, drawn back.
  if (const double e = w.resid_sd();
      w.n >= 6 && w.first >= a + k + 4 && sums.post_line(k).sd > 2.0 * e + 1e-12 &&
      rough_sd(store_, a + k, w.first) > 3.0 * std::max(rough_sd(store_, w.first, b + 1), 0.5 * e) &&
      rough_sd(store_, a, a + k) > 3.0 * std::max(rough_sd(store_, w.first, b + 1), 0.5 * e)) {
    const double tol = std::max(4.0 * e, 2.0 * reading_step(store_, w.first, b + 1));
    const double slope = w.slope(), t_mid = w.t0 + w.st() / w.n, mid = w.mean();
    std::size_t j = w.first;
    while (j > a + k && std::abs(v(j - 1) - (mid + slope * (t(j - 1) - t_mid))) <= tol) --j;
    k = j - a;
  }
  const TwoSegmentSplit::Line l = sums.post_line(k);
  const std::size_t c = a + k;
  sp.a = a + kb;
  sp.v0 = l.v0;
  sp.post_slope = l.slope;
  sp.sd_post = l.sd;
  sp.post_rough = rough_sd(store_, c, b + 1);
  sp.cut_index = c;
  sp.pre_end = c;
  const bool sample_before = c > store_.base() && c > stream_start_ && c - 1 >= search_lo_;
  sp.t_cut_s = sample_before ? 0.5 * (t(c - 1) + t(c)) : t(c);
}


void RunDetector::Impl::take_bounce(CutSplit& sp, const WindowFit& w) {
  // Up to three samples around the coast's first that lie neither on the coast's course (a line
  // through the samples that follow them) nor on the lead-in's course before them: a contact
  // bouncing as a wire is pushed in (the handout's step 6 connects the pin to the motor by hand).
  // The coast starts at the first of them; they are left out of the fit as outliers.
  constexpr std::size_t most = 3, local = 8;
  const std::size_t c = sp.cut_index, lower = std::max({search_lo_, store_.base(), sp.a});
  if (sp.clipped || w.end < c + most + local + 1 || c < lower + local + 1) return;
  const double step = reading_step(store_, c, std::min(w.end, c + 4 * local));
  // The course of [from, from + local) at sample j, and how far from it a sample is off it.
  const auto course = [&](std::size_t from, std::size_t j, double& off) {
    const WindowFit f = window_over(store_.data(), store_.mask(), 1e300, from, from + local);
    const double at = f.mean() + f.slope() * (t(j) - f.t0 - f.st() / f.n);
    off = std::max({5.0 * f.resid_sd(), 0.03 * std::abs(at), 2.0 * step});
    return at;
  };
  // After the cut found: samples off the course of the coast beyond the reach of any bounce.
  std::size_t settled = c;
  double off = 0;
  while (settled < c + most && std::abs(v(settled) - course(c + most, settled, off)) > off) ++settled;
  // Before it: samples off the coast's course (drawn back from where it settled) and off the
  // lead-in's own course (a line through the samples before them: a rise into the cut goes on).
  std::size_t first = c;
  for (std::size_t m = 1; m + (settled - c) <= most && c >= lower + local + m; ++m) {
    const std::size_t j = c - m;
    double off_coast = 0, off_lead = 0;
    if (std::abs(v(j) - course(c + most, j, off_coast)) <= off_coast) break;  // the coast already
    if (std::abs(v(j) - course(j - local, j, off_lead)) <= std::max(off_lead, off_coast)) break;  // the lead-in
    // … or within the lead-in's own recent swing (an open pin's hum turns up and down).
    double lead_lo = v(j - 1), lead_hi = v(j - 1);
    for (std::size_t k = j - local; k < j; ++k) lead_lo = std::min(lead_lo, v(k)), lead_hi = std::max(lead_hi, v(k));
    if (v(j) >= lead_lo - off_lead && v(j) <= lead_hi + off_lead) break;
    first = j;
  }
  if (first == c && settled == c) return;
  for (std::size_t k = first; k < settled; ++k) bounce_.push_back(k);
  if (first == c) return;  // the cut stays where the lead-in ended; its first samples bounced
  sp.cut_index = first;
  sp.pre_end = first;
  sp.npre = first > sp.a ? first - sp.a : 0;
  sp.t_cut_s = first > store_.base() && first > stream_start_ ? 0.5 * (t(first - 1) + t(first)) : t(first);
}

void RunDetector::Impl::refine_plateau_cut(CutSplit& sp, std::size_t b) {
  // Up to 50 samples of the plateau and of the coast on either side of the split (the coast's
  // curve is a line that near its start), then y = level + slope·max(0, t − tc) by least squares
  // for each tc on a grid of a tenth of a period over ±4 samples of the split.
  constexpr std::size_t side = 50, reach = 4;
  const std::size_t c = sp.cut_index;
  const std::size_t lo = std::max(sp.a, c >= side ? c - side : 0), hi = std::min(b + 1, c + side);
  if (c < lo + 8 || hi < c + 8 || c < lo + reach + 1 || hi < c + reach + 1) return;
  // The plateau must meet the coast without a step: at the split, within 4 of the coast's noise.
  if (!(std::abs(sp.pre_mean - sp.v0) <= 4.0 * std::max(sp.sd_post, sp.pre_sd))) return;
  const double period = (t(hi - 1) - t(lo)) / double(hi - 1 - lo);
  if (!(period > 0)) return;
  const double from = t(c - reach), to = t(c + reach);
  double best_sse = std::numeric_limits<double>::infinity(), best_tc = sp.t_cut_s;
  for (double tc = from; tc <= to; tc += 0.1 * period) {
    double sx = 0, sy = 0, sxx = 0, sxy = 0, syy = 0;
    for (std::size_t k = lo; k < hi; ++k) {
      const double x = std::max(0.0, t(k) - tc), y = v(k);
      sx += x, sy += y, sxx += x * x, sxy += x * y, syy += y * y;
    }
    const double n = double(hi - lo);
    const double vxx = sxx - sx * sx / n, vxy = sxy - sx * sy / n, vyy = syy - sy * sy / n;
    if (!(vxx > 0)) continue;
    const double slope = vxy / vxx;
    const double sse = vyy - slope * vxy;
    if (slope < 0 && sse < best_sse) best_sse = sse, best_tc = tc;
  }
  if (!std::isfinite(best_sse)) return;
  std::size_t first = c - reach;
  while (first < c + reach && t(first) < best_tc) ++first;
  sp.t_cut_s = best_tc;
  sp.cut_index = sp.pre_end = first;
  sp.npre = first > sp.a ? first - sp.a : 0;
}

std::size_t RunDetector::Impl::level_end(std::size_t r, std::size_t p, std::size_t b) {
  // [r, b] split into a level and the coast's line by least squares (the coast's start is close to
  // a line), the level reaching from r past the peak p …
  const TwoSegmentSplit sums(store_, r, b, split_scratch_);
  const std::size_t c = r + sums.best_split(0);
  if (c < p + 8) return p;
  // … taken when the coast after the split is a second or more long (a kink with no step rests
  // on the slope alone, and a ripple's swing down over a few tenths of a second fakes one) and
  // falls by 4 standard errors of its slope, and the readings from the peak to the split are
  // shown to be flat beside it (at a third of its slope, within two standard errors), as a
  // powered lead-in is.
  const WindowFit coast = window_over(store_.data(), store_.mask(), 1e300, c, b + 1);
  const double slope = coast.slope();
  if (coast.n < 6 || t(b) - t(c) < 1.0 || !(-slope > 4.0 * coast.slope_se())) return p;
  const WindowFit held = window_over(store_.data(), store_.mask(), 1e300, p, c);
  return std::abs(held.slope()) + 2.0 * held.slope_se() <= 0.3 * -slope ? c : p;
}

bool RunDetector::Impl::at_peak(CutSplit& sp, std::size_t b, bool rising_lead) {
  if (sp.clipped || b < sp.cut_index + 3) return false;
  // A rise is judged against the coast line's scatter; after a lead-in known to rise into the cut
  // (a recording that begins in a spin-up), against the sample-to-sample noise when smaller: a
  // line drawn through the rest of the rise and the fall after it scatters by the rise itself.
  const double noise = rising_lead && sp.post_rough > 0 ? std::min(sp.sd_post, sp.post_rough) : sp.sd_post;
  const double thr = std::max(4.0 * noise, 0.02 * std::abs(sp.v0));
  // The highest reading (a 3-sample mean, so one noisy sample does not make the peak) from the
  // cut found to the newest sample.
  std::size_t p = sp.cut_index;
  double top3 = 3.0 * smoothed(store_, p, sp.cut_index, b);  // three times the mean: sums compared, no division
  for (std::size_t k = sp.cut_index + 1; k < b; ++k) {
    const double m3 = v(k - 1) + v(k) + v(k + 1);
    if (m3 > top3) top3 = m3, p = k;
  }
  const double top = top3 / 3.0;
  if (top > smoothed(store_, sp.cut_index, sp.cut_index, b) + thr && p < b) {
    // A rise after the cut found: the coast starts where the level it rose to ends, and what came
    // before is the rise. That level's highest 3-sample mean is only where its noise peaked (a
    // per-pulse sensor's reading alternates between neighbouring periods for seconds): from where
    // the rise reached the level (its median reading from the peak on; a coast straight from the
    // peak puts that mid-coast, and no level is found), level_end splits it from the coast.
    bool level = false;
    if (b >= p + 16) {
      std::vector<double> after;
      after.reserve(b - p + 1);
      for (std::size_t k = p; k <= b; ++k) after.push_back(v(k));
      std::nth_element(after.begin(), after.begin() + std::ptrdiff_t(after.size() / 2), after.end());
      const double mid = after[after.size() / 2];
      std::size_t r = sp.cut_index;
      while (r < p && smoothed(store_, r, sp.cut_index, b) < mid) ++r;
      const std::size_t e = level_end(r, p, b);
      level = e > p;
      p = e;
    }
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
    if (level) sp.v0 = coast.mean() + sp.post_slope * (t(p) - coast.t0 - coast.st() / coast.n);
    return true;
  }
  // A lead-in that climbs into the cut: its last samples rise to the coast's start.
  const std::size_t c = sp.cut_index;
  if (c < sp.a + 6) return false;
  const double before = smoothed(store_, c - 5, sp.a, b), last = smoothed(store_, c - 2, sp.a, b);
  return last > before + thr && last >= sp.v0 - thr && before < sp.v0 - 2.0 * thr;
}

std::string RunDetector::Impl::start_not_seen(CutSplit& sp) {
  const std::size_t c = sp.cut_index;
  // The first sample after the stream's start or the last pause, whichever came last.
  const bool after_pause = resume_index_ > stream_start_;
  const std::size_t seen_from = after_pause ? resume_index_ : stream_start_;
  if (c < seen_from) return {};
  // Joined part-way into a stream (joined_stream()): a "cut" found within the first samples, with
  // less than twice the lead-in it takes to judge one (try_start_coast's "too short"), has no
  // powered phase before it to show: the coast's start was not seen. A fitter that joined a coast late in it took its
  // first samples for a supply (issue 42 item 7). (A recording that starts so close to its cut
  // keeps its cut: it began with the bridge's stream.)
  const std::size_t seen = c - seen_from;  // samples before the cut since the stream's start
  const bool too_short =
      joined_stream_ && !after_pause && stream_start_ == 0 && seen < 2 * min_lead_samples;
  if (!too_short && std::max(sp.a, store_.base()) > seen_from) return {};
  // From there to the cut found, a "lead-in" that lies on the coast's line is more coast.
  const std::size_t a = seen_from;
  if (c > a && !too_short) {
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
      const WindowFit pre = window_over(store_.data(), store_.mask(), 1e300, a, c);
      // The question is whether these samples are more coast: if they are, their noise is the
      // coast's, measured over its many samples. Far quieter than that, beyond chance (χ² at 1 in
      // 1,000), they are no coast: a level held (a reading pinned at the converter's top).
      // A quantized reading's spread is at least the step's, however often it repeats a value.
      const double post_noise = sp.post_rough > 0 ? std::min(sp.sd_post, sp.post_rough) : sp.sd_post;
      const double e_pre = std::max(pre.resid_sd(), reading_step(store_, a, c + 1) * step_sd);
      const double dof = double(c - a) - 2.0;
      if (post_noise > 0 && dof * (e_pre * e_pre) / (post_noise * post_noise) < chi2_lower_tail(dof, z_one_in_1000))
        return {};
      // Otherwise its slope is judged on the coast's noise: a few readings that repeat one value
      // (a quantized coast near its end, 0.57 V eight times on a 10-mV print) show a spread below it.
      const double e = std::max(e_pre, post_noise);
      const double s = pre.slope(), se = pre.sxx() > 0 ? e / std::sqrt(pre.sxx()) : 0.0;
      // Nor can a span over which the coast's line falls less than two of the reading's steps show
      // a level: the print cannot tell a plateau there from the coast.
      const double fall = -sp.post_slope * (t(c - 1) - t(a));
      const bool resolvable = fall >= 2.0 * reading_step(store_, a, store_.end());
      if (resolvable && s - sp.post_slope > 3.0 * se && s > 0.5 * sp.post_slope) return {};
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
  if (stream_start_ > 0 && stream_after_restart_)
    return fmt::format("the coast begins at the device clock's restart ({} on the new clock), falling: its cut was "
                       "not recorded, so the coast is partial, taken from its first sample",
                       fmt_s(t(a)));
  return fmt::format("the recording starts mid-coast at {}: the cut was not recorded, so the coast is partial",
                     fmt_s(t(a)));
}

std::string RunDetector::Impl::rest_after_silence(CutSplit& sp) {
  // The coast that went silent goes on: taken from the first sample after the silence (or the
  // oldest still held), its cut long before and not in this stream.
  const std::size_t a = std::max({resume_index_, store_.base(), lo_});
  if (a >= store_.end()) return {};
  const std::size_t c = sp.cut_index;
  sp.v0 = sp.v0 + sp.post_slope * (t(a) - t(c));
  sp.cut_index = a;
  sp.pre_end = a;
  sp.npre = 0;
  sp.t_cut_s = t(a);
  sp.clipped = false;
  sp.pre_declining = false;
  return fmt::format("the samples stopped for over {:g} s mid-coast and resumed on the same clock at {}: this is the "
                     "rest of run {}'s coast, whose cut came before the silence, so it is partial (no cut)",
                     silence_s_, fmt_s(t(a)), silenced_run_);
}


}  // namespace spindown
