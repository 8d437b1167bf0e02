#!/usr/bin/env bash
# The port itself: a device that does not exist (clear error; --exit-on-missing exits 1, the
# default keeps retrying and connects as soon as the device appears), and a wrong baud rate
# (the bench's UART garbage is counted and reported, never published, and the bridge runs on).
source "$(dirname "$0")/bridge_common.bash"

# 1. Missing device, --exit-on-missing: exit code 1 and the errno text.
rc=0
timeout 10 "$BIN/spindown-bridge" --device "$WORK/nope" --bench missing --lcm-url "$LCM_URL" --exit-on-missing \
  2>"$WORK/missing.log" || rc=$?
[[ $rc == 1 ]] || fail "--exit-on-missing exited with $rc, want 1"
grep -q "cannot open $WORK/nope: No such file or directory" "$WORK/missing.log" || fail "no clear error: $(cat "$WORK/missing.log")"

# 2. Missing device, retrying: status says disconnected; the device appears; samples flow.
start_tap late late
"$BIN/spindown-bridge" --device "$WORK/late.tty" --bench late --lcm-url "$LCM_URL" 2>"$WORK/late.bridge.log" &
bridge=$!; PIDS+=($bridge)
wait_for "grep -q '\"open_failures\":[1-9]' '$WORK/late.status.jsonl' 2>/dev/null" 10 "a status with open failures"
[[ $(last_status late state) == disconnected ]] || fail "late: state is not disconnected"
last_status late last_error | grep -q "No such file or directory" || fail "late: last_error lacks the reason"
"$BIN/spindown-virtual-bench" --link "$WORK/late.tty" --sent "$WORK/late.sent.tsv" --truth "$WORK/late.truth.json" \
  --wait-reader 10 --linger 1 --speed 50 --runs 1 >"$WORK/late.bench.out" 2>"$WORK/late.bench.log" &
bench=$!; PIDS+=($bench)
wait_pid "$bench" 60 || fail "late: the bridge did not open the device once it appeared: $(cat "$WORK/late.bench.log")"
n=$(truth late "t['samples']")
wait_samples "late" "$n" 10
compare_samples late || fail "late: samples differ"
kill -TERM "$bridge"; wait_pid "$bridge" 5 || fail "late: bridge exit code $? on SIGTERM"

# 3. Wrong baud: the bench talks 115200, the bridge listens at 9600.
start_tap baud baud
"$BIN/spindown-virtual-bench" --link "$WORK/baud.tty" --truth "$WORK/baud.truth.json" --protocol spindown-v1 \
  --period-ms 10 --wait-reader 10 --linger 1.5 --speed 20 --runs 1 >"$WORK/baud.bench.out" 2>"$WORK/baud.bench.log" &
bench=$!; PIDS+=($bench)
wait_for "[[ -L '$WORK/baud.tty' ]]" 10 "the virtual bench's pty"
"$BIN/spindown-bridge" --device "$WORK/baud.tty" --bench baud --baud 9600 --lcm-url "$LCM_URL" 2>"$WORK/baud.bridge.log" &
bridge=$!; PIDS+=($bridge)
wait_pid "$bench" 60 || fail "baud: virtual bench failed"
grep -q "garbled (baud mismatch)" "$WORK/baud.bench.log" || fail "baud: the bench did not see the mismatch"
sleep 1.2
kill -0 "$bridge" || fail "baud: the bridge stopped"
kill -TERM "$bridge"; wait_pid "$bridge" 5 || fail "baud: bridge exit code $? on SIGTERM"
[[ $(last_status baud samples) == 0 ]] || fail "baud: garbage was published as samples"
[[ ! -s "$WORK/baud.samples.tsv" ]] || fail "baud: the tap received samples"
bad=$(last_status baud lines_bad)
((bad > 10)) || fail "baud: only $bad bad lines counted"
grep -qE '"last_error":"[^"]*line [0-9]+: ' "$WORK/baud.status.jsonl" || fail "baud: bad lines not reported"
echo "PASS bridge_port (missing device, late device, wrong baud: $bad bad lines, 0 samples)"
