#!/usr/bin/env bash
# Faults a real Arduino Uno has, on the emulated one running the real lab sketch (see
# avr_bench.sh), against the bridge's promises (services/bridge/README.md):
#  1. a reset mid-coast, and the USB cable pulled between runs (the pty goes away; a new one
#     appears and the board boots when the bridge reopens it — DTR): the bridge never stops,
#     counts 2 device resets, 1 reconnect, clock epoch 2, publishes every sample line that
#     reached it, counts the line the reset cut as bad and the one the pull cut as partial; the
#     run that coasted on one clock is fitted within its errors.
#  2. a baud mismatch: the bridge at 115200 reads the 9600-baud sketch as framing garbage, says
#     so and publishes nothing; restarted at 9600 it opens the port again (the board resets:
#     DTR) and publishes the sketch's lines.
source "$(dirname "$0")/avr_common.bash"

build_firmware "$WORK/fw"
start_services

# ---- 1. reset mid-coast, cable pulled and plugged back ------------------------------------------
# Run 1: lead-in from 0.5 s, cut at 2.5 s, a ~9 s coast: the reset at 6 s is mid-coast. The cable
# is out from 14.5 s for 1 s (run 1 stopped and rested; run 2's lead-in starts at 16.5 s).
name=avr-faults
start_tap "$name" "$name"
start_avr "$name" "$WORK/fw/lab_sketch.elf" --speed 0 --runs 2 --seed 5 "${AVR_PHYSICS[@]}" --idle 3 \
  --reset-at 6 --unplug-at 14.5 --unplug-for 1
start_bridge "$name" 9600
bridge=$BRIDGE_PID
wait_pid "$AVR_PID" 150 || fail "$name: spindown-avr-bench failed: $(tail -5 "$WORK/$name.avr.log")"
grep -h 'real time' "$WORK/$name.avr.log" | sed "s/^/$name: /"
python3 - "$WORK/$name.truth.json" <<'PY' || fail "$name: the faults did not land where the test needs them"
import json, sys
t = json.load(open(sys.argv[1]))
r1, r2 = t["runs"]
assert r1["cut_bench_s"] < 6 < r1["stop_bench_s"], ("reset not mid-coast", r1)
assert r1["stop_bench_s"] + 1.5 < 14.5 and 15.5 < r2["cut_bench_s"] - 1, ("unplug not between runs", r1, r2)
assert r1["reset_mid_coast"] and not r2["reset_mid_coast"], t["runs"]
assert len(t["resets"]) == 2, t["resets"]
PY
deadline=$((SECONDS + 30))
while (( $(grep -c " $name run [0-9]* fitted: " "$WORK/fitter.err" || true) < 1 && SECONDS < deadline )); do sleep 0.1; done
sleep 1.2
kill -0 "$bridge" 2>/dev/null || fail "$name: the bridge stopped"
grep -q '"state":"disconnected"' "$WORK/$name.status.jsonl" || fail "$name: no status said disconnected"
sent=$(truth "$name" "t['samples']")
[[ $(last_status "$name" samples) == "$sent" ]] ||
  fail "$name: the bridge published $(last_status "$name" samples) samples, the board sent $sent sample lines"
[[ $(last_status "$name" device_resets) == 2 ]] || fail "$name: device_resets $(last_status "$name" device_resets), want 2"
[[ $(last_status "$name" clock_epoch) == 2.0 ]] || fail "$name: clock_epoch $(last_status "$name" clock_epoch), want 2"
[[ $(last_status "$name" reconnects) == 1 ]] || fail "$name: reconnects $(last_status "$name" reconnects), want 1"
[[ $(last_status "$name" lines_bad) == "$(truth "$name" "t['faults']['broken_lines']")" ]] ||
  fail "$name: lines_bad $(last_status "$name" lines_bad), the reset cut $(truth "$name" "t['faults']['broken_lines']") lines"
