#!/usr/bin/env bash
# A wrong baud rate: the bridge at 115200 reads the lab sketch's 9600-baud lines as garbled
# bytes (0xC0 0xF0 0x80 …, what a real port delivers; a pty does not garble, so a script writes
# them). The bridge says "no valid line in N bytes at 115200 baud — wrong baud? the lab sketch
# uses 9600" in its STATUS state, last_error and on stderr, publishes nothing, and goes back to
# "connected" once valid lines arrive (the sketch re-flashed at 115200).
source "$(dirname "$0")/bridge_common.bash"

start_tap wb wb
# The "board": a pty whose slave is linked at $WORK/wb.tty; garbage once told to start, then
# valid lab lines; it holds the pty open until the bridge is stopped.
python3 - "$WORK" <<'PY' 2>"$WORK/board.log" &
import os, sys, time, tty
work = sys.argv[1]
master, slave = os.openpty()
tty.setraw(slave)
os.symlink(os.ttyname(slave), f"{work}/wb.tty")
deadline = time.monotonic() + 20
while not os.path.exists(f"{work}/go") and time.monotonic() < deadline: time.sleep(0.05)
garbled = bytes([0xC0, 0xF0, 0x80, 0xFE, 0x00, 0xE0, 0xF8, 0xFC, 0x80, 0xC0, 0xF0, 0x00, 0xFE, 0xFF, 0x80, 0xE0])
for _ in range(40):  # 640 bytes over 2 s, 4 stray newlines among them
    os.write(master, garbled * 3 + b"\n" if _ % 10 == 9 else garbled)
    time.sleep(0.05)
with open(f"{work}/garbage.done", "w"): pass
time.sleep(1.5)  # the STATUS with the wrong-baud state goes out at once, and one more beat
for i in range(100):  # 2 s of the lab sketch's lines
    os.write(master, f"{5000 + 20 * i}\t{2.5 - 0.01 * i:.2f}\r\n".encode())
    time.sleep(0.02)
with open(f"{work}/lines.done", "w"): pass
deadline = time.monotonic() + 30
while not os.path.exists(f"{work}/stop") and time.monotonic() < deadline: time.sleep(0.05)
PY
PIDS+=($!)
wait_for "[[ -L '$WORK/wb.tty' ]]" 10 "the board's pty"
"$BIN/spindown-bridge" --device "$WORK/wb.tty" --bench wb --lcm-url "$LCM_URL" --baud 115200 \
  2>"$WORK/wb.bridge.log" &
bridge=$!; PIDS+=($bridge)
wait_for "grep -q '\"state\":\"connected\"' '$WORK/wb.status.jsonl' 2>/dev/null" 10 "the bridge to connect"
touch "$WORK/go"
wait_for "[[ -e '$WORK/garbage.done' ]]" 10 "the garbage to be written"
want='no valid line in [0-9]+ bytes at 115200 baud — wrong baud\? the lab sketch uses 9600'
wait_for "grep -qE '\"state\":\"$want\"' '$WORK/wb.status.jsonl'" 5 "a STATUS naming the wrong baud"
grep -qE "spindown-bridge: $WORK/wb.tty: $want" "$WORK/wb.bridge.log" || fail "stderr lacks the wrong-baud line: $(cat "$WORK/wb.bridge.log")"
grep -qE "\"last_error\":\"$WORK/wb.tty: $want \\([0-9]+% of them not text\\)\"" "$WORK/wb.status.jsonl" ||
  fail "last_error does not name the wrong baud: $(tail -1 "$WORK/wb.status.jsonl")"
[[ ! -s "$WORK/wb.samples.tsv" ]] || fail "garbage published as samples: $(head -3 "$WORK/wb.samples.tsv")"
echo "ok: $(grep -m1 -oE "$want" "$WORK/wb.bridge.log") (stderr, STATUS state and last_error)"

wait_for "[[ -e '$WORK/lines.done' ]]" 10 "the valid lines to be written"
wait_samples wb 100 5
sleep 1.2  # a heartbeat after the lines
[[ $(wc -l <"$WORK/wb.samples.tsv") == 100 ]] || fail "published $(wc -l <"$WORK/wb.samples.tsv") samples of the 100 valid lines"
[[ $(last_status wb state) == connected ]] || fail "state after valid lines: $(last_status wb state)"
grep -qF "spindown-bridge: $WORK/wb.tty: valid lines again at 115200 baud" "$WORK/wb.bridge.log" ||
  fail "stderr does not say the lines are valid again: $(cat "$WORK/wb.bridge.log")"
n=$(grep -cE "$want" "$WORK/wb.bridge.log")
[[ $n == 1 ]] || fail "the wrong baud was said $n times on stderr, want once"
echo "ok: 100 samples after the garbage, state back to connected, said once"
touch "$WORK/stop"
kill -TERM "$bridge"
wait_pid "$bridge" 5 || fail "bridge exited with $? on SIGTERM (want 0)"
echo "PASS bridge_wrong_baud"
