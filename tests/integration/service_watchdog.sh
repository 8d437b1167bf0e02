#!/bin/bash
# systemd's notify protocol without systemd: spindown-fitter, spindown-logger and spindown-bridge
# each run with NOTIFY_SOCKET pointing at a unix datagram socket this test listens on (a small
# python3 listener standing in for systemd) and WATCHDOG_USEC=600000. For each:
#  - READY=1 comes first (before any WATCHDOG=1), then WATCHDOG=1 again and again;
#  - the main loop frozen (the SPINDOWN_TEST_STALL_FILE hook blocks the loop's own thread and
#    says so with STATUS=test stall first): not one WATCHDOG=1 arrives while it is blocked —
#    the pings come from the loop, not from a thread that would ping whatever the loop does;
#  - unfrozen: WATCHDOG=1 again; SIGTERM: STOPPING=1, exit 0.
# No timed assertion: every wait is for a message, bounded at 10 s; the frozen stretch lasts 2 s
# (over 6 ping periods) and nothing may arrive in it.
# Runs in a private network namespace (unshare -n) with multicast on loopback, ttl=0.
source "$(dirname "${BASH_SOURCE[0]}")/netns_common.bash"

# listen SOCKET LOG: every datagram on SOCKET becomes one line of LOG (newlines as '|').
listen() {
  python3 - "$1" "$2" <<'EOF' &
import os, socket, sys
path, log = sys.argv[1], sys.argv[2]
s = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
s.bind(path)
s.settimeout(60)  # bounded: the test ends it long before
with open(log, "a", buffering=1) as out:
    for _ in range(100000):
        try:
            data = s.recv(4096)
        except socket.timeout:
            break
        out.write(data.decode("utf-8", "replace").replace("\n", "|") + "\n")
EOF
  PIDS+=($!)
  for _ in $(seq 100); do [ -S "$1" ] && return 0; sleep 0.05; done
  fail "the notify socket $1 did not appear"
}

# wait_line LOG REGEX FROM: waits (at most 10 s) until a line after line FROM of LOG matches;
# prints its line number.
wait_line() {
  for _ in $(seq 200); do
    local n
    n=$(awk -v from="$3" -v re="$2" 'NR > from && $0 ~ re { print NR; exit }' "$1")
    [ -n "$n" ] && { echo "$n"; return 0; }
    sleep 0.05
  done
  return 1
}

check_service() {  # NAME COMMAND...
  local name=$1; shift
  local sock="$T/$name.sock" log="$T/$name.notify" stall="$T/$name.stall"
  : >"$log"
  listen "$sock" "$log"
  NOTIFY_SOCKET="$sock" WATCHDOG_USEC=600000 SPINDOWN_TEST_STALL_FILE="$stall" "$@" >"$T/$name.out" 2>"$T/$name.err" &
  local pid=$!; PIDS+=($pid)

  local ready
  ready=$(wait_line "$log" '^READY=1' 0) || fail "$name: no READY=1 ($(tr '\n' ' ' <"$log"))"
  awk -v r="$ready" 'NR < r && /WATCHDOG=1/ { exit 1 }' "$log" || fail "$name: WATCHDOG=1 before READY=1"
  local at=$ready
  for i in 1 2 3; do
    at=$(wait_line "$log" '^WATCHDOG=1$' "$at") || fail "$name: only $((i - 1)) WATCHDOG=1 after READY=1"
  done

  # Freeze the main loop: from its "test stall" status on, no ping may come.
  touch "$stall"
  local frozen
  frozen=$(wait_line "$log" '^STATUS=test stall: main loop blocked' "$at") || fail "$name: the loop never reached its stall point"
  sleep 2
  local during
  during=$(awk -v f="$frozen" 'NR > f && /^WATCHDOG=1$/' "$log" | wc -l)
  rm -f "$stall"
  [ "$during" = 0 ] || fail "$name: $during WATCHDOG=1 while its main loop was blocked"
  local over
  over=$(wait_line "$log" '^STATUS=test stall over' "$frozen") || fail "$name: the stall did not end"
  wait_line "$log" '^WATCHDOG=1$' "$over" >/dev/null || fail "$name: no WATCHDOG=1 after the loop went on"

  stop "$pid"
  local rc=0
  wait "$pid" || rc=$?
  [ "$rc" = 0 ] || fail "$name: exit $rc after SIGTERM"
  wait_line "$log" '^STOPPING=1' "$over" >/dev/null || fail "$name: no STOPPING=1"
  local pings
  pings=$(grep -c '^WATCHDOG=1$' "$log")
  echo "ok: $name: READY=1, $pings WATCHDOG=1, none in 2 s with its loop blocked, STOPPING=1"
}

mkdir -p "$T/logs"
check_service fitter "$B/spindown-fitter" --lcm-url "$URL" --no-explain
check_service logger "$B/spindown-logger" --lcm-url "$URL" --dir "$T/logs"
check_service bridge "$B/spindown-bridge" --lcm-url "$URL" --bench wd1 --device "$T/no-such-tty" --retry-interval 0.1

# Outside systemd (no NOTIFY_SOCKET) the services run as before.
"$B/spindown-logger" --lcm-url "$URL" --dir "$T/logs" >"$T/plain.out" 2>"$T/plain.err" &
plain=$!; PIDS+=($plain)
sleep 0.5
kill -0 "$plain" || fail "the logger without NOTIFY_SOCKET did not keep running"
stop "$plain"
echo "PASS: READY=1, WATCHDOG=1 only while the main loop runs, STOPPING=1 (fitter, logger, bridge)"
