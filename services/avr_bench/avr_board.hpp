#pragma once
// An Arduino Uno in simavr: an ATmega328P at 16 MHz running a compiled sketch (ELF or Intel
// HEX), its UART0 captured byte by byte, host bytes fed to its receiver, and ADC0 answered by a
// callback at the moment the firmware starts each conversion. Time is the emulator's cycle
// counter (it never restarts, also not across resets). Only this file sees simavr's headers.
#include <cstdint>
#include <deque>
#include <functional>
#include <string>
#include <vector>

struct avr_t;
struct avr_irq_t;
struct avr_uart_t;

namespace spindown {

class AvrBoard {
 public:
  // adc0(t_s) → counts 0…1023 for a conversion of A0 started at emulated second t_s.
  using AdcSource = std::function<int(double t_s)>;
  // Throws std::runtime_error naming the file when it cannot be loaded.
  AvrBoard(const std::string& firmware_path, std::uint32_t f_cpu, AdcSource adc0);
  ~AvrBoard();
  AvrBoard(const AvrBoard&) = delete;
  AvrBoard& operator=(const AvrBoard&) = delete;

  // The reset pin pulled low and released (DTR on open, the reset button, power-on): the sketch
  // starts again from its first instruction, its RAM and peripherals cleared; bytes still in the
  // UART (not yet on the wire) are lost.
  void reset();
  // Runs until the cycle counter reaches `cycle`. False when the firmware stopped (crashed, or
  // slept with interrupts off): a real board would hang there too.
  bool run_until(std::uint64_t cycle);
  std::uint64_t cycle() const;
  std::uint32_t f_cpu() const { return f_cpu_; }
  double seconds() const { return double(cycle()) / f_cpu_; }

  // Bytes the UART put on the wire since the last call (in emulated-time order).
  std::string take_output();
  // Bytes from the host, fed to the receiver as its FIFO has room.
  void send_input(std::string_view bytes);
  // The rate the firmware set (UBRR0, U2X0), 0 before it set one.
  int uart_baud() const;
  long conversions() const { return conversions_; }

 private:
  static void on_uart_byte(avr_irq_t* irq, std::uint32_t value, void* param);
  static void on_uart_xoff(avr_irq_t* irq, std::uint32_t value, void* param);
  static void on_adc_trigger(avr_irq_t* irq, std::uint32_t value, void* param);
  void fix_frame_time();
  void feed_input();

  avr_t* avr_ = nullptr;
  avr_uart_t* uart_ = nullptr;
  std::uint32_t f_cpu_;
  AdcSource adc0_;
  std::string out_;
  std::deque<char> in_;
  bool rx_full_ = false;
  long conversions_ = 0;
  std::uint64_t fixed_for_ = 0;  // cycles_per_byte value already corrected
  // What elf_read_firmware allocated (flash image, EEPROM, fuses, symbols): ours to free, after
  // the core that may point into the symbols is gone.
  std::vector<void*> firmware_blocks_;
};

}  // namespace spindown
