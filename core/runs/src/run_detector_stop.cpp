// A coast's end: the standstill (or why there is none), the tail after it, a stop retracted.
#include "run_detector_impl.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fmt/format.h>
#include <string>

#include "run_detector_tuning.hpp"
#include "spindown/plateau_watch.hpp"
#include "spindown/signal_loss.hpp"
#include "spindown/stop_shape.hpp"

namespace spindown {

using namespace detector_tuning;

void RunDetector::Impl::coast_too_long(std::size_t i) {
  if (buffered() > opt_.max_buffer) {
    // The memory bound: the coast so far is fitted (never stopped), as at the time bound below; what
    // it does after is not a run.
    run_note_severity_ = Diagnostic::Severity::warning;
    close_unstopped(i, fmt::format("no standstill within the {} samples ({:.0f} s at this rate) kept of one coast: "
                                   "closed there as never stopped, the coast fitted up to there; the rest of this "
                                   "coast is not a run",
                                   opt_.max_buffer, t(i - 1) - run_.t_cut_s),
                    Run::End::cap);
    to_idle(i, true);
    block_until_rise(v(i - 1));
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
                  fmt::format("no standstill within {:g} s, the longest coast kept: closed there as never stopped, "
                              "the coast fitted up to there; the rest of this coast is not a run",
                              opt_.max_coast_s),
                  Run::End::cap);
  to_idle(i + 1, true);
  // The coast goes on: no new run until the reading rises above where it was closed, or has come
  // down to the motor's zero (stopped) first.
  block_until_rise(v(i));
}

std::string RunDetector::Impl::swing_reason(std::size_t at) const {
  // The coast fell from v0_ to its lowest level, then rose again. Before its cut, over up to 10 s
  // (or three times the coast), did the reading already swing as far both ways? A motor's lead-in
  // (at rest, powered, spun up) rises at most once, into the cut; an open analog pin whose jumper
  // picks up the mains (the handout's step 6: A0 is connected only after the cut) swings up and
  // down all the time, its 50 Hz hum aliased by the ~20 ms loop into a slow beat.
  const std::size_t cut = run_.cut_index;
  const double fall = v0_ - level_min_;
  if (!(fall > 0) || !std::isfinite(fall) || at <= cut) return {};
  constexpr double look_s = 10.0;
  const std::size_t lower = std::max({store_.base(), stream_start_});
  std::size_t from = cut;
  while (from > lower && t(cut) - t(from - 1) <= look_s) --from;
  if (cut < from + 8) return {};
  // Zigzag of the 3-sample mean with hysteresis h: a turn is a move of at least h from the last
  // extreme against the direction before it (the first move counts as one).
  const double h = std::max({0.3 * fall, 4.0 * coast_sd_, 3.0 * coast_step_});
  int turns = 0, dir = 0;
  double x0 = smoothed(store_, from, from, cut - 1), top = x0, bottom = x0, hi = x0, lo = x0;
  for (std::size_t k = from + 1; k < cut; ++k) {
    const double x = smoothed(store_, k, from, cut - 1);
    hi = std::max(hi, x), lo = std::min(lo, x);
    top = std::max(top, x), bottom = std::min(bottom, x);
    if (dir >= 0 && top - x >= h) ++turns, dir = -1, bottom = x;      // a fall from the last top
    else if (dir <= 0 && x - bottom >= h) ++turns, dir = 1, top = x;  // a rise from the last bottom
  }
  // A rise into the cut is one turn (a spin-up); a fall and a rise before it are a swing.
  if (turns < 2 || !(hi - lo >= 0.5 * fall)) return {};
  return fmt::format("the reading swings up and down before it too ({} turns of at least {:.3g} within {:.3g} s, "
                     "between {:.3g} and {:.3g}), as an open analog input picking up mains hum does: not a coast "
                     "(the handout's step 6 connects A0 to the motor only after the cut)",
                     turns, h, t(cut) - t(from), lo, hi);
}

std::string RunDetector::Impl::stall_reason(std::size_t at) const {
  // Friction slows a coast at every speed it passes: the deceleration at speed ω is T(ω)/J, and
  // T falls with ω no faster than windage's ω² (Coulomb holds it, viscous ∝ ω, Stribeck raises it).
  // A decline that levels off while the reading is still well above standstill, then rises, was
  // no coast: an open pin's slow wander (the handout's step 6) or a drive holding a lower speed.
  const std::size_t cut = run_.cut_index;
  if (at < cut + 24) return {};
  const std::size_t third = (at - cut) / 3;
  const WindowFit first = window_over(store_.data(), store_.mask(), 1e300, cut, cut + third);
  const WindowFit last = window_over(store_.data(), store_.mask(), 1e300, at - third, at);
  const double rate0 = -first.slope(), rate1 = -last.slope();
  const double se1 = last.sxx() > 0 ? last.resid_sd() / std::sqrt(last.sxx()) : INFINITY;
  const double se0 = first.sxx() > 0 ? first.resid_sd() / std::sqrt(first.sxx()) : INFINITY;
  const double zero = motor_zero();
  const double u0 = first.mean() - zero, u1 = last.mean() - zero;
  // Not even lower at the end than at the start, beyond the noise of the two means.
  const double se_means = std::hypot(first.resid_sd() / std::sqrt(first.n), last.resid_sd() / std::sqrt(last.n));
  if (u0 - u1 < 3.0 * se_means)
    return fmt::format("over its last third the reading is no lower than over its first ({:.3g} against {:.3g}) before "
                       "it rose again: no coast (an open pin's wander before it was connected? a drive holding its "
                       "speed?)",
                       last.mean(), first.mean());
  if (!(rate0 > 4.0 * se0) || !(u0 > 0) || !(u1 > 0.3 * u0)) return {};
  const double least = 0.25 * (u1 / u0) * (u1 / u0) * (rate0 - 2.0 * se0);
  if (!(rate1 + 2.0 * se1 < least)) return {};
  return fmt::format("the decline levelled off at {:.3g} ({:.0f} % of where it began) before the reading rose again: "
                     "it fell {:.3g} a second at first and {:.2g} at the end, where friction would still slow it at "
                     "least {:.2g} — no motor coasts like that (an open pin's wander before it was connected? a drive "
                     "holding a lower speed?)",
                     last.mean(), 100.0 * u1 / u0, rate0, rate1, least);
}

bool RunDetector::Impl::held_plateau(std::size_t i) {
  const std::optional<Plateau> p = plateau_.look(
      store_, hold_, t(i), hold_half_s_,
      {run_.cut_index, run_.t_cut_s, v0_, motor_zero(), coast_step_ * step_sd, same_start_ <= hold_.first});
  if (!p) return false;
  not_coast_ = fmt::format(
      "it fell from {:.4g} and then held level at {:.4g} from {} ({:.2g} a second, where friction would "
      "still take off at least {:.2g}): a coast never holds a plateau — a drive stepping down to a lower "
      "speed under power (a setpoint step, a start-up overshoot settling); the cut is looked for after it",
      v0_, p->level, fmt_s(t(p->from)), p->rate, p->least);
  close_unstopped(p->from, "held a plateau under power", Run::End::power_back);
  to_idle(p->from, false, p->from);
  return true;
}

void RunDetector::Impl::power_back() {
  const std::size_t at = rise_start_, cut = run_.cut_index;
  not_coast_ = swing_reason(at);
  if (not_coast_.empty()) not_coast_ = stall_reason(at);
  // Its start not recorded and its end a rise: nothing shows this decline was a motor's coast.
  if (not_coast_.empty() && run_.partial())
    not_coast_ = "neither its cut nor a standstill was seen (the recording starts on it, and the reading rose again): a "
                 "piece of a coast, or an open pin's wander before it was connected — not a run";
  // A speed sensor read the motor at rest (zeros) and then straight at the decline's top: its
  // spin-up was one sample long at most, no cut was seen, and the reading rose again before
  // standstill: nothing shows a coast (a start-up under power, or a sensor's first readings).
  if (not_coast_.empty() && speed_reading_ && run_.lead_in == "zeros")
    not_coast_ = fmt::format(
        "the speed sensor read the motor at rest and then {:.4g} a sample later (no spin-up, so no cut), and the "
        "reading rose again {:.3g} s after, before standstill: a start-up under power or a sensor's first readings, "
        "not a run",
        v0_, t(at) - run_.t_cut_s);
  // The window ends early, so the result changes: said in the default output.
  run_note_severity_ = Diagnostic::Severity::warning;
  close_unstopped(at,
                  fmt::format("the reading rose again at {}, {:.3g} s after the cut, before standstill: the motor "
                              "powered again (the coast is fitted up to there), or, if A0 was not yet connected to "
                              "the motor, an open pin's hum and no coast",
                              fmt_s(t(at)), t(at) - run_.t_cut_s),
                  Run::End::power_back);
  // The samples before the rise are the next coast's lead-in: what the reading did before a step up
  // to it (a floating pin connected to the motor, a motor powered again) tells where that coast's
  // cut is.
  to_idle(at, false, cut);
}

void RunDetector::Impl::standstill_checks(std::size_t i, bool at_end, double mu, double sxx, double e) {
  // The hold window is flat and low (coast_checks has shown it: mu is its mean, sxx and e its
  // Sxx and residual sd), and either its slope is resolved well below the coast's mean rate or
  // a three times longer window is flat too (noisy, slow coasts).
  bool resolved = at_end;
  if (!at_end) {
    const double mean_rate = (v0_ - mu) / std::max(t(i) - run_.t_cut_s, 1e-9);
    // A quantized reading can sit on one value for the whole window (e = 0) while the motor still
    // turns: its resolution is at best the step's uniform spread. A coast so slow that its first
    // samples showed no step yet learns it here, once.
    if (coast_step_ == 0) coast_step_ = reading_step(store_, run_.cut_index, i + 1);
    const double e_eff = std::max(e, coast_step_ * step_sd);
    resolved = sxx > 0 && e_eff / std::sqrt(sxx) <= slope_resolution * mean_rate;
  }
  if (creeping_ && !at_end) resolved = false;  // an asymptotic coast ends when the long window is flat
  if (!resolved) {
    if (!hold_long_live_) {
      // Three hold windows, or 3 % of the coast so far if longer: a heavy flywheel's coast falls a
      // few mV a second near its end, which a 3 s window of noisy readings can take for level.
      hold_long_.span_s = std::max(3.0 * hold_.span_s, long_hold_fraction * (t(i) - run_.t_cut_s));
      reset_window(hold_long_, run_.cut_index, i + 1);
      hold_long_live_ = true;
    }
    if (!flat(hold_long_)) return;
  }
  found_standstill(i, at_end);
}

void RunDetector::Impl::found_standstill(std::size_t i, bool at_end) {
  const std::size_t h0 = hold_.first;
  const double z = median_of(h0, i + 1);
  double var = 0;
  for (std::size_t k = h0; k <= i; ++k) var += (v(k) - z) * (v(k) - z);
  const double sd_z = std::sqrt(var / double(i + 1 - h0));
  const double amp = v0_ - z;
  const double band = std::max(3.0 * sd_z, 1e-9 * std::max(std::abs(amp), 1e-300));

  const std::size_t first_in = standstill_start(i, z, band);
  if (signal_lost(i, first_in, z, amp)) return;

  // Where the coast crossed the last quarter of its amplitude.
  const std::size_t k = last_quarter_index(store_, run_.cut_index, first_in, z + 0.25 * amp);
  const double t_quarter = crossing_time(store_, k, run_.cut_index, z + 0.25 * amp);
  // A value held into the standstill longer than the coast allows (a per-tooth sensor's last
  // reading, held until it gives up) is one reading: the approach ends at its first sample.
  const std::size_t held = held_into(store_, k, first_in, coast_step_);
  const std::size_t approach_end = held < first_in ? held + 1 : first_in;
  const std::size_t stop = first_sample_from(approach_meets_zero(first_in, approach_end, k, z, t_quarter, i), i);
  note_stop_in_pause(stop);

  // A real stop arrives with a finite slope; an exponential creeps in.
  const double t_stop = t(stop);
  run_.zero_level = z;
  run_.noise_level = sd_z;
  // … and right before it the reading still falls clearly (an exponential has flattened).
  stop_approach_t_ = approach_t_stat(store_, run_.cut_index, stop, opt_.stop_hold_s);
  stop_floor_t_ = floor_rate_t(store_, k, approach_end, z);
  if (!creeps_in(run_.t_cut_s, t_quarter, t_stop) || amp <= 0) {
    stop_at(i, stop, z, sd_z, amp);
  } else if (!creeping_ && !at_end) {
    // Keep the coast until the decay is lost in the noise even over the long window: the
    // exponential's tail still carries information for the fit.
    creeping_ = true;
  } else {
    const double coast = t_stop - run_.t_cut_s, last_quarter = t_stop - t_quarter;
    const double end_rate = last_quarter > 0 ? 0.25 * coast / last_quarter : std::numeric_limits<double>::infinity();
    close_asymptotic(i, at_end, z, sd_z, amp, end_rate);
  }
}

std::size_t RunDetector::Impl::standstill_start(std::size_t i, double z, double band) const {
  // First sample of the standstill that contains the hold window (an isolated sample outside
  // the band is noise; two in a row are the coast, unless the readings before them come back to
  // the standstill: a coast only gets further from its standstill going back in time, noise
  // returns). The band is three times a noise measured from the hold window's few readings (10
  // at 10 Hz), which often reads it low, so "come back" is judged by that noise's upper 95 %
  // bound: the mean of a hold window's worth of readings before the pair within three of its
  // standard errors of the standstill's level. A slow coast, whose readings a second back lie
  // above the level by more than that, still ends the standstill; so does a pair inside the hold
  // window, and a pair a whole step of the reading off a standstill quieter than that step (the
  // coast's last step down).
  const std::size_t h0 = std::min(hold_.first, i), lookback = i + 1 - h0;
  const auto in_band = [&](std::size_t k) { return std::abs(v(k) - z) <= band; };
  std::size_t first_in = i + 1;
  while (first_in > run_.cut_index + 1) {
    if (in_band(first_in - 1)) {
      --first_in;
    } else if (first_in - 1 > run_.cut_index + 1 && in_band(first_in - 2) && first_in - 1 < i + 1) {
      first_in -= 2;  // lone outlier
    } else if (lookback >= 4 && first_in <= h0 + 1 && first_in - 1 > run_.cut_index + 1 + lookback) {
      const std::size_t pair = first_in - 2;  // the first of the two out of the band
      if (band < coast_step_) break;
      double sum = 0;
      for (std::size_t k = pair - lookback; k < pair; ++k) sum += v(k) - z;
      if (std::abs(sum) > band * noise_upper_bound(lookback) * std::sqrt(double(lookback))) break;
      first_in = pair;  // noise: the walk goes on before the pair
    } else {
      break;
    }
  }
  return std::min(first_in, i);
}

double RunDetector::Impl::approach_meets_zero(std::size_t first_in, std::size_t end, std::size_t k, double z,
                                              double t_quarter, std::size_t i) const {
  // Stop time: the approach line (the last ≤2 s of [k, end) above the band) meets the zero level.
  double t_hit = t(first_in);
  const double t_ref = end < first_in ? t(end - 1) : t(first_in);
  std::size_t from = end;
  while (from > k && t_ref - t(from - 1) <= 2.0) --from;
  if (end >= from + 3) {
    WindowFit f;
    f.clear(from, t(from));
    for (std::size_t j = from; j < end; ++j) f.add(t(j), v(j));
    const double sl = f.slope();
    if (sl < 0) {
      const double tb = f.st() / f.n, vb = f.mean();
      const double th = f.t0 + tb + (z - vb) / sl;
      if (std::isfinite(th)) t_hit = std::clamp(th, t_quarter, t(i));
    }
  }
  return t_hit;
}

std::size_t RunDetector::Impl::first_sample_from(double t_hit, std::size_t i) const {
  // The first sample at or after t_hit (times never decrease within a stream), at most i.
  std::size_t lo = run_.cut_index + 1, hi = std::max(lo, i);
  while (lo < hi) {
    const std::size_t mid = lo + (hi - lo) / 2;
    if (t(mid) < t_hit) lo = mid + 1;
    else hi = mid;
  }
  return lo;
}

void RunDetector::Impl::note_stop_in_pause(std::size_t stop) {
  // A stop that falls in a pause of the recording is known only to lie in it.
  if (stop <= run_.cut_index + 2) return;
  const double pause = t(stop) - t(stop - 1);
  const double period = (t(stop - 1) - t(run_.cut_index)) / double(stop - 1 - run_.cut_index);
  if (pause > 1.0 && pause > 25.0 * period) {
    run_note_ = fmt::format("the stop falls in a pause of the recording ({:.3g} s, from {} to {}): it lies somewhere "
                            "in it, and the stop time is the pause's end",
                            pause, fmt_s(t(stop - 1)), fmt_s(t(stop)));
    run_note_severity_ = Diagnostic::Severity::warning;
  }
}


void RunDetector::Impl::stop_at(std::size_t i, std::size_t stop, double z, double sd_z, double amp) {
  const double t_stop = t(stop);
  run_.stopped = true;
  run_.stop_index = stop;
  run_.t_stop_s = t_stop;
  // A standstill that sits on one value of a quantized reading (a quiet converter) a step or
  // more above the lowest the motor read at rest may be a slow exponential's dwell on that value
  // (a viscous coast near its end takes seconds per step of the print): the tail is watched
  // longer, and a step down held retracts the stop (tail_step).
  floor_doubt_ = quiet_dwell_above_rest(z, sd_z, amp);
  tail_until_s_ = t_stop + (floor_doubt_ ? std::max(opt_.tail_s, 0.25 * (t_stop - run_.t_cut_s)) : opt_.tail_s);
  depart_band_ = std::max(6.0 * sd_z, 0.05 * std::abs(amp));
  departing_ = 0;
  state_ = State::tail;
  emit_run_event(RunEvent::Kind::stop);
  tail_ends_by_time(i);
}

void RunDetector::Impl::close_asymptotic(std::size_t i, bool at_end, double z, double sd_z, double amp,
                                         double end_rate) {
  // The floor an asymptotic coast shows is where its decay was lost in the noise or the print,
  // not where it is heading (an exponential heads for the true zero): 0.01 V on the lab's
  // 2-decimal print long before the motor stops, and subtracting that from every reading
  // bends the viscous curve into Coulomb friction that is not there. A floor the detector's
  // own flatness test cannot tell from the lead-in's zero (the motor at rest, read before the
  // run) gives way to that zero: within 3 noise sd, 1 % of the cut's reading (level()'s
  // allowance for a flat window's drop) or one reading step. A floor clearly above it (an
  // offset only the coasting reading has) is kept.
  // A per-revolution sensor keeps its last reading once the pulses stop: a floor reached by a
  // jump and held exactly, far longer than any value before it, is that reading, not a zero to
  // subtract (the shaft turning at that speed would have updated it long since).
  std::size_t held_from = 0, longest = 1;
  const bool held_jump = held_last_value(run_.cut_index, i + 1, held_from, longest, false);
  const bool held_long = held_jump && i + 1 - held_from >= 5 * longest;
  if (held_jump && !held_long && !at_end) return;  // wait and see how long it holds
  std::string floor_said;
  const double band = std::max({3.0 * sd_z, 0.01 * std::abs(v0_), reading_step(store_, hold_.first, i + 1)});
  if (held_long) {
    run_.zero_level = motor_zero();
    floor_said = fmt::format(", the last reading of a sensor that holds it ({} samples from {}, where no value "
                             "before it lasted more than {}), not a zero: zero level {:g}, the coast fitted up "
                             "to that last update",
                             i + 1 - held_from, fmt_s(t(held_from)), longest, run_.zero_level);
  } else if (std::isfinite(lead_in_zero_) && std::abs(z - lead_in_zero_) <= band * (1 + 1e-9) && z != lead_in_zero_) {
    run_.zero_level = lead_in_zero_;
    floor_said = fmt::format(", not to be told from the lead-in's zero, so zero level {:g}", lead_in_zero_);
  } else if (std::isfinite(rest_level_) && z > rest_level_ &&
             (z - rest_level_ <= band * (1 + 1e-9) || quiet_dwell_above_rest(z, sd_z, amp))) {
    // No zeros before this cut (the supply's lead-in), but the stream held the motor's reading
    // at rest before (rest_level_): a floor that cannot be told from it, or a quiet print's last
    // value a few steps above it, is where the decay was lost, and the exponential heads on to
    // the rest reading.
    run_.zero_level = rest_level_;
    floor_said = fmt::format(", {:g} above the motor's reading at rest, where the decay heads: zero level {:g}",
                             z - rest_level_, rest_level_);
  }
  run_note_ = fmt::format(
      "run cut at {}: the coast approaches its floor ({:g}{}) asymptotically (last quarter {:.2f}x slower than "
      "the mean rate), as pure viscous friction does: treated as never stopped, coast closed at {}",
      fmt_s(run_.t_cut_s), z, floor_said, end_rate > 0 ? 1.0 / end_rate : 0.0, fmt_s(t(i)));
  run_.stopped = false;
  run_.end = Run::End::asymptotic;
  complete_run(held_long ? held_from + 1 : i + 1);
  to_idle(i + 1, true);
  // The coast goes on below its floor, a step of the print at a time: no new run until the reading
  // rises well above where it was closed (a new spin-up), as after any coast closed before its stop.
  block_until_rise(z);
}

bool RunDetector::Impl::quiet_dwell_above_rest(double z, double sd_z, double amp) const {
  const double step = coast_step_;
  return std::isfinite(rest_level_) && step > 0 && sd_z < quiet_floor_sd * step && z - rest_level_ >= 0.99 * step &&
         z - rest_level_ < 0.25 * amp;
}


double RunDetector::Impl::last_quarter_time(std::size_t cut, std::size_t first_in, double quarter) const {
  return crossing_time(store_, last_quarter_index(store_, cut, first_in, quarter), cut, quarter);
}

bool RunDetector::Impl::creeps_in(double t_cut, double t_quarter, double t_stop) const {
  return StopShape{end_rate(t_cut, t_quarter, t_stop), stop_approach_t_, stop_floor_t_}.creeps_in();
}



void RunDetector::Impl::block_until_rise(double level) {
  need_rise_ = true;
  block_band_ = rise_jump_;  // as far above as power coming back
  rise_level_ = level + block_band_;
}

bool RunDetector::Impl::signal_lost(std::size_t i, std::size_t first_in, double z, double amp) {
  const std::optional<SignalLoss> loss = signal_loss(store_, {run_.cut_index, first_in, z, amp, motor_zero(), coast_step_});
  if (!loss) return false;
  run_note_severity_ = Diagnostic::Severity::warning;
  close_unstopped(loss->held + 1,
                  fmt::format("signal lost below {:g} at {}: {} where friction lets it fall about {:.2g} a sample; a "
                              "sensor that gives up at low speed (per-revolution pulses, an encoder, a display)? "
                              "Fitted up to there, as never stopped",
                              loss->level, fmt_s(t(loss->held)),
                              fmt::format("the reading fell from {:g} to {:g} in one sample", loss->last, z),
                              loss->fall > 1e-9 * amp ? loss->fall : 0.0),
                  Run::End::signal_lost);
  to_idle(i + 1, true);
  // No new run until the reading rises above what the sensor last showed (or after a standstill).
  block_until_rise(std::max(loss->level, z));
  return true;
}

void RunDetector::Impl::tail_ends_by_time(std::size_t upto) {
  const double t_end = tail_until_s_;
  for (std::size_t e = run_.stop_index + 1; e <= upto; ++e) {
    if (t(e) >= t_end) {
      complete_run(e);
      to_idle(e, false);
      return;
    }
  }
}

bool RunDetector::Impl::still_falling(std::size_t i) const {
  // Over the whole tail, a slope many standard errors below zero, lower than the quantization
  // allows a level reading, and at least a third of the approach's: the "standstill" was a slow
  // exponential's stretch (a viscous coast at a fraction of its start), not a stop.
  if (i < run_.stop_index + 8) return false;
  const WindowFit w = window_over(store_.data(), store_.mask(), 1e300, run_.stop_index, i + 1);
  const double sxx = w.sxx();
  if (!(sxx > 0)) return false;
  const double slope = w.slope();
  const double e = std::max(w.resid_sd(), coast_step_ * step_sd);
  const double mean_rate = (v0_ - run_.zero_level) / std::max(run_.t_stop_s - run_.t_cut_s, 1e-9);
  return slope < 0 && -slope * std::sqrt(sxx) > 6.0 * e && -slope > 0.1 * mean_rate;
}

void RunDetector::Impl::close_unstopped(std::size_t end, const std::string& why, Run::End reason) {
  run_.stopped = false;
  run_.end = reason;
  run_.zero_level = 0;
  run_.noise_level = coast_sd_;
  run_note_ = fmt::format("run cut at {}: {}", fmt_s(run_.t_cut_s), why);
  complete_run(end);
}

}  // namespace spindown
