// Why a coast's cut was moved after it was found: every re-cut of a closed coast, in the order
// complete_run() applies them (recut_coast). Each says what it measured, in the recording's own
// noise and step, with the run:
//  * a coast never rises (recut_after_rise): a jump far beyond the reading's noise inside it means
//    what came before was no part of it (an open pin's swing before it was connected, a coast the
//    power came back on unseen);
//  * a coast never comes back to its level (recut_after_return): standing at the cut's level again
//    where its own pace says it must have fallen far below it, no coast had begun (a drive hunting
//    about its setpoint);
//  * a spin-up's peak held as a level (recut_at_level_end): the coast starts where the level ends;
//  * a coast never dwells (recut_after_dwell): a level held far longer than the coast then took to
//    fall through it was a drive under power (a start-up overshoot settling on its setpoint).
// Each moves the cut as any cut is found (recut_from: the two-segment split, the lead-in named).
#include "run_detector_impl.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fmt/format.h>
#include <limits>
#include <string>
#include <vector>

#include "run_detector_tuning.hpp"
#include "spindown/coast_dwell.hpp"
#include "spindown/coast_jump.hpp"
#include "spindown/level_return.hpp"

namespace spindown {

using namespace detector_tuning;

void RunDetector::Impl::recut_coast(Run& r, std::size_t end) {
  if (!not_coast_.empty() || fragment_) return;
  const std::size_t coast_end = r.stopped ? r.stop_index : end;
  coast_noise_for_.reset();  // the store has changed since any was kept
  recut_after_rise(r, coast_end);
  if (!not_coast_.empty() || fragment_) return;
  recut_after_return(r, coast_end);
  if (!not_coast_.empty() || fragment_) return;
  recut_at_level_end(r, coast_end);
  if (!not_coast_.empty() || fragment_) return;
  recut_after_dwell(r, r.stopped ? r.stop_index : end);
}

const LagNoise& RunDetector::Impl::coast_noise(std::size_t c, std::size_t coast_end) {
  if (coast_noise_for_ != std::pair{c, coast_end}) {
    const std::size_t mid = c + (coast_end - c) / 2;
    const LagNoise early = noise_over(store_, c, mid), late = noise_over(store_, mid, coast_end);
    coast_noise_ = early.wander < late.wander ? early : late;
    coast_noise_for_ = std::pair{c, coast_end};
  }
  return coast_noise_;
}

void RunDetector::Impl::recut_after_rise(Run& r, std::size_t coast_end) {
  const std::size_t c = r.cut_index;
  const double zero = r.stopped ? r.zero_level : motor_zero();
  const std::optional<CoastJump> jump =
      coast_jump(store_, {c, coast_end, v0_ - zero, coast_step_, r.lead_in == "floating"},
                 [&]() -> const LagNoise& { return coast_noise(c, coast_end); }, median5_);
  if (!jump) return;
  const std::size_t rise = jump->at;
  const double rose = jump->rose;
  // What made it evidence, said with it: the jump in units of the reading's noise, or the level
  // over whole ripples.
  const std::string evidence =
      jump->ripple_len > 0 ? fmt::format(" (its level over whole ripples of {} samples moved {:.3g}, {:.0f} times those means' noise)",
                                         jump->ripple_len, jump->ripple_shift, std::abs(jump->ripple_shift) / jump->ripple_se)
      : jump->white > 0    ? fmt::format(" ({:.0f} times the reading's sample-to-sample noise {:.2g})", std::abs(rose) / jump->white,
                                         jump->white)
                           : std::string(" (the reading shows no noise)");
  // The coast after the rise: its cut found as any cut is, with the samples before the rise as lead-in.
  std::size_t a = rise, b = rise;
  while (a > c && t(rise) - t(a - 1) <= back_search_s) --a;
  while (b + 1 < coast_end && t(b + 1) - t(rise) <= 1.0) ++b;
  if (b < rise + 6 || rise < a + 4) return;
  const WindowFit w = window_over(store_.data(), store_.mask(), 1.0, rise, b + 1);
  const std::size_t keep_lo = search_lo_;
  search_lo_ = std::max(search_lo_, c);
  CutSplit sp = split_at_cut(a, b, w);
  search_lo_ = keep_lo;
  if (!(sp.v0 > 0) || sp.cut_index <= c) return;
  const double t_old = r.t_cut_s;
  bounce_.clear();
  take_bounce(sp, w);
  r.cut_index = sp.cut_index;
  r.t_cut_s = sp.t_cut_s;
  r.lead_in = classify_lead_in(sp);
  v0_ = sp.v0;
  const std::string said = fmt::format(
      "the reading {} by {:.3g}{} at {}, inside the coast taken from {}: a coast never {}, so the coast is taken "
      "from {} (the pin connected to the motor then? the power back on?), lead-in {}",
      rose > 0 ? "rose" : "stepped down", std::abs(rose), evidence, fmt_s(t(rise)), fmt_s(t_old),
      rose > 0 ? "rises" : "jumps", fmt_s(r.t_cut_s), r.lead_in);
  run_note_ = run_note_.empty() ? said : said + "; " + run_note_;
  run_note_severity_ = Diagnostic::Severity::warning;
  // The standstill was judged against the old cut: from the new one, a coast whose last quarter
  // creeps in is an exponential's (pure viscous friction), not a stop.
  if (r.stopped && creeps_in(r.t_cut_s, last_quarter_time(c, r.stop_index, r.zero_level + 0.25 * (v0_ - r.zero_level)),
                             r.t_stop_s)) {
    r.stopped = false;
    r.end = Run::End::asymptotic;
    r.stop_index = r.end_index;
    r.t_stop_s = std::numeric_limits<double>::quiet_NaN();
    run_note_ += fmt::format("; from there the coast approaches its floor ({:g}) asymptotically, as pure viscous "
                             "friction does: treated as never stopped, coast closed at {}",
                             r.zero_level, fmt_s(r.t_end_s));
  }
}

void RunDetector::Impl::recut_after_return(Run& r, std::size_t coast_end) {
  const std::size_t c = r.cut_index;
  if (coast_end < c + 24 || !(v0_ > 0)) return;
  // Readings held at the converter's top (find_pinned_start) are not the motor's: from after them.
  std::size_t from = c;
  if (std::isfinite(pin_level_))
    for (std::size_t k = c; k < coast_end; ++k)
      if (v(k) >= pin_level_) from = k + 1;
  const std::optional<LevelReturn> ret =
      level_return(store_, {c, from, coast_end, r.t_cut_s, v0_, coast_step_},
                   [&]() -> const LagNoise& { return coast_noise(c, coast_end); }, return_scratch_);
  if (!ret || ret->back + 6 >= coast_end) return;
  // The coast after the return, with the next seconds (a drive's hunting may run on a while below
  // the level before the cut).
  const double t_old = r.t_cut_s;
  const bool was_partial = r.partial();  // "the recording starts mid-coast": no longer so
  if (!recut_from(r, ret->back, coast_end, back_search_s, 4)) return;
  const std::string said = fmt::format(
      "the reading stood at {:.4g} until {}, back at the level of the coast taken from {} ({:.4g}), where that coast "
      "would have lost {:.2g} by then at a quarter of its own pace ({:.0f} times its means' noise {:.2g}): friction "
      "only takes speed off, so no coast had begun; the coast is taken from {} (lead-in {})",
      ret->at_level, fmt_s(t(ret->back - 1)), fmt_s(t_old), ret->level, ret->lost, ret->lost / ret->se, ret->se,
      fmt_s(r.t_cut_s), r.lead_in);
  run_note_ = run_note_.empty() || was_partial ? said : said + "; " + run_note_;
  run_note_severity_ = Diagnostic::Severity::warning;
}

bool RunDetector::Impl::recut_from(Run& r, std::size_t at, std::size_t coast_end, double ahead_s, std::size_t min_lead) {
  const std::size_t c = r.cut_index;
  std::size_t a = at, b = at;
  while (a > c && t(at) - t(a - 1) <= back_search_s) --a;
  while (b + 1 < coast_end && t(b + 1) - t(at) <= ahead_s) ++b;
  if (b < at + 6 || at < a + min_lead) return false;
  const WindowFit w = window_over(store_.data(), store_.mask(), 1.0, at, b + 1);
  const std::size_t keep_lo = search_lo_;
  search_lo_ = std::max(search_lo_, c);
  CutSplit sp = split_at_cut(a, b, w);
  const std::string lead = classify_lead_in(sp);
  if (lead == "powered" && sp.pre_flat) refine_plateau_cut(sp, b);
  search_lo_ = keep_lo;
  if (!(sp.v0 > 0) || sp.cut_index <= c) return false;
  bounce_.clear();
  r.cut_index = sp.cut_index;
  r.t_cut_s = sp.t_cut_s;
  r.lead_in = lead;
  v0_ = sp.v0;
  return true;
}

void RunDetector::Impl::recut_at_level_end(Run& r, std::size_t coast_end) {
  // A coast taken from a spin-up's peak whose reading held that level for a while: the coast starts
  // where the level ends, judged now on the coast's first quarter (the cut judged on the samples
  // up to the window that confirmed the coast may have had too little coast to tell).
  const std::size_t p = r.cut_index;
  if (r.lead_in != "spin-up" || coast_end < p + 24) return;
  double low = v(p);
  for (std::size_t k = p; k < coast_end; ++k) low = std::min(low, v(k));
  const double quarter = v0_ - 0.25 * (v0_ - low);
  std::size_t b = p + 16;
  while (b + 1 < coast_end && smoothed(store_, b, p, coast_end - 1) > quarter) ++b;
  const std::size_t c = level_end(p, p, b);
  if (c == p) return;
  const double held = t(c) - t(p);
  r.cut_index = c;
  r.t_cut_s = t(c);
  v0_ = smoothed(store_, c, p, coast_end - 1);
  const std::string said = fmt::format(
      "the reading held the level it rose to for {:.3g} s after its peak: the coast is taken from where it "
      "leaves that level, {}",
      held, fmt_s(r.t_cut_s));
  run_note_ = run_note_.empty() ? said : said + "; " + run_note_;
}

void RunDetector::Impl::recut_after_dwell(Run& r, std::size_t coast_end) {
  const std::optional<CoastDwell> d = coast_dwell(store_, {r.cut_index, coast_end, coast_sd_, coast_step_}, dwell_scratch_);
  if (!d) return;
  // The coast after the dwell: its cut found as any cut is, the dwell its lead-in.
  const double t_old = r.t_cut_s;
  if (!recut_from(r, d->at, coast_end, 1.0, 8)) return;
  const std::string said = fmt::format(
      "the reading held at {:.4g} ± {:.2g} or above from {} to {}, inside the coast taken from {}, and then fell {:.2g} "
      "times as far in a twentieth of that time or less: a coast never dwells, so the coast is taken from {} (lead-in {})",
      v(d->from), 2.0 * d->band, fmt_s(t(d->from)), fmt_s(t(d->at - 1)), fmt_s(t_old), 2.0 * dwell_fall_bands,
      fmt_s(r.t_cut_s), r.lead_in);
  run_note_ = run_note_.empty() ? said : said + "; " + run_note_;
  run_note_severity_ = Diagnostic::Severity::warning;
}

}  // namespace spindown
