#!/usr/bin/env bash
# spindown-logger over real LCM (UDP multicast in a private network namespace): a burst from
# three benches as fast as the publisher can send is recorded completely, and SIGTERM right
# after the last message loses nothing (the logger drains LCM and its queue before exiting).
source "$(dirname "$0")/logger_common.bash"

mkdir "$WORK/logs"
start_logger logger --lcm-url "$URL" --dir "$WORK/logs" --bench lab --channels 'SPINDOWN\..*'
wait_for_log "$WORK/logs"
N=4000
"$BIN/spindown-lcm-publish" --lcm-url "$URL" --benches 3 --count $N --rate 0 --batch 2 >"$WORK/pub.json"
stop_logger "$LOGGER_PID"   # at once: no pause after the burst
[[ $LOGGER_RC == 0 ]] || fail "logger exited with $LOGGER_RC: $(cat "$WORK/logger.err")"
[[ $(json "$WORK/pub.json" 'd["failures"]') == 0 ]] || fail "publisher failures: $(cat "$WORK/pub.json")"

"$BIN/spindown-log-summary" "$WORK"/logs/*.lcm >"$WORK/summary.json"
[[ $(json "$WORK/summary.json" 'd["problems"]') == 0 ]] || fail "log problems: $(cat "$WORK/summary.json")"
for b in bench-1 bench-2 bench-3; do
  got=$(json "$WORK/summary.json" "d['benches']['$b']['messages']")
  gaps=$(json "$WORK/summary.json" "d['benches']['$b']['gaps']")
  first=$(json "$WORK/summary.json" "d['benches']['$b']['first_seq']")
  echo "$b: $got of $N messages logged, $gaps gaps, first seq $first"
  [[ $got == "$N" && $gaps == 0 && $first == 0 ]] || fail "$b: $got of $N messages, $gaps gaps, first seq $first"
done
# The log says how it ended: the last status event is the logger's own "stopped" with no drops.
state=$(json "$WORK/summary.json" 'd["files"][-1]["last_logger_status"]["state"]')
drops=$(json "$WORK/summary.json" 'd["files"][-1]["last_logger_status"]["counters"]["drops"]')
events=$(json "$WORK/summary.json" 'd["files"][-1]["last_logger_status"]["counters"]["events"]')
[[ $state == stopped && $drops == 0 ]] || fail "last status event: state $state, drops $drops"
(( events >= 3 * N )) || fail "last status event counts $events events, want >= $((3 * N))"
grep -q "stopped: .* 0 drops, 0 write errors" "$WORK/logger.err" || fail "summary line: $(cat "$WORK/logger.err")"
echo "PASS: $((3 * N)) messages of a burst logged, nothing lost on SIGTERM"
