#!/usr/bin/env bash
# The real world, on a pty: garbage lines, lines cut short, a 10 MB line without newline, an
# Arduino reset mid-run and the USB cable pulled and plugged back. The bridge never stops, counts
# each fault in its status, and every sample the bench sent is published with the right clock
# epoch (no garbage published as data).
source "$(dirname "$0")/bridge_common.bash"

for proto in lab spindown-v1; do
  name=faults-${proto//[^a-z0-9]/}
  start_tap "$name" "$name"
  period=20 baud=9600; [[ $proto == spindown-v1 ]] && period=10 baud=115200
  "$BIN/spindown-virtual-bench" --link "$WORK/$name.tty" --sent "$WORK/$name.sent.tsv" \
    --truth "$WORK/$name.truth.json" --wait-reader 20 --linger 1 --protocol "$proto" --period-ms "$period" \
    --speed 10 --runs 2 --lead-in-s 2 --tail-s 1 --garbage-every 40 --partial-every 55 \
    --long-line-at 4 --long-line-bytes 10485760 --reset-at 9 --unplug-at 16 --unplug-for 0.8 \
    >"$WORK/$name.bench.out" 2>"$WORK/$name.bench.log" &
  bench=$!; PIDS+=($bench)
  wait_for "[[ -L '$WORK/$name.tty' ]]" 10 "the virtual bench's pty"
  "$BIN/spindown-bridge" --device "$WORK/$name.tty" --bench "$name" --lcm-url "$LCM_URL" --retry --baud "$baud" \
    2>"$WORK/$name.bridge.log" &
  bridge=$!; PIDS+=($bridge)
  wait_pid "$bench" 150 || fail "$name: virtual bench failed: $(cat "$WORK/$name.bench.log")"
  n=$(truth "$name" "t['samples']")
  wait_samples "$name" "$n" 10
  sleep 1.2
  kill -0 "$bridge" 2>/dev/null || fail "$name: the bridge stopped"
  grep -q '"state":"disconnected"' "$WORK/$name.status.jsonl" || fail "$name: no status said disconnected"
  kill -TERM "$bridge"
  wait_pid "$bridge" 5 || fail "$name: bridge exited with $? on SIGTERM (want 0)"

  compare_samples "$name" || fail "$name: published samples differ from what the bench sent"
  garbage=$(truth "$name" "t['faults']['garbage_lines']")
  partial=$(truth "$name" "t['faults']['partial_lines']")
  ((garbage > 10 && partial > 10)) || fail "$name: bench sent too few faults ($garbage, $partial)"
  want_bad=$((garbage + partial + 1))
  got_bad=$(last_status "$name" lines_bad)
  [[ $got_bad == "$want_bad" ]] || fail "$name: lines_bad $got_bad, want $want_bad (garbage $garbage + partial $partial + 1 over-long)"
  [[ $(last_status "$name" oversize_lines) == 1 ]] || fail "$name: oversize_lines != 1"
  [[ $(last_status "$name" reconnects) == 1 ]] || fail "$name: reconnects != 1"
  [[ $(last_status "$name" disconnects) -ge 1 ]] || fail "$name: disconnects not counted"
  # The reset at 9 s and the replug (USB power returns: the board boots) are two restarts.
  [[ $(last_status "$name" device_resets) == 2 ]] || fail "$name: device_resets != 2"
  [[ $(last_status "$name" clock_epoch) == 2.0 ]] || fail "$name: clock_epoch != 2"
  grep -qE '"last_error":"[^"]*line [0-9]+: ' "$WORK/$name.status.jsonl" || fail "$name: no bad line was reported with its reason"
  echo "$name: $n samples, $got_bad bad lines ($garbage garbage, $partial partial, 1 over-long), 1 reconnect, 2 resets"
done
echo "PASS bridge_faults"
