#pragma once
// RunDetector's implementation: its state (the sample ring, the sliding windows, the open run)
// and the steps of its decisions, shared by run_detector*.cpp. Private to the runs module; the
// contract is spindown/run_detector.hpp.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "spindown/lag_noise.hpp"
#include "spindown/lead_in.hpp"
#include "spindown/reading_scale.hpp"
#include "spindown/run_detector.hpp"
#include "spindown/plateau_watch.hpp"
#include "spindown/sample_store.hpp"
#include "spindown/window_fit.hpp"

namespace spindown {

class RunDetector::Impl {
 public:
  using State = RunDetector::State;

  // RunDetector's contract (spindown/run_detector.hpp), which forwards each call here.
  Impl(RunOptions opt, std::string source);
  void push(double t_s, double value);
  void push_many(const double* t_s, const double* value, std::size_t n);
  void clock_restart();
  void new_source(const std::string& why);
  void finish();
  void went_silent(double silent_s);
  void joined_stream() { joined_stream_ = true; }
  void set_quantity(Quantity q) { speed_reading_ = q != Quantity::back_emf_volts; }
  std::vector<RunEvent> take_events();
  bool has_events() const { return !events_.empty(); }
  State state() const { return state_; }
  std::size_t samples_seen() const { return store_.end(); }
  std::size_t buffered() const { return store_.size(); }

 private:
  // Least-squares line over a sliding time window of the buffer, O(1) per sample (window_fit.hpp).
  using WindowFit = spindown::WindowFit;

