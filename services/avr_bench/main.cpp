// spindown-avr-bench: a compiled bench sketch on an emulated Arduino Uno (simavr, ATmega328P at
// 16 MHz), its UART on a pseudo-terminal like a USB serial port, A0 driven by spindown's motor
// simulator on the emulated clock. Prints the pty's path (and links it with --link), waits for
// a reader (the Uno boots when its port is opened), runs the motor's runs and exits.
// services/avr_bench/README.md says what it models and how time is paced; avr_session.hpp runs it.
#include <CLI/CLI.hpp>
#include <string>

#include "avr_session.hpp"
#include "spindown/virtual_bench_cli.hpp"

namespace {

void add_options(CLI::App& app, spindown::AvrBenchOptions& o, std::string& lead_in) {
  spindown::EmulatedMotorOptions& m = o.motor;
  app.add_option("--firmware", o.firmware, "the sketch: .elf or .hex from deploy/firmware (make -C deploy/firmware)")->required();
  app.add_option("--link", o.link, "symlink to the pty's path (like /dev/ttyACM0)");
  app.add_option("--truth", o.truth_file, "write parameters, cut/stop times, resets and the emulator's speed as JSON");
  app.add_option("--speed", o.speed, "at most this many emulated seconds per wall second; 0 = as fast as the emulator runs")
      ->check(CLI::Range(0.0, 1e6));
  app.add_option("--wait-reader", o.wait_reader_s, "seconds to wait for a reader to open the pty");
  app.add_option("--linger", o.linger_s, "seconds to keep the pty open after the last run");
  app.add_option("--f-cpu", o.f_cpu, "crystal (Hz)")->check(CLI::Range(1e6, 32e6));
  app.add_option("--runs", m.runs, "runs: powered, cut, coast, stop, rest");
  app.add_option("--first-run-s", m.first_run_s, "emulated seconds from the first boot to the first run");
  app.add_option("--lead-in-s", m.lead_in_s, "seconds powered before each cut");
  app.add_option("--lead-in", lead_in, "what A0 reads while powered")->check(CLI::IsMember({"zeros", "supply"}));
  app.add_option("--supply", m.supply_v, "A0 while powered with --lead-in supply (V)");
  app.add_option("--tail-s", m.tail_s, "seconds at rest after each stop");
  app.add_option("--idle", m.idle_s, "more seconds at rest before the next run");
  app.add_option("--max-coast-s", m.max_coast_s, "longest coast");
  app.add_option("--e0", m.e0_v, "back-EMF at the cut (V)");
  app.add_option("--e0-step", m.e0_step_v, "added to e0 at each further run (V)");
  spindown::add_motor_options(app, m.bench, m.friction);
  app.add_option("--noise", m.noise_v, "white noise on A0 (V)");
  app.add_option("--seed", m.seed, "random seed of the noise");
  app.add_option("--reset-at", o.reset_at_s, "emulated seconds at which the board resets (reset button, a DTR pulse; repeatable)");
  app.add_option("--unplug-at", o.unplug_at_s, "emulated seconds at which the USB cable is pulled (the pty goes away)");
  app.add_option("--unplug-for", o.unplug_for_s, "emulated seconds it stays out (then a new pty; the board boots when it is opened)");
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"spindown-avr-bench: a bench sketch on an emulated Arduino Uno (simavr), UART on a pty, A0 from the motor simulator"};
  spindown::AvrBenchOptions o;
  std::string lead_in = "zeros";
  add_options(app, o, lead_in);
  CLI11_PARSE(app, argc, argv);
  o.motor.lead_in_supply = lead_in == "supply";
  o.motor.adc_bits = 10;
  o.motor.adc_ref_v = 5.0;
  return spindown::run_avr_bench(o);
}
