#pragma once
// The streaming run detector: fed one sample at a time (live fitter) or every sample of a
// recording (find_runs), it finds each spin-down — the power cut, the coast, the stop — and
// emits events as it decides. Memory is bounded: in the lead-in it keeps only a few seconds,
// during a coast at most RunOptions::max_buffer samples.
//
// How it decides (all thresholds relative to the data's own level and noise):
//  * a coast is confirmed when a trailing window (0.25 s, 1 s or 4 s; a slow logger's 4-s window
//    and hold windows widened to hold enough readings) shows a smooth, significant decline (slope
//    t-statistic, roughness relative to the level);
//  * the cut is then located by a two-segment least-squares split of the last seconds
//    (constant lead-in | linear coast start), which finds both steps (zeros, floating pin,
//    supply) and kinks (powered motor at steady speed); a reading pinned at its maximum
//    (ADC top) is skipped: the coast starts where it leaves it;
//  * the stop is the start of a stop_hold_s window that is flat (no significant slope) and low;
//    the zero level and noise come from that standstill, the stop time from the approach line;
//  * a coast that approaches standstill asymptotically (pure viscous) is not a stop: it is
//    closed, never stopped, once even the long window sees no decay;
//  * a cut needs a visible change (step or kink) unless the stream starts mid-coast, and after a
//    stop a new coast must start above the standstill.
// Latency: a cut is announced ~0.25–1 s after it (4 s for very slow, noisy coasts), a stop
// ~stop_hold_s after it (up to 3·stop_hold_s when the noise hides a slow final decline), a run
// tail_s after its stop.
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "spindown/quantity.hpp"
#include "spindown/recording.hpp"
#include "spindown/runs.hpp"

namespace spindown {

struct RunEvent {
  enum class Kind {
    cut,         // a coast started: run has number, cut_index, t_cut_s, lead_in
    stop,        // standstill reached: run also has stop_index, t_stop_s, zero_level. Provisional:
                 // if the reading keeps falling during the tail, a diagnostic says the stop was
                 // retracted and a later stop event follows
    complete,    // the run is final (tail collected, or closed without a stop)
    ignored,     // a coast too short or otherwise unusable; diagnostic says why
    diagnostic,  // a note or warning not tied to a finished run (clipping, bad samples…)
  };
  Kind kind = Kind::diagnostic;
  Run run;                // valid for cut/stop/complete/ignored
  Diagnostic diagnostic;  // valid for ignored/diagnostic (and notes on complete runs)
  bool has_diagnostic = false;
};

class RunDetector {
 public:
  enum class State { idle, coasting, tail };

  explicit RunDetector(RunOptions opt = {}, std::string source = {});
  ~RunDetector();
  RunDetector(RunDetector&&) noexcept;
  RunDetector& operator=(RunDetector&&) noexcept;

  // One sample; its index is the number of push() calls before it. Non-finite samples are
  // counted (reported by finish()) and otherwise ignored; time going backwards is taken as
  // a clock restart.
  void push(double t_s, double value);
  // n samples, exactly as n calls of push() would take them (same arithmetic, same events).
  // A whole recording's samples go through here (find_runs): the ordinary coasting sample, most
  // of a recording, runs in a loop on local copies of the state it changes, written back once.
  void push_many(const double* t_s, const double* value, std::size_t n);
  // The device clock restarted before the next sample: an open run is closed there.
  void clock_restart();
  // Another source took over the stream before the next sample (a restarted bridge, a replugged
  // board: SampleStream's new_source): like clock_restart(), an open run is closed there with why
  // as its reason (End::new_source).
  void new_source(const std::string& why);
  // End of the stream: an open coast is closed (never stopped), a tail is cut short.
  void finish();
  // Live: no sample came for silent_s (host time). An open coast is closed there (End::silent,
  // a warning), a tail is cut short; samples that come after are found afresh. A coast that goes
  // on after the silence (the samples resume on the same clock: an outage, a frozen fitter) is
  // that run's rest: partial, never given a cut, until the reading shows the coast is over (it
  // rises above where the silence began, or holds still at a standstill). Nothing happens when idle.
  void went_silent(double silent_s);
  // Live, before the first sample: the samples begin in a stream already under way (a listener
  // that joined a bridge's stream part-way: its first sequence number is not the stream's first).
  // A cut found within the first samples with a lead-in too short to judge is then no cut: the
  // coast's start was not seen (a fitter restarted, or slow to start, late in a coast).
  void joined_stream();
  // What the reading is (before the first sample; find_runs gives the recording's). A speed
  // sensor (rpm, rad/s) reads the motor all the time: zeros before a step are the motor at rest,
  // never the handout's A0 left unconnected until the cut (step 6) that a back-EMF reading may show.
  void set_quantity(Quantity q);

  // Events since the last call, oldest first.
  std::vector<RunEvent> take_events();
  bool has_events() const;

  State state() const;
  std::size_t samples_seen() const;
  std::size_t buffered() const;

 private:
  // The detector's state and its decisions' steps (run_detector_impl.hpp, private to the runs
  // module: run_detector*.cpp).
  class Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace spindown
