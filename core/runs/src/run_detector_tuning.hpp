#pragma once
// The run detector's tuning, shared by its files (run_detector.cpp: the per-sample path and the
// tests of a window; run_detector_cut.cpp: finding the cut; run_detector_stop.cpp: the stop;
// run_detector_close.cpp: closing a run and its warnings). Private to the runs module.
#include <cstddef>
#include <fmt/format.h>
#include <string>

namespace spindown::detector_tuning {

// Seconds of lead-in searched for the cut before the window that confirmed the coast.
inline constexpr double back_search_s = 2.0;
// Seconds of lead-in kept while idle.
inline constexpr double idle_keep_s = 40.0;
// Samples searched at least, for slow loops.
inline constexpr std::size_t back_search_min_samples = 16;
// A lead-in of fewer samples is too short to judge (flat, rising or part of the decline).
inline constexpr std::size_t min_lead_samples = 8;
// A coast is confirmed by a decline this many standard errors strong …
inline constexpr double confirm_t_stat = 6.0;
// … whose residual roughness is at most this fraction of its level (rejects a floating pin).
inline constexpr double confirm_max_roughness = 0.05;
// Standstill: slope within this many standard errors of zero.
inline constexpr double flat_t_stat = 3.0;
// Standstill must be below this fraction of the reading at the cut.
inline constexpr double standstill_max_fraction = 0.3;
// A real stop arrives with a finite slope: the last quarter of the amplitude is crossed at
// least this fast relative to the coast's mean rate (Coulomb ≈ 1, lab's combined ≈ 0.8,
// pure viscous ≈ 0.3–0.45, depending on the noise that decides "flat").
inline constexpr double stop_min_end_rate = 0.5;
// … or the last stop_hold_s before the stop still falls with this t-statistic (an exponential
// that has become "flat" shows ~3–6 there, a Coulomb stop tens).
inline constexpr double stop_min_approach_t = 10.0;
// … or the coast's fall over its last quarter, as a + b·(height above the floor), keeps a rate a at
// the floor this many standard errors above 0 (Coulomb friction: an exponential's a is 0).
inline constexpr double floor_rate_min_t = 4.0;
// A 1 s hold window decides alone when its slope error is this fraction of the mean rate.
inline constexpr double slope_resolution = 0.05;
// In the tail, a hold-window mean this fraction of the amplitude below the zero level retracts
// the stop.
inline constexpr double retract_fraction = 0.01;
// A standstill whose readings spread less than this many reading steps (sd) sits on one value.
inline constexpr double quiet_floor_sd = 0.3;
// The spread of a reading rounded to steps of 1, as uniform rounding error: 1/sqrt(12).
inline constexpr double step_sd = 0.2886751345948129;
// The long hold window spans at least this fraction of the coast before it.
inline constexpr double long_hold_fraction = 0.03;
// A slow logger's windows hold at least this many samples, whatever their spans in seconds say
// (set_spans). The longest window that confirms a coast: confirms_decline's own minimum (a slope
// t-statistic of 6 on 4 degrees of freedom). At one reading a second its 4 s would hold 5.
inline constexpr std::size_t confirm_min_samples = 6;
// The hold windows that find a standstill: a slope and its residual on 3 degrees of freedom. At
// one reading a second the 1-s hold window would hold one or two, and no stop could be found; at
// 10 Hz and faster the spans in seconds hold more, and are kept.
inline constexpr std::size_t hold_min_samples = 5;
// A period longer than this between two samples is a pause in the recording, not its rate.
inline constexpr double pause_s = 2.0;
// A coast crosses a band of its noise (2h wide) in about 2h over its rate there, and falls
// dwell_fall_bands more bands after it in about that many times as long, or less (friction grows
// with speed; Stribeck's rise at low speed is at most a few times the Coulomb level). A reading that
// held a band more than dwell_max_ratio times as long as the coast then took for those bands did
// not coast while it held.
inline constexpr double dwell_fall_bands = 4.0;
inline constexpr double dwell_max_ratio = 20.0;
// Recompute sliding sums from scratch this often (rounding drift).
inline constexpr unsigned refresh_every = 4096;

// A silence inside a coast (from the sample at prev to the one at t, the coast cut at t_cut) that
// ends it: longer than half a minute and than the coast seen before it, so the samples after it
// would be a coast the fit barely knew the way to. A shorter one is samples lost (or a clock
// that jumped), said by warn_of_gap_in_coast, and the coast goes on.
[[gnu::always_inline]] inline bool long_silence(double prev, double t, double t_cut) {
  return t - prev > 30.0 && t - prev > prev - t_cut;
}

inline std::string fmt_s(double t) { return fmt::format("{:.3f} s", t); }

}  // namespace spindown::detector_tuning