[[ $(last_status "$name" partial_lines) == "$(truth "$name" "t['faults']['partial_lines']")" ]] ||
  fail "$name: partial_lines $(last_status "$name" partial_lines), the pull cut $(truth "$name" "t['faults']['partial_lines']")"
# Every published sample in order on its epoch's clock: device time never goes back within an epoch.
python3 - "$WORK/$name.samples.tsv" <<'PY' || fail "$name: published samples out of order"
import sys
last = {}
for line in open(sys.argv[1]):
    f = line.split("\t"); epoch, t = int(f[1]), int(f[2])
    assert t > last.get(epoch, -1), (epoch, t, last.get(epoch)); last[epoch] = t
assert sorted(last) == [0, 1, 2], last
PY
kill -TERM "$bridge"; wait_pid "$bridge" 5 || fail "$name: bridge exited with $? on SIGTERM"
echo "$name: $sent samples published; 2 resets (mid-coast, replug), 1 reconnect, epochs 0-2;" \
  "$(truth "$name" "t['faults']['broken_lines']") line cut by the reset, $(truth "$name" "t['faults']['partial_lines']") dropped at the pull or the end"

# ---- 2. baud mismatch, then the right rate ------------------------------------------------------
name=avr-baud
start_tap "$name" "$name"
# Real time (--speed 1) while the wrong rate is on, so the bridge reads garbage for a while.
start_avr "$name" "$WORK/fw/lab_sketch.elf" --speed 1 --runs 1 --seed 9 "${AVR_PHYSICS[@]}"
bench=$AVR_PID
start_bridge "$name" 115200
wrong=$BRIDGE_PID
want='no valid line in [0-9]+ bytes at 115200 baud — wrong baud\? the lab sketch uses 9600'
wait_for "grep -qE '\"state\":\"$want\"' '$WORK/$name.status.jsonl' 2>/dev/null" 30 "a STATUS naming the wrong baud"
[[ ! -s "$WORK/$name.samples.tsv" ]] || fail "$name: garbage published as samples: $(head -3 "$WORK/$name.samples.tsv")"
kill -TERM "$wrong"; wait_pid "$wrong" 5 || fail "$name: bridge exited with $? on SIGTERM"
echo "$name: at 115200: '$(grep -m1 -oE "$want" "$WORK/$name.bridge.log")', nothing published"
start_bridge "$name" 9600
right=$BRIDGE_PID
wait_samples "$name" 50 30
(( $(wc -l <"$WORK/$name.samples.tsv") >= 50 )) || fail "$name: no samples at the right baud rate"
grep -q 'the port was opened again: DTR' "$WORK/$name.avr.log" || fail "$name: reopening the port did not reset the board"
wait_pid "$bench" 150 || fail "$name: spindown-avr-bench failed: $(tail -5 "$WORK/$name.avr.log")"
sleep 1.2
kill -0 "$right" 2>/dev/null || fail "$name: the bridge stopped"
[[ $(last_status "$name" samples) -ge 50 ]] || fail "$name: the bridge's samples counter"
kill -TERM "$right"; wait_pid "$right" 5 || fail "$name: bridge exited with $? on SIGTERM"
echo "$name: at 9600 after reopening (the board reset): $(last_status "$name" samples) samples, state $(last_status "$name" state)"

sleep 1
stop_services
LOG=$(ls "$WORK"/log/*.lcm | head -1)
"$BIN/spindown" refit "$LOG" --live --json >"$WORK/live.json" 2>"$WORK/refit.err" || fail "refit --live"
python3 - "$WORK/live.json" "$WORK/avr-faults.live.json" <<'PY'
import json, sys
live = json.load(open(sys.argv[1]))
runs = [r for f in live["files"] for r in f["runs"] if r["bench"].get("id") == "avr-faults"]
json.dump({"files": [{"runs": runs}]}, open(sys.argv[2], "w"))
PY
echo "avr-faults: the run that coasted on one clock against the truth"
check_fits "$WORK/avr-faults.live.json" "$WORK/avr-faults.truth.json" 1 || fail "avr-faults: fits after the faults"
echo "PASS avr_bench_faults"
