#!/usr/bin/env bash
# spindown-logger killed with SIGKILL at random moments (5 times) while a bench publishes at
# 500 Hz: every log stays readable (it ends on a whole event: no problems), holds a gap-free
# prefix of the traffic, and loses at most the flush interval (plus scheduling slack).
source "$(dirname "$0")/logger_common.bash"

FLUSH=0.2
FLUSH_US=200000
SLACK_US=500000   # scheduling slack on a loaded machine: the kill, the wake-ups, the packet
RATE=500
for round in 1 2 3 4 5; do
  dir="$WORK/round$round"
  mkdir "$dir"
  start_logger "logger$round" --lcm-url "$URL" --dir "$dir" --flush-interval $FLUSH
  logger=$LOGGER_PID
  wait_for_log "$dir"
  kernel_before=$(udp_rcvbuf_errors)
  "$BIN/spindown-lcm-publish" --lcm-url "$URL" --bench kill-test --count 0 --rate $RATE --duration 20 \
    >"$dir/pub.json" &
  pub=$!
  PIDS+=("$pub")
  # A random moment between 0.4 and 1.9 s into the traffic.
  sleep "$(printf '0.%03d' $((RANDOM % 1000)))"
  sleep 0.4
  sleep "$(( RANDOM % 2 ))"
  kill_us=$(now_us)
  kill -KILL "$logger"
  wait "$logger" 2>/dev/null || true
  kill -TERM "$pub"
  wait "$pub" || fail "publisher failed"
  # At 500 Hz the receive buffer (16 MiB asked, capped at rmem_max) holds seconds of traffic: the kernel should drop none
  # (a gap with kernel drops here would mean the logger was starved for seconds, not lost data).
  kernel_drops=$(( $(udp_rcvbuf_errors) - kernel_before ))

  "$BIN/spindown-log-summary" "$dir"/*.lcm >"$dir/summary.json" || fail "round $round: log unreadable"
  problems=$(json "$dir/summary.json" 'd["problems"]')
  msgs=$(json "$dir/summary.json" 'd["benches"]["kill-test"]["messages"]')
  gaps=$(json "$dir/summary.json" 'd["benches"]["kill-test"]["gaps"]')
  first=$(json "$dir/summary.json" 'd["benches"]["kill-test"]["first_seq"]')
  last_us=$(json "$dir/summary.json" 'd["benches"]["kill-test"]["last_utime"]')
  lost_us=$(( kill_us - last_us ))
  printf 'round %d: %d messages logged, last one published %.3f s before SIGKILL (~%d messages lost), %d problems, %d dropped by the kernel\n' \
    "$round" "$msgs" "$(awk "BEGIN{print $lost_us / 1e6}")" $(( lost_us * RATE / 1000000 )) "$problems" "$kernel_drops"
  [[ $problems == 0 ]] || fail "round $round: the killed log has problems: $(cat "$dir/summary.json")"
  [[ $gaps == 0 && $first == 0 ]] || fail "round $round: $gaps gaps, first seq $first ($kernel_drops datagrams dropped by the kernel)"
  (( msgs > 0 )) || fail "round $round: nothing logged"
  (( lost_us <= FLUSH_US + SLACK_US )) || fail "round $round: lost $lost_us us of traffic (flush $FLUSH s)"
  lcm-logplayer -s 100 --lcm-url 'udpm://239.255.76.67:7699?ttl=0' "$dir"/*.lcm >/dev/null 2>&1 \
    || fail "round $round: lcm-logplayer rejected the killed log"
done
echo "PASS: 5 SIGKILLs, every log readable, loss within the flush interval"
