#pragma once
// One spindown-avr-bench session: the sketch on the emulated Uno, its UART on a pty, A0 from
// the motor simulator, the faults on the emulated clock, until the motor's runs are done.
#include <string>
#include <vector>

#include "spindown/emulated_motor.hpp"

namespace spindown {

struct AvrBenchOptions {
  EmulatedMotorOptions motor;
  std::string firmware;    // the sketch: .elf or .hex
  std::string link;        // symlink to the pty's path ("" none)
  std::string truth_file;  // the truth JSON ("" none)
  double speed = 1.0;      // at most this many emulated seconds per wall second; 0 = unpaced
  double wait_reader_s = 30, linger_s = 1.0;
  double unplug_at_s = -1, unplug_for_s = 1.0;  // the cable pulled (emulated seconds; < 0 never)
  double f_cpu = 16e6;
  std::vector<double> reset_at_s;  // emulated seconds of the board's resets
};

// The exit code: 0 done (or stopped by a signal), 1 nobody opened the port or the firmware
// stopped, 2 the firmware or the motor could not be set up.
int run_avr_bench(const AvrBenchOptions& options);

}  // namespace spindown
