#pragma once
// The analog side of an emulated bench (spindown-avr-bench): the voltage the motor puts on the
// Arduino's A0 at any instant of the emulator's clock, run after run — powered (the pin reads 0 V
// or the supply), the power cut, the coast J·dω/dt = −T_f(ω) with the chosen friction terms, the
// stop, at rest — and the ATmega328P's 10-bit conversion of it. Unlike VirtualBench, which
// decides every byte in advance, this answers "what does A0 read now?" whenever the firmware
// starts a conversion, so the sketch's own loop timing, millis() and printing decide the bytes.
// The truth (truth_json) has the virtual bench's format (tests/integration and deploy/lab read
// both the same way); device times there come from the boots the caller reports.
#include <cstdint>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "spindown/bench.hpp"
#include "spindown/coast_simulator.hpp"
#include "spindown/friction.hpp"

namespace spindown {

struct EmulatedMotorOptions {
  int runs = 1;
  double first_run_s = 0.5;   // emulated seconds from the first boot to the first run's lead-in
  double lead_in_s = 3.0;     // powered before each cut
  bool lead_in_supply = false;  // false: the pin reads 0 V while powered (the lab's rig); true: supply_v
  double supply_v = 3.0;
  double tail_s = 2.0;        // at rest after each stop (or after max_coast_s)
  double idle_s = 1.0;        // more rest before the next run's lead-in
  double max_coast_s = 120.0;
  double e0_v = 2.8;          // back-EMF at the cut
  double e0_step_v = 0.0;     // run k starts at e0 + k·step
  BenchParams bench;
  FrictionTerms friction{1.822e-7, 1.1389e-4};
  double noise_v = 0.0;       // white noise on the pin (V, Gaussian), before the converter
  double adc_ref_v = 5.0;     // AVCC, the Arduino's default reference
  int adc_bits = 10;
  std::uint64_t seed = 1;

  bool is_valid(std::string* why) const;
};

class EmulatedMotor {
 public:
  explicit EmulatedMotor(EmulatedMotorOptions options);  // throws std::invalid_argument

  // The pin's voltage at emulated time t (seconds; calls must not go back in time).
  double volts_at(double t_s);
  // The count an ideal ATmega328P converter gives for v: ADC = V·2^bits/Vref, first transition
  // at ½ LSB (rounds to nearest), clamped to 0 … 2^bits − 1.
  int counts_for(double volts) const;
  // The conversion started at t: counts_for(volts_at(t)), counted for the truth.
  int convert(double t_s);

  // Emulated seconds when the last run's tail ends (the bench can stop there).
  double end_s() const { return end_s_; }
  struct RunTimes {
    double lead_in_s, cut_s, stop_s, end_s;  // emulated seconds
    double omega0, e0;
    bool stopped;
  };
  const std::vector<RunTimes>& runs() const { return runs_; }
  long conversions() const { return conversions_; }

  // The truth in VirtualBench's format. boots_s: emulated time of each boot of the board (the
  // first is epoch 0; each later one is a reset, a new clock epoch); a cut is stamped with the
  // device time (µs since the boot before it) and that epoch. extra is merged in (protocol, baud,
  // faults, the emulator's numbers).
  nlohmann::json truth_json(const std::vector<double>& boots_s, const nlohmann::json& extra = {}) const;

 private:
  EmulatedMotorOptions o_;
  std::vector<RunTimes> runs_;
  double end_s_ = 0;
  std::size_t run_ = 0;  // the run volts_at is in (or next)
  std::unique_ptr<CoastSimulator> coast_;
  double last_t_ = 0;
  long conversions_ = 0;
  std::mt19937_64 rng_;
  std::normal_distribution<double> noise_{0.0, 1.0};
};

}  // namespace spindown