  // The samples held (sample_store.hpp).
  using Sample = SampleStore::Sample;
  double t(std::size_t i) const { return store_.t(i); }
  double v(std::size_t i) const { return store_.v(i); }
  // Moves w on to end at sample i (s), reading older samples from ring. Static, with the ring
  // passed in: a window that is a local of a loop then stays in registers.
  static inline void advance(WindowFit& w, const Sample* ring, std::size_t mask, std::size_t i, Sample s);
  inline void advance(WindowFit& w, std::size_t i, Sample s);
  void rebuild(WindowFit& w, std::size_t from, std::size_t to);
  void reset_window(WindowFit& w, std::size_t lo, std::size_t end);
  double duration(const WindowFit& w) const;
  void trim_idle();
  // prev_t: the time of the sample before s (-inf at a stream's start).
  void idle_step(std::size_t i, Sample s, double prev_t);
  inline void coast_step(std::size_t i, Sample s, double prev_t);
  // push_many's loop over samples [k, n) while coasting: push() for each, on local copies of the
  // state it touches, up to the first sample that decides something (taken) or that push()
  // alone handles (not taken). Returns the index of the first sample it did not take.
  std::size_t coast_run(const double* t_s, const double* value, std::size_t k, std::size_t n);
  template <bool LongLive>
  std::size_t coast_loop(const double* t_s, const double* value, std::size_t k, std::size_t n);
  inline void coast_checks(std::size_t i, Sample s, bool at_end = false);
  // What the coast checks read and a coast does not change, as one value: coast_loop keeps it
  // in locals, since a store into the ring (doubles) could alias any double member and the
  // compiler would reload each of them for every sample.
  struct CoastLimits {
    const Sample* ring;
    std::size_t mask, base, max_buffer, cut_index;
    double max_coast_s, t_cut_s, hold_half_s, hold_full_s, rise_jump, standstill_ceiling, v0, plateau_check_t;
  };
  CoastLimits coast_limits() const {
    return {store_.data(), store_.mask(), store_.base(), opt_.max_buffer, run_.cut_index, opt_.max_coast_s, run_.t_cut_s, hold_half_s_,
            hold_full_s_, rise_jump_, standstill_ceiling_, v0_, plateau_.next_look_s()};
  }
  // What the checks of a coasting sample decided: nothing (the usual case), or one of the rare
  // outcomes, which act_on() carries out.
  struct CoastVerdict {
    enum What { go_on, too_long, power_back, level, plateau } what = go_on;
    double mu = 0, sxx = 0, e = 0;  // level: the hold window's mean, Sxx and residual sd
  };
  inline CoastVerdict coast_verdict(std::size_t i, Sample s, const WindowFit& h, double& level_min, int& rising,
                                    const CoastLimits& c);
  void act_on(const CoastVerdict& v, std::size_t i, bool at_end);
  inline void track_repeats(std::size_t i, double value, std::size_t& same_start, double& last_v);
  void time_went_back(double t_s);     // the note, then clock_restart()
  void coast_too_long(std::size_t i);  // max_buffer or max_coast_s reached
  void power_back();                   // the reading rose again before standstill
  void standstill_checks(std::size_t i, bool at_end, double mu, double sxx, double e);
  void tail_step(std::size_t i, Sample s);
  // Whether the tail up to sample i still falls clearly: the stop was no stop.
  bool still_falling(std::size_t i) const;
  // Back to coasting from the tail at sample i (s), with a note.
  void retract_stop(std::size_t i, Sample s);
  inline bool confirms_decline(const WindowFit& w) const;
  // Whether w, rough about its line but falling drop, is a smooth curve (a short fast coast).
  [[gnu::cold, gnu::noinline]] bool smooth_curve(const WindowFit& w, double mu, double drop) const;
  // Whether w shows a standstill: full, low, and no significant slope or drop.
  bool flat(const WindowFit& w) const;
  // The part of flat() after "full": low, no significant slope or drop, for w of duration d and
  // mean m, in a coast cut at reading v0. Sets sxx and e (w.sxx(), w.resid_sd()) for the
  // caller's resolution test.
  static inline bool level(const WindowFit& w, double d, double m, double v0, double& sxx, double& e);
  // Whether w's slope is certainly too strong for level() (mean m, coast cut at v0), decided
  // without its divisions and square roots.
  static inline bool clearly_sloped(const WindowFit& w, double v0, double m);
  // Where the cut lies in [a, b] (b = newest sample), and what came before it.
  using CutSplit = spindown::CutSplit;  // lead_in.hpp
  // A powered plateau that runs into the coast without a step (a speed reading: the speed is
  // continuous at the cut): the cut is where a level and the coast's line meet, found to a tenth of
  // a period by least squares over the samples around it, not the sample split of split_at_cut
  // (which lets the line start with a step, so noise moves it by samples). Leaves sp as it is when
  // the two do not meet within a few samples of the split.
  void refine_plateau_cut(CutSplit& sp, std::size_t b);
  // split_at_cut's steps: a reading pinned at the converter's top and left (true, sp filled), else
  // the best two-segment least-squares split (two_segment_split.hpp), then the lead-in's description.
  CutSplit split_at_cut(std::size_t a, std::size_t b, const WindowFit& w);
  bool split_at_top(CutSplit& sp, std::size_t a, std::size_t b, const WindowFit& w);
  std::vector<double> split_scratch_;  // the split's sums
  void split_two_segments(CutSplit& sp, std::size_t a, std::size_t b, const WindowFit& w);
  // Samples of contact bounce at the start of the coast in sp (a wire pushed onto the pin), judged
  // against the line of w (the window that confirmed the coast): the cut moves to the first of
  // them, and they go to bounce_ (left out of the fit).
  void take_bounce(CutSplit& sp, const WindowFit& w);
  std::vector<std::size_t> bounce_;  // the open run's bounce samples, ascending
  // Why the open coast, closed by a rise at sample at, was a swing of an open (floating) input and
  // no coast: the readings before its cut swung up and down as much; empty when it was a coast.
  std::string swing_reason(std::size_t at) const;
  // Why the open coast, closed by a rise at sample at, was no coast: it levelled off well above
  // standstill, where friction would still slow it; empty when it kept falling as a coast does.
  std::string stall_reason(std::size_t at) const;
  // A coast never holds a plateau: friction slows it at every speed it passes. Whether the open
  // coast, high above standstill at sample i, has held level (hold_) where friction would still
  // take speed off fast, three times in a row (a second and more): then its fall was a drive stepping down under power (a
  // setpoint step, a start-up overshoot settling), and the coast is given up (ignored, with why),
  // its plateau the next cut's lead-in. Checked every half hold window.
  bool held_plateau(std::size_t i);
  PlateauWatch plateau_;  // the decision (plateau_watch.hpp)
  std::string not_coast_;  // set: the open run is ignored with this warning when it completes
  // Every re-cut of the closed coast r (ending at sample end), in order (run_detector_recut.cpp):
  // the one place a cut moves after it was found.
  void recut_coast(Run& r, std::size_t end);
  // The noise of the coast [c, coast_end) at every lag, the quieter (less wander) of its two
  // halves' (an open pin's hum before a connection is in one of them only). Kept for the re-cuts of
  // one recut_coast call, which ask it of the same coast (coast_noise_for_: its c and coast_end).
  const LagNoise& coast_noise(std::size_t c, std::size_t coast_end);
  LagNoise coast_noise_;
  std::optional<std::pair<std::size_t, std::size_t>> coast_noise_for_;
  // A coast never rises: when the reading rose inside r's coast [cut, coast_end) by far more than its
  // noise, what came before the rise was no part of it (an open pin's swing before it was connected,
  // a coast the power came back on unseen). r then starts at the last such rise, with a warning.
  void recut_after_rise(Run& r, std::size_t coast_end);
  // Friction only takes speed off: a coast never comes back to the level it began at. When the
  // reading inside r's coast [cut, coast_end), long after the cut, stood at the cut's level again
  // (within its means' noise) where the coast's own pace says it must have fallen far below it, no
  // coast had begun (a drive hunting about its setpoint): r starts after the last such return.
  void recut_after_return(Run& r, std::size_t coast_end);  // the decision: level_return.hpp
  std::vector<double> return_scratch_;
  // r's cut moved to the coast after sample `at` inside it, found as any cut is: the samples up to
  // back_search_s before it (at least min_lead) as lead-in, ahead_s after it; false when there is
  // no such cut after r's (r unchanged).
  bool recut_from(Run& r, std::size_t at, std::size_t coast_end, double ahead_s, std::size_t min_lead);
  // A coast never dwells: when the reading inside r's coast [cut, coast_end) held a level far
  // longer than the coast then took to fall through it (the decision: coast_dwell.hpp), r starts
  // after that dwell, with a warning.
  void recut_after_dwell(Run& r, std::size_t coast_end);
  std::vector<double> dwell_scratch_;
  // Why the coast in sp has no recorded cut (the stream begins on it, or a pause hides it), with
  // sp moved to the coast's first sample; empty when its cut is in the data.
  std::string start_not_seen(CutSplit& sp);
  // Whether a standstill or floor z (spread sd_z, of a coast falling amp) sits on one value of a
  // quantized reading a step or more above the motor's reading at rest (rest_level_).
  bool quiet_dwell_above_rest(double z, double sd_z, double amp) const;
  // When the coast cut at `cut` crossed `quarter` for the last time before first_in (interpolated).
  double last_quarter_time(std::size_t cut, std::size_t first_in, double quarter) const;
  // Whether a coast from t_cut that crossed its last quarter at t_quarter and reached its floor at
  // t_stop creeps in as an exponential does, rather than stopping (the decision: stop_shape.hpp,
  // with the open run's stop_approach_t_ and stop_floor_t_).
  bool creeps_in(double t_cut, double t_quarter, double t_stop) const;
  // The same for a coast found while after_silence_: the silenced coast's rest, from the first
  // sample after the silence; empty only when nothing of it is held.
  std::string rest_after_silence(CutSplit& sp);
  // Whether the coast found in sp follows a rise straight into its peak (a spin-up): a rise after
  // the cut moves the cut to the peak.
  // rising_lead: the lead-in is known to rise into the cut (judged against the finer noise).
  bool at_peak(CutSplit& sp, std::size_t b, bool rising_lead = false);
  // Whether the open coast starts held at the converter's top (pin_level_, with a warning), seen up
  // to sample b; every reading of the coast at that level is then left out of its fit.
  void find_pinned_start(std::size_t b);
  // Whether the powered lead-in in sp sits at the converter's top (seen up to sample b): the cut
  // moved to where the reading first comes down, pin_level_ set.
  bool pinned_lead_in(CutSplit& sp, std::size_t b);
  // Where a level that a rise reached at r ends, after its peak p (b: the newest sample looked at):
  // p when no level is shown there.
  std::size_t level_end(std::size_t r, std::size_t p, std::size_t b);
  // At a run's close: a spin-up's coast re-cut where the level after its peak ends.
  void recut_at_level_end(Run& r, std::size_t coast_end);
  bool try_start_coast(std::size_t i, const WindowFit& w);
  // The hold window ending at sample i is a standstill: where it began, when the coast met it, and
  // whether that is a stop (stop_at) or an exponential's floor (close_asymptotic), in these steps.
  void found_standstill(std::size_t i, bool at_end);
  // The first sample of the standstill at level z (within band) that holds the window ending at i.
  std::size_t standstill_start(std::size_t i, double z, double band) const;
  // When the approach line (the last ≤2 s of [k, end), end <= first_in the standstill's first
  // sample) meets the zero level z, within [t_quarter, t(i)]; t(first_in) when no falling line is there.
  double approach_meets_zero(std::size_t first_in, std::size_t end, std::size_t k, double z, double t_quarter,
                             std::size_t i) const;
  // The open run's first sample at or after t_hit, at most i.
  std::size_t first_sample_from(double t_hit, std::size_t i) const;
  // A stop at sample stop that falls in a pause of the recording: the run's note says so.
  void note_stop_in_pause(std::size_t stop);
  // The run stopped at sample stop (standstill z, spread sd_z, coast falling amp): into its tail.
  void stop_at(std::size_t i, std::size_t stop, double z, double sd_z, double amp);
  // The coast crept into its floor z as an exponential does: closed, never stopped, at sample i
  // (unless a held last reading is still to be judged).
  void close_asymptotic(std::size_t i, bool at_end, double z, double sd_z, double amp, double end_rate);
  // At a standstill found at sample i (its first sample first_in, level z, the coast's amplitude
  // amp): whether the reading collapsed to it from a held value faster than friction allows, the
  // sensor giving up; if so the run is closed there, never stopped.
  bool signal_lost(std::size_t i, std::size_t first_in, double z, double amp);
  void tail_ends_by_time(std::size_t upto);
  void close_unstopped(std::size_t end, const std::string& why, Run::End reason);
  void restart_stream(const std::string& why, Run::End reason);  // clock_restart(), new_source()
  void complete_run(std::size_t end);
  // Why the finished coast r (falling amp in coast_s) is a fragment and not a run: too small for
  // the reading's resolution, or small and short beside the runs found before it in this stream;
  // empty when it is a run.
  std::string fragment_reason(const Run& r, double amp, double coast_s) const;
  // Why a stopped coast falling amp in coast_s is small beside runs of up to largest_amp and
  // longest_s; empty when it is not.
  static std::string small_beside(double amp, double coast_s, double largest_amp, double longest_s);
  // Runs accepted before r (falling amp in coast_s) that r shows to be fragments: a warning each.
  void warn_of_earlier_fragments(const Run& r, double amp, double coast_s);
  // A stopped run whose standstill is one value held far longer than the coast's values: a warning.
  void warn_of_held_standstill(const Run& r);
  // Whether the readings up to end (of a coast cut at cut) end on one value held exactly, well above
  // the motor's zero and reached by a jump of many steps (a per-revolution counter's last update),
  // and (need_long) held five times longer than any value of the coast before it: a sensor
  // keeping its last reading. held_from: where it began; longest: the longest value before it.
  bool held_last_value(std::size_t cut, std::size_t end, std::size_t& held_from, std::size_t& longest,
                       bool need_long) const;
  struct Earlier {
    int number;
    double t_cut_s, amp, coast_s;
    bool stopped, warned;
  };
  static constexpr std::size_t max_earlier = 16;  // the last runs remembered for that
  std::vector<Earlier> earlier_;
  // r's coast [cut, coast_end) in one pass: its longest silence (said by warn_of_gap_in_coast)
  // and the single samples that are not the motor's (into r.outliers, with a warning).
  void scan_coast(Run& r, std::size_t coast_end);
  // The longest silence in a coast from sample from, before sample at (0: none), longest seconds.
  void warn_of_gap_in_coast(int number, std::size_t from, std::size_t at, double longest, double period_s);
  std::string gap_before(std::size_t i) const;  // "no samples for … s mid-coast (from … to …)", before sample i
  // Idle from sample lo on (windows start there); the lead-in search may reach back to search_from
  // (lo when not given).
  void to_idle(std::size_t lo, bool need_quiet, std::size_t search_from = SIZE_MAX);
  void emit_diag(Diagnostic::Severity sev, std::string msg);
  // An event of the open run (its cut, its stop), as the run stands now.
  void emit_run_event(RunEvent::Kind kind);
  double median_of(std::size_t from, std::size_t to);
  // Whether samples [from, to) rise steadily: a line's slope far beyond its error, and no hum.
  bool rises_steadily(std::size_t from, std::size_t to) const;
  // The median of the sample periods in [from, to) (at least two samples), as nth_element picks it.
  double median_period(std::size_t from, std::size_t to);
  // For the m periods ending at p[0..m) (the first one starting at prev, which becomes the time of
  // p[m-1]), adds how many are below guess and how many at or below it.
  static void count_periods(const Sample* p, std::size_t m, double guess, double& prev, std::size_t& below,
                            std::size_t& at_or_below);

