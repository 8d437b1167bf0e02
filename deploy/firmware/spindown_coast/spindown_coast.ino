// spindown-coast: the improved spin-down firmware, protocol spindown-v1 (README.md here is the
// normative definition; core/sources/src/spindown_protocol.cpp parses exactly that).
//   - raw ADC counts (the lab sketch's 2-decimal volts lose half the 10-bit resolution); volts =
//     count * adc_ref_v / 1024, the ATmega328P datasheet's ADC = V_in * 1024 / V_ref
//   - micros() time stamps on a fixed schedule (not delay(): the loop period does not drift)
//   - a sequence number and a CRC-8 per line, 115200 baud
//   - period 1-20 ms: compile with -DSPINDOWN_PERIOD_US=…, or send "P<ms>\n" at run time
//   - a banner naming firmware, version and units at start (and after "P" or "?")
#include <Arduino.h>
#include <stdlib.h>

#ifndef SPINDOWN_BAUD
#define SPINDOWN_BAUD 115200UL
#endif
#ifndef SPINDOWN_PERIOD_US
#define SPINDOWN_PERIOD_US 5000UL
#endif

static const char kFirmware[] = "spindown-coast";
static const char kVersion[] = "1.0.0";

static uint32_t period_us = SPINDOWN_PERIOD_US;
static uint32_t seq = 0;
static uint32_t next_us = 0;
static uint8_t crc = 0;
static char cmd[8];
static uint8_t cmd_len = 0;

// CRC-8/SMBUS: polynomial 0x07, initial 0, MSB first, no final xor.
static void crc_byte(uint8_t b) {
  crc ^= b;
  for (uint8_t i = 0; i < 8; ++i) crc = (crc & 0x80) ? (uint8_t)((crc << 1) ^ 0x07) : (uint8_t)(crc << 1);
}

static void out(const char* s) {
  for (; *s; ++s) {
    crc_byte((uint8_t)*s);
    Serial.write(*s);
  }
}

static void out_u32(uint32_t v) {
  char buf[11];
  ultoa(v, buf, 10);
  out(buf);
}

// "*CC\r\n" and a fresh CRC for the next line.
static void end_line() {
  static const char hex[] = "0123456789ABCDEF";
  Serial.write('*');
  Serial.write(hex[crc >> 4]);
  Serial.write(hex[crc & 0x0F]);
  Serial.write('\r');
  Serial.write('\n');
  crc = 0;
}

static void banner() {
  crc = 0;
  out("#spindown-v1 firmware=");
  out(kFirmware);
  out(" version=");
  out(kVersion);
  out(" time=us value=adc adc_bits=10 adc_ref_v=5.000 period_us=");
  out_u32(period_us);
  out(" baud=");
  out_u32(SPINDOWN_BAUD);
  end_line();
}

static void note(const char* text) {
  crc = 0;
  out("#");
  out(text);
  end_line();
}

// Host commands, one per line: "P<ms>" sets the period (1-20 ms), "?" repeats the banner.
static void poll_commands() {
  while (Serial.available() > 0) {
    const char c = (char)Serial.read();
    if (c != '\n' && c != '\r') {
      if (cmd_len < sizeof cmd - 1) cmd[cmd_len++] = c;
      continue;
    }
    cmd[cmd_len] = '\0';
    if (cmd[0] == 'P') {
      const long ms = atol(cmd + 1);
      if (ms >= 1 && ms <= 20) {
        period_us = (uint32_t)ms * 1000UL;
        banner();
      } else {
        note("error period must be 1-20 ms");
      }
    } else if (cmd[0] == '?') {
      banner();
    } else if (cmd_len > 0) {
      note("error unknown command");
    }
    cmd_len = 0;
  }
}

void setup() {
  Serial.begin(SPINDOWN_BAUD);
  if (period_us < 1000UL || period_us > 20000UL) period_us = 5000UL;
  banner();
  next_us = micros();
}

void loop() {
  poll_commands();
  const uint32_t now = micros();
  if ((int32_t)(now - next_us) < 0) return;
  // On schedule; if the line could not be sent within a period (baud too low for it), resync
  // rather than burst: the time stamps stay true either way.
  next_us += period_us;
  if ((int32_t)(now - next_us) >= 0) next_us = now + period_us;
  const int adc = analogRead(A0);  // ~112 µs after `now`
  crc = 0;
  out("S,");
  out_u32(seq++);
  out(",");
  out_u32(now);
  out(",");
  out_u32((uint32_t)adc);
  end_line();
}
