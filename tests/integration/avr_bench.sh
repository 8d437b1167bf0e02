#!/usr/bin/env bash
# The firmware's own bytes: the lab sketch and spindown-coast (deploy/firmware), compiled with
# avr-gcc, run on an emulated Arduino Uno (spindown-avr-bench: simavr's ATmega328P at 16 MHz,
# A0 from the motor simulator on the emulated clock) -> pty -> spindown-bridge -> LCM (private
# network namespace) -> spindown-fitter and spindown-logger. The FIT messages' c3, c4 and cut
# match the bench's truth within their errors; the bridge published every sample line the board
# sent; and `spindown fit` of a PuTTY-like capture of the same port (the same emulation again,
# read with stty + cat) gives the same numbers as the live fitter, for each sketch: the lab
# sketch's millis<TAB>volts and spindown_coast's spindown-v1 lines (read by read_spindown_text).
source "$(dirname "$0")/avr_common.bash"

build_firmware "$WORK/fw"
start_services

# firmware bench-name baud runs
for spec in "lab_sketch avr-lab 9600 2" "spindown_coast avr-v1 115200 1"; do
  read -r sketch name baud runs <<<"$spec"
  start_tap "$name" "$name"
  start_avr "$name" "$WORK/fw/$sketch.elf" --speed 0 --runs "$runs" --seed 7 "${AVR_PHYSICS[@]}"
  bench=$AVR_PID
  start_bridge "$name" "$baud"
  bridge=$BRIDGE_PID
  wait_pid "$bench" 150 || fail "$name: spindown-avr-bench failed: $(tail -5 "$WORK/$name.avr.log")"
  grep -h 'real time' "$WORK/$name.avr.log" | sed "s/^/$name: /"
  want_fits=$(truth "$name" "len(t['runs'])")
  deadline=$((SECONDS + 30))
  while (( $(grep -c " $name run [0-9]* fitted: " "$WORK/fitter.err" || true) < want_fits && SECONDS < deadline )); do sleep 0.1; done
  sleep 1.2  # a last heartbeat
  kill -TERM "$bridge"; wait_pid "$bridge" 5 || fail "$name: bridge exited with $? on SIGTERM"
  kill -TERM "$TAP_PID" 2>/dev/null || true

  [[ $(truth "$name" "t['protocol']") == "$([[ $sketch == lab_sketch ]] && echo lab-tsv || echo spindown-v1)" ]] ||
    fail "$name: the board printed $(truth "$name" "t['protocol']"), not its protocol"
  sent=$(truth "$name" "t['samples']")
  got=$(last_status "$name" samples)
  bad=$(last_status "$name" lines_bad)
  ((sent > 300)) || fail "$name: the board sent only $sent sample lines"
  [[ $got == "$sent" && $bad == 0 ]] ||
    fail "$name: the bridge published $got samples ($bad bad lines) of the $sent sample lines the board sent"
  echo "$name: the board sent $sent sample lines; the bridge published $got, 0 bad lines"