  RunOptions opt_;
  std::string source_;
  State state_ = State::idle;
  SampleStore store_;
  std::size_t time_cursor_ = 0;  // first buffered sample within the idle keep time
  std::size_t lo_ = 0;          // earliest index a window that confirms a coast may start at
  std::size_t search_lo_ = 0;   // earliest index the current lead-in search may use (<= lo_): after a
                                // rise that closed a coast, what came before the rise is lead-in too
  double pin_level_ = std::numeric_limits<double>::quiet_NaN();  // the open coast's converter top
  std::size_t stream_start_ = 0;  // first index after the stream start / last clock restart
  bool stream_after_restart_ = false;  // that stream began at a clock restart (not a new source)
  std::size_t resume_index_ = 0;  // first sample after the last pause (over 2 s) while idle
  double resume_pause_s_ = 0;     // that pause's length
  bool need_quiet_ = false;     // after a closed coast: no new run until the decline pauses
  bool need_rise_ = false;      // after a stop: a new coast must start above rise_level_
  double rise_level_ = 0;
  double block_band_ = 0;  // > 0: rise_level_ follows the lowest reading since, plus this
  // After a coast closed before its stop at reading level: no new run until the reading rises
  // well above it, or above the lowest it shows since (a new spin-up from rest).
  void block_until_rise(double level);
  double last_t_ = -std::numeric_limits<double>::infinity();  // -inf: no sample since the (re)start
  double last_v_ = std::numeric_limits<double>::quiet_NaN();  // the last sample's value; NaN: none since (re)start
  std::size_t non_finite_ = 0;
  std::size_t same_start_ = 0;  // first of the current run of identical readings
  std::size_t plateau_start_ = 0, plateau_end_ = 0;  // last long positive plateau (clipping?)
  bool have_plateau_ = false;
  int accepted_ = 0;
  double largest_amp_ = 0, longest_coast_s_ = 0;  // of the runs accepted so far (fragments are judged by them)

