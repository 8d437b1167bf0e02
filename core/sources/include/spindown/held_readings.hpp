#pragma once
// A slow channel written in every row of a faster log (a drive's 10 Hz speed over CAN in a DAQ's
// 1 kHz rows, a display logged faster than it updates): each reading is held, unchanged, for many
// rows until the next one arrives. Counted row by row, one reading weighs as much as a hundred, the
// noise looks a hundred times smaller than it is, and the sample period is the rows', not the
// readings'. This finds such a channel from the values alone and keeps each reading once.
#include <cstddef>

#include "spindown/recording.hpp"

namespace spindown {

// The channel is held when even its fastest changes come only every few rows: the shortest holds
// (the 2nd percentile of the lengths of runs of one value, the first and last runs aside) last 3
// rows or more. A quantized reading of a coast is not held: where the coast falls fast it changes
// from row to row. The readings' period P is the lower quartile of the holds' durations (most
// readings differ from the one before: a hold is one reading, sometimes two equal ones).
// Keeps each row where the value changes, and within a longer hold one row every P (a standstill
// read at 0 for a minute is still a minute of readings); the rest are dropped, and a warning on the
// recording says how many and why. Clock-restart indices follow the rows kept. Returns the rows
// dropped (0: not held, the recording unchanged).
std::size_t take_held_readings_once(Recording& rec);

}  // namespace spindown