done
sleep 1
stop_services
LOG=$(ls "$WORK"/log/*.lcm | head -1)
"$BIN/spindown" refit "$LOG" --live --json >"$WORK/live.json" 2>"$WORK/refit.err" || fail "refit --live: $(cat "$WORK/refit.err")"
python3 - "$WORK/live.json" >"$WORK/split.log" <<'PY' || fail "splitting the live fits by bench"
import json, sys, os
live = json.load(open(sys.argv[1]))
for bench in ("avr-lab", "avr-v1"):
    runs = [r for f in live["files"] for r in f["runs"] if r["bench"].get("id") == bench]
    json.dump({"files": [{"runs": runs}]}, open(os.path.join(os.path.dirname(sys.argv[1]), f"{bench}.live.json"), "w"))
PY
for name in avr-lab avr-v1; do
  echo "$name: live FIT messages against the truth"
  check_fits "$WORK/$name.live.json" "$WORK/$name.truth.json" "$(truth "$name" "len(t['runs'])")" ||
    fail "$name: the live fits do not match the truth"
done

# PuTTY on the same port: the same emulation (deterministic: same firmware, options and seed),
# logged to a file and fitted offline.
start_avr cap "$WORK/fw/lab_sketch.elf" --speed 0 --runs 2 --seed 7 "${AVR_PHYSICS[@]}"
capture cap "$WORK/capture.log" 9600
wait_pid "$AVR_PID" 60 || fail "capture: spindown-avr-bench failed: $(tail -5 "$WORK/cap.avr.log")"
"$BIN/spindown" fit "$WORK/capture.log" --json >"$WORK/capture.json" 2>"$WORK/capture.err" ||
  fail "spindown fit of the capture: $(cat "$WORK/capture.err")"
head -4 "$WORK/capture.log" | cat -A | sed 's/^/  capture: /'
# The lab protocol as the handout's sketch prints it: millis, TAB, volts with two decimals, CR LF
# (Serial.println(float)); a sketch printing anything else is not the lab's sketch.
python3 - "$WORK/capture.log" <<'PY' || fail "the lab sketch's lines are not millis<TAB>volts with two decimals"
import re, sys
lines = open(sys.argv[1], "rb").read().split(b"\n")[1:-1]
bad = [l for l in lines if not re.fullmatch(rb"[0-9]+\t[0-9]+\.[0-9]{2}\r", l)]
assert len(lines) > 300 and not bad, (len(lines), bad[:3])
PY
same_fits "$WORK/avr-lab.live.json" "$WORK/capture.json" ||
  fail "spindown fit of the PuTTY capture differs from the live FIT messages"
echo "capture: spindown fit of the PuTTY log of the same port = the live FIT messages ($(truth cap "t['samples']") lines)"

# The same for spindown_coast at 115200 baud: a capture of its spindown-v1 lines (banner, then
# S,seq,micros,adc*CRC) is read as a spindown-v1 file, every sample the board sent used with the
# bridge's conversion and clock, and fitted to the live FIT messages' numbers.
start_avr cap1 "$WORK/fw/spindown_coast.elf" --speed 0 --runs 1 --seed 7 "${AVR_PHYSICS[@]}"
capture cap1 "$WORK/capture-v1.log" 115200
wait_pid "$AVR_PID" 60 || fail "v1 capture: spindown-avr-bench failed: $(tail -5 "$WORK/cap1.avr.log")"
"$BIN/spindown" fit "$WORK/capture-v1.log" --json >"$WORK/capture-v1.json" 2>"$WORK/capture-v1.err" ||
  fail "spindown fit of the spindown-v1 capture: $(cat "$WORK/capture-v1.err")"
head -3 "$WORK/capture-v1.log" | cat -A | sed 's/^/  v1 capture: /'
python3 - "$WORK/capture-v1.log" "$WORK/capture-v1.json" "$(truth cap1 "t['samples']")" <<'PY' || fail "the spindown-v1 capture was not read whole as spindown-v1"
import json, re, sys
lines = open(sys.argv[1], "rb").read().split(b"\n")[1:-1]
# The board's bytes: its banner, then spindown-v1 samples (the reader, not this script, checks the CRCs).
assert lines[0].startswith(b"#spindown-v1 firmware=spindown-coast "), lines[0]
bad = [l for l in lines[1:] if not re.fullmatch(rb"S,[0-9]+,[0-9]+,[0-9]+\*[0-9A-F]{2}\r", l)]
assert len(lines) > 300 and not bad, (len(lines), bad[:3])
f = json.load(open(sys.argv[2]))["files"][0]
diags = f["diagnostics"]
summary = [d["message"] for d in diags if d["line"] == 0]
problems = [d for d in diags if d["severity"] != "note"]
assert any("spindown-v1 samples from" in m for m in summary), ("not read as spindown-v1", summary)
assert not problems, problems
assert f["samples_read"] == int(sys.argv[3]), (f["samples_read"], "samples read, the board sent", sys.argv[3])
print(f"  v1 capture: read as spindown-v1, {f['samples_read']} samples, no warnings: {summary[0]}")
PY
same_fits "$WORK/avr-v1.live.json" "$WORK/capture-v1.json" ||
  fail "spindown fit of the spindown-v1 capture differs from the live FIT messages"
echo "v1 capture: spindown fit of the PuTTY log of spindown_coast's port = the live FIT messages ($(truth cap1 "t['samples']") lines)"
echo "PASS avr_bench"