  WindowFit short_{0.25}, long_{1.0}, vlong_{4.0};  // confirm a decline
  WindowFit hold_{1.0}, hold_long_{3.0};            // confirm a standstill
  double hold_half_s_ = 0.5, hold_full_s_ = 0.9;     // hold_ durations: 0.5 and 0.9 of its span
  // A slow logger: when confirm_min_samples periods in a row are longer than slow_period_, the
  // windows' spans are widened to hold enough samples (set_spans), and slow_period_ becomes the
  // period that would widen them further. slow_last_: the last sample after such a period. A coast
  // sets the spans from its confirming window's shortest period (a stream may change its rate).
  double slow_period_ = 0;
  double slow_longest_ = 0;
  std::size_t slow_count_ = 0, slow_last_ = SIZE_MAX;
  void set_spans(double period_s);
  double shortest_period(const WindowFit& w) const;  // between two of w's samples (0: fewer than two)
  // Sample i came dt after the one before, longer than slow_period_ (and no pause).
  [[gnu::cold, gnu::noinline]] void follow_slow_period(std::size_t i, double dt);
  bool hold_long_live_ = false;
  bool creeping_ = false;
  double rest_level_ = std::numeric_limits<double>::infinity();  // the lowest level held while idle (idle_step)
  bool floor_doubt_ = false;  // the standstill may be a quiet reading's dwell on one step (found_standstill)
  double tail_until_s_ = 0;   // the tail ends then (t_stop + tail_s, longer on floor_doubt_)
  double stop_approach_t_ = 0;  // found_standstill's approach t-value of the run's standstill
  double stop_floor_t_ = 0;     // … and the t-value of the rate it met its floor at (floor_rate_t)
  bool speed_reading_ = false;        // a speed sensor's reading (set_quantity): its zeros are the motor at rest
  bool restarted_mid_coast_ = false;  // the clock restarted while a coast was open: its rest is a fragment
  bool joined_stream_ = false;        // the samples began part-way into a stream (joined_stream())
  // A coast closed by went_silent(): until the reading rises above silence_level_ +
  // silence_band_ or holds still low, a coast found is that one's rest (partial, no cut).
  bool after_silence_ = false;
  int silenced_run_ = 0;
  double silence_level_ = 0, silence_band_ = 0, silence_s_ = 0;
  void watch_after_silence(double v);  // idle: releases after_silence_ when the coast is over
  bool fragment_ = false;             // the open run is such a rest: ignored when complete  // the coast was seen approaching standstill asymptotically
  double quiet_until_s_ = -std::numeric_limits<double>::infinity();  // after a rejected cut

