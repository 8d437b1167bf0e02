#pragma once
// What a bench is doing, in the words of spindown-web's pages, from what `spindown watch`'s table
// (LabTable, lab_table.hpp) knows about it — its run's state from RUN, its bridge from STATUS —
// and what the web service saw on its SAMPLE channel (the time and value of the latest sample):
//
//   silent    no sample for silent_after_s (or never one)
//   coasting  the fitter's run is coasting (the cut was seen)
//   partial   the run is coasting or stopped but its cut was not seen (joined mid-coast)
//   powered   no run coasting and the reading is above standstill (supply on the pin, a spin-up)
//   stopped   the latest run stopped (the tail, the fit) and the reading is at standstill
//   idle      heard, no run yet (or the last one abandoned), the reading at standstill
//
// and the bridge's health: "silent" (no samples), "unplugged" (the bridge says disconnected),
// "replugged" (the bridge reconnected to its board since it started), "no heartbeat" (samples
// but no bridge STATUS lately), else "ok".
#include <cstdint>
#include <limits>
#include <string_view>

#include "spindown/lab_table.hpp"

namespace spindown {

enum class BenchState { idle, powered, coasting, stopped, partial, silent };
std::string_view bench_state_name(BenchState s);

// What the web service saw of one bench beside the table's row.
struct BenchActivity {
  std::int64_t last_sample_us = 0;  // host time of the latest sample (0: none yet)
  double last_value = std::numeric_limits<double>::quiet_NaN();
  std::int8_t quantity = 0;         // samples_t::QUANTITY_*
  double zero_level = 0;            // the reading at standstill (the latest FIT's), quantity unit
  std::int64_t reconnects = 0;      // the bridge's "reconnects" counter (its latest STATUS)
  std::int64_t last_status_us = 0;  // host time of the bridge's latest STATUS (0: none yet)
};

// The reading's distance from standstill above which the motor turns: 0.1 V of back-EMF (the
// lab sketch prints 0.01 V steps), 10 rpm, 1 rad/s.
double standstill_threshold(std::int8_t quantity);

// row may be null (a bench known from its bench file, never heard).
BenchState bench_state(const LabBenchRow* row, const BenchActivity& a, std::int64_t now_us, double silent_after_s);
std::string_view bridge_health(const LabBenchRow* row, const BenchActivity& a, std::int64_t now_us,
                               double silent_after_s);

}  // namespace spindown
