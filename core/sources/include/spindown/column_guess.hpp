#pragma once
// Which columns of a table whose header does not say are the time and the speed, from the numbers
// alone, for an error that proposes them as options ready to paste:
//  - the time rises steadily (nearly every row later than the one before, at a steady step); its
//    unit from its step and span: whole numbers stepping by 1 or more are a millis() count (µs
//    from steps of 5000), fractions are seconds. A column counting 0, 1, 2… by exactly 1 is a
//    sample number rather than a time when another column rises steadily too.
//  - the speed (or back-EMF) rises and falls, or falls to a rest, over many samples and smoothly:
//    the smoothest such column. A column that drops to its rest in a sample or two (a motor
//    current, a relay) is not a coast.
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "spindown/column_names.hpp"

namespace spindown {

// A time column's unit from its values (the first 65 steps): whole numbers stepping by at least 1
// are ms, or µs from steps of 5000; anything else is s. *integral and *step say what was seen.
TimeUnit time_unit_from_values(std::span<const double> t, bool* integral = nullptr, double* step = nullptr);

struct ColumnGuess {
  int time = -1;   // 0-based; -1 when no column rises steadily
  TimeUnit time_unit = TimeUnit::s;
  std::string time_why;   // "rises steadily from 0 to 61.98 in steps of 0.02 (seconds)"
  bool time_counter = false;  // the time column counts 0, 1, 2… by exactly 1: a sample number, no clock
  int value = -1;  // 0-based; -1 when no column rises and falls or falls to a rest
  std::string value_why;  // "rises to 4.21 and falls to 0 over 1450 samples"
  double value_peak = 0;  // the value column's largest reading
};

// columns[c][row]: the table's numbers (NaN where a cell is not one), every column as long.
ColumnGuess guess_columns(const std::vector<std::vector<double>>& columns);

// "--time-column 1 --time-unit s --value-column 3" (1-based) and why, when the guess found both;
// nullopt otherwise. A peak reading above 30 (no back-EMF of the lab's motors) adds that the unit
// must be named too. A sample number is never proposed as a clock: the period is asked for
// (--period-ms) with the value column.
std::optional<std::string> column_proposal(const ColumnGuess& guess);

}  // namespace spindown