  // The open run.
  Run run_;
  std::string run_note_;  // said with the run when it completes, at run_note_severity_
  Diagnostic::Severity run_note_severity_ = Diagnostic::Severity::note;
  double v0_ = 0;          // reading at the cut (start of the coast line)
  double standstill_ceiling_ = 0;  // a hold-window mean above it is not low yet (0.3 v0_, or inf if v0_ <= 0)
  double coast_sd_ = 0;    // coast noise near the cut
  double coast_step_ = 0;  // the reading's smallest step near the cut (its quantization; 0 if none seen)
  double lead_in_zero_ = 0;  // mean reading of a "zeros" lead-in (the motor at rest); NaN for other lead-ins
  // The motor's zero reading: the lead-in's when it showed the motor at rest, else 0.
  double motor_zero() const { return std::isfinite(lead_in_zero_) ? lead_in_zero_ : 0.0; }
  double rise_jump_ = 0;   // a reading this far above level_min_ is power coming back
  double level_min_ = 0;   // lowest hold-window mean seen in this coast
  int rising_ = 0;         // consecutive samples far above level_min_ (power back?)
  std::size_t rise_start_ = 0;
  double depart_band_ = 0; // tail: how far from zero_level counts as leaving standstill
  int departing_ = 0;
  std::size_t depart_start_ = 0;

  std::vector<RunEvent> events_;
  // Work space for medians and the cut search, grown (never shrunk, never zeroed) as needed.
  double* scratch(std::size_t size);
  std::unique_ptr<double[]> scratch_;
  std::size_t scratch_size_ = 0;
  std::vector<double> median5_;  // recut_after_rise: each coast sample's median of five
};

}  // namespace spindown
