#pragma once
// Finding spin-down runs in a recording: the power cut (the reading before it may sit at 0,
// float on an unconnected pin, or sit at the supply voltage) and the stop (speed reaches
// zero and stays). One streaming detector serves both the offline readers (find_runs feeds
// it every sample) and the live fitter (feeds it as samples arrive), so both find the same
// runs; its memory is bounded.
#include <cstddef>
#include <functional>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "spindown/recording.hpp"

namespace spindown {

struct RunOptions {
  double stop_hold_s = 1.0;        // reading must stay at the zero level this long to call a stop
  double min_coast_s = 0.5;        // shorter coasts are reported and ignored
  std::size_t min_samples = 8;     // fewer coasting samples: reported and ignored
  double max_coast_s = std::numeric_limits<double>::infinity();  // live: a memory bound (the fitter sets 600 s);
                                   // a coast that has not stopped by then is closed as "never stopped"
  double tail_s = 2.0;             // standstill kept after the stop for the fit (pins the stop)
  std::size_t max_buffer = 200000; // samples buffered per stream (bounded memory)
  bool is_valid(std::string* why) const;
};

struct Run {
  int number = 0;                  // 1-based, in order of the cut
  std::size_t cut_index = 0;       // first coasting sample (index into the recording/stream); after a
                                   // clipped (pinned) start, the first sample below the clip
  std::size_t stop_index = 0;      // first sample at standstill (== end_index if never stopped)
  std::size_t end_index = 0;       // one past the last sample given to the fit (tail included)
  double t_cut_s = 0;              // estimated cut: midway between last powered and first coasting sample
                                   // (with clipping: midway into the pinned stretch, the real cut)
  double t_stop_s = std::numeric_limits<double>::quiet_NaN();  // device time of the stop (= t of stop_index)
  bool stopped = false;
  double zero_level = 0;           // reading at standstill (median of the stopped tail; for an
                                   // asymptotic coast its floor; 0 when the coast was cut short)
  double noise_level = 0;          // standard deviation of the reading at standstill
  std::string lead_in;             // "zeros", "floating", "supply", "powered", "spin-up" (a rise straight into
                                   // the peak), "none" (the cut was not recorded: the coast is partial)
  double period_s = 0;             // median sample period within the coast
  // Why the fitted window ends where it does, and the device time of its last sample.
  enum class End {
    stopped,        // standstill reached (the tail after it is in the window)
    signal_lost,    // the reading collapsed or froze faster than friction allows: the sensor gave up
    gap,            // a pause in the recording mid-coast
    end_of_data,    // the recording ends (or the stream was closed) mid-coast
    cap,            // max_coast_s reached (a live memory bound)
    power_back,     // the reading rose again before standstill
    clock_restart,  // the device clock restarted (reset, reconnect)
    asymptotic,     // the decay was lost in the noise before a stop (pure viscous)
    silent,         // live: the bench sent no samples for FitterOptions::silent_s mid-coast
    new_source,     // another source took over the bench's stream (a restarted bridge, a replugged board)
  };
  End end = End::end_of_data;
  double t_end_s = std::numeric_limits<double>::quiet_NaN();
  std::vector<std::size_t> outliers;  // single samples in the coast that are not the motor's (dropouts,
                                      // glitches): left out of every fit, ascending
  bool partial() const { return lead_in == "none"; }
};

// The name of why a run's window ends, as text and JSON say it ("stopped", "signal lost", …).
const char* end_name(Run::End e);
// The reason named by end_name(), or end_of_data for a name it does not give.
Run::End end_from_name(std::string_view name);

struct Segmentation {
  std::vector<Run> runs;
  std::vector<Diagnostic> diagnostics;  // runs ignored and why, clipping, etc.
};

// Feeds every sample to a RunDetector (run_detector.hpp), restarting it at each
// rec.clock_restarts index, so the live fitter finds the same runs. Runs that never stop are
// returned with stopped=false and a note in diagnostics.
Segmentation find_runs(const Recording& rec, const RunOptions& opt = {});

}  // namespace spindown
