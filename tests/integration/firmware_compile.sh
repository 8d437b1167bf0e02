#!/usr/bin/env bash
# Both sketches (the lab's, fixed, and spindown-coast) compile with avr-gcc and Debian's Arduino
# core into Intel HEX files, our sources warning-free, also with a compile-time period.
# Never skips: deploy/setup --tests (what deploy/run-tests calls) installs the AVR toolchain, and
# its absence is a failure.
set -euo pipefail
SRC=${SPINDOWN_SOURCE_DIR:?SPINDOWN_SOURCE_DIR not set}/deploy/firmware
command -v avr-gcc >/dev/null ||
  { echo "FAIL: avr-gcc not installed (deploy/setup --tests installs gcc-avr avr-libc arduino-core-avr)"; exit 1; }
[[ -d /usr/share/arduino/hardware/arduino/avr/cores/arduino ]] || { echo "FAIL: avr-gcc present but arduino-core-avr missing"; exit 1; }
OUT=$(mktemp -d /tmp/spindown-firmware.XXXXXX)
trap 'rm -rf "$OUT"' EXIT
timeout 240 make -C "$SRC" BUILD="$OUT" -j2 >"$OUT/make.log" 2>&1 || { cat "$OUT/make.log"; echo "FAIL: make"; exit 1; }
for hex in lab_sketch spindown_coast; do
  [[ -s "$OUT/$hex.hex" ]] || { echo "FAIL: $hex.hex missing"; exit 1; }
  head -c1 "$OUT/$hex.hex" | grep -q ':' || { echo "FAIL: $hex.hex is not Intel HEX"; exit 1; }
done
# Our sketches must compile without warnings (the core's own are silenced with -w).
if grep -E "(lab_sketch|spindown_coast)\.ino.*warning" "$OUT/make.log"; then echo "FAIL: warnings"; exit 1; fi
# A period set at compile time reaches the firmware.
timeout 120 make -C "$SRC" BUILD="$OUT/p2" PERIOD_US=2000 -j2 >"$OUT/make2.log" 2>&1 || { cat "$OUT/make2.log"; exit 1; }
[[ -s "$OUT/p2/spindown_coast.hex" ]] || { echo "FAIL: PERIOD_US build"; exit 1; }
echo "PASS firmware_compile: $(wc -c < "$OUT/lab_sketch.hex") and $(wc -c < "$OUT/spindown_coast.hex") bytes of HEX"
