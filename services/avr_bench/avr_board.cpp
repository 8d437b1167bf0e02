#include "avr_board.hpp"

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <fmt/format.h>
#include <stdexcept>
#include <utility>

extern "C" {
#include <simavr/avr_adc.h>
#include <simavr/avr_uart.h>
#include <simavr/sim_avr.h>
#include <simavr/sim_elf.h>
#include <simavr/sim_hex.h>
#include <simavr/sim_irq.h>
}

namespace spindown {

namespace {

// ATmega328P USART0 registers (data-space addresses) and the U2X0 bit.
constexpr std::uint16_t kUcsr0a = 0xC0, kUbrr0l = 0xC4, kUbrr0h = 0xC5;
constexpr std::uint8_t kU2x0 = 1 << 1;

// The emulator's sleep callback: the stock one usleep()s in wall time while the AVR sleeps;
// the bench keeps its own pace (main.cpp), so emulated sleep costs no wall time.
void no_wall_sleep(avr_t*, avr_cycle_count_t) {}

bool ends_with(const std::string& s, std::string_view tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

}  // namespace

AvrBoard::AvrBoard(const std::string& firmware_path, std::uint32_t f_cpu, AdcSource adc0)
    : f_cpu_(f_cpu), adc0_(std::move(adc0)) {
  avr_ = avr_make_mcu_by_name("atmega328p");
  if (!avr_) throw std::runtime_error("simavr has no atmega328p core");
  avr_init(avr_);
  if (ends_with(firmware_path, ".hex")) {
    std::uint32_t size = 0, start = 0;
    std::uint8_t* code = read_ihex_file(firmware_path.c_str(), &size, &start);
    if (!code || size == 0) throw std::runtime_error(fmt::format("{}: not a readable Intel HEX file", firmware_path));
    avr_loadcode(avr_, code, size, start);
    std::free(code);
  } else {
    elf_firmware_t fw{};
    if (elf_read_firmware(firmware_path.c_str(), &fw) != 0 || fw.flashsize == 0)
      throw std::runtime_error(fmt::format("{}: not a readable AVR ELF file (want the .elf or .hex that "
                                           "deploy/firmware builds)", firmware_path));
    avr_load_firmware(avr_, &fw);
    for (void* block : {static_cast<void*>(fw.flash), static_cast<void*>(fw.eeprom), static_cast<void*>(fw.fuse),
                        static_cast<void*>(fw.lockbits)})
      if (block) firmware_blocks_.push_back(block);
    for (std::uint32_t i = 0; fw.symbol && i < fw.symbolcount; ++i) firmware_blocks_.push_back(fw.symbol[i]);
    if (fw.symbol) firmware_blocks_.push_back(fw.symbol);
  }
  // An Uno: 16 MHz crystal, 5 V from USB on VCC, AVCC and AREF (analogRead's default
  // reference is AVCC).
  avr_->frequency = f_cpu_;
  avr_->vcc = avr_->avcc = avr_->aref = 5000;
  avr_->sleep = no_wall_sleep;

  std::uint32_t flags = 0;
  avr_ioctl(avr_, AVR_IOCTL_UART_GET_FLAGS('0'), &flags);
  // No console echo of the sketch's lines, no usleep() when the firmware polls the receiver.
  flags &= ~std::uint32_t(AVR_UART_FLAG_STDIO | AVR_UART_FLAG_POLL_SLEEP);
  avr_ioctl(avr_, AVR_IOCTL_UART_SET_FLAGS('0'), &flags);
  avr_irq_register_notify(avr_io_getirq(avr_, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUTPUT), on_uart_byte, this);
  avr_irq_register_notify(avr_io_getirq(avr_, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUT_XOFF), on_uart_xoff, this);
  avr_irq_register_notify(avr_io_getirq(avr_, AVR_IOCTL_ADC_GETIRQ, ADC_IRQ_OUT_TRIGGER), on_adc_trigger, this);
  for (avr_io_t* io = avr_->io_port; io; io = io->next)
    if (io->kind && std::strcmp(io->kind, "uart") == 0 && reinterpret_cast<avr_uart_t*>(io)->name == '0')
      uart_ = reinterpret_cast<avr_uart_t*>(io);  // avr_uart_t starts with its avr_io_t
}

AvrBoard::~AvrBoard() {
  if (avr_) {
    avr_terminate(avr_);
    std::free(avr_);
  }
  for (void* block : firmware_blocks_) std::free(block);
}

void AvrBoard::reset() {
  avr_reset(avr_);
  avr_->frequency = f_cpu_;
  in_.clear();
  rx_full_ = false;
  fixed_for_ = 0;
}

std::uint64_t AvrBoard::cycle() const { return avr_->cycle; }

bool AvrBoard::run_until(std::uint64_t cycle) {
  // Bounded by the cycle target; each avr_run executes at least one instruction or a sleep.
  for (std::uint64_t guard = 0; avr_->cycle < cycle && guard < 100'000'000; ++guard) {
    const int state = avr_run(avr_);
    if (state == cpu_Done || state == cpu_Crashed) return false;
    if ((guard & 0x3ff) == 0) {
      fix_frame_time();
      feed_input();
    }
  }
  fix_frame_time();
  feed_input();
  return true;
}

void AvrBoard::fix_frame_time() {
  // simavr 1.6 counts a parity bit in every frame (11 bit times for 8N1); the ATmega sends
  // start + 8 data + stop = 10. Correct the UART's byte time so 9600 baud carries 960 bytes/s.
  if (!uart_ || uart_->cycles_per_byte == fixed_for_ || uart_->cycles_per_byte == 0) return;
  const auto ubrr = std::uint64_t(avr_->data[kUbrr0l]) | (std::uint64_t(avr_->data[kUbrr0h] & 0x0F) << 8);
  const std::uint64_t per_bit = (ubrr + 1) * ((avr_->data[kUcsr0a] & kU2x0) ? 8 : 16);
  if (uart_->cycles_per_byte == per_bit * 11) uart_->cycles_per_byte = per_bit * 10;
  fixed_for_ = uart_->cycles_per_byte;
}

int AvrBoard::uart_baud() const {
  if (!(avr_->data[0xC1] & (1 << 3))) return 0;  // UCSR0B.TXEN0: not set up yet
  const auto ubrr = unsigned(avr_->data[kUbrr0l]) | (unsigned(avr_->data[kUbrr0h] & 0x0F) << 8);
  const unsigned per_bit = (ubrr + 1) * ((avr_->data[kUcsr0a] & kU2x0) ? 8 : 16);
  return int((f_cpu_ + per_bit / 2) / per_bit);
}

std::string AvrBoard::take_output() { return std::exchange(out_, std::string()); }

void AvrBoard::send_input(std::string_view bytes) { in_.insert(in_.end(), bytes.begin(), bytes.end()); }

void AvrBoard::feed_input() {
  // One byte at a time while the receiver's FIFO has room; simavr paces RXC at the byte time.
  for (int guard = 0; guard < 64 && !in_.empty() && !rx_full_; ++guard) {
    avr_raise_irq(avr_io_getirq(avr_, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_INPUT), std::uint8_t(in_.front()));
    in_.pop_front();
  }
}

void AvrBoard::on_uart_byte(avr_irq_t*, std::uint32_t value, void* param) {
  static_cast<AvrBoard*>(param)->out_ += static_cast<char>(value & 0xFF);
}

void AvrBoard::on_uart_xoff(avr_irq_t*, std::uint32_t value, void* param) {
  static_cast<AvrBoard*>(param)->rx_full_ = value != 0;
}

void AvrBoard::on_adc_trigger(avr_irq_t*, std::uint32_t value, void* param) {
  auto* self = static_cast<AvrBoard*>(param);
  union {
    avr_adc_mux_t mux;
    std::uint32_t v;
  } e{};
  e.v = value;
  if (e.mux.kind != ADC_MUX_SINGLE || e.mux.src != 0) return;  // only A0 is wired
  ++self->conversions_;
  const int counts = std::clamp(self->adc0_(self->seconds()), 0, 1023);
  // simavr converts millivolts as mV·1023/AVCC (truncated); the smallest mV that gives
  // `counts` back, so the firmware reads exactly the count the motor's converter chose.
  const std::uint32_t mv = (std::uint32_t(counts) * 5000u + 1022u) / 1023u;
  avr_raise_irq(avr_io_getirq(self->avr_, AVR_IOCTL_ADC_GETIRQ, ADC_IRQ_ADC0), mv);
}

}  // namespace spindown
