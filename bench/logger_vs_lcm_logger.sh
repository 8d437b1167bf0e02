#!/usr/bin/env bash
# spindown-logger beside Debian's lcm-logger 1.3.1 on the same traffic (design §7), in a private
# network namespace over real UDP multicast:
#   A  burst: 4 benches × N messages as fast as the publisher sends, then SIGTERM at once
#   B  quiet tail: 200 messages at 100 Hz, 2 s of silence, then SIGKILL
#   C  load: 100 benches at 50 Hz for 10 s (5000 msg/s): CPU of each logger, drops
#   K  issue 6: KILL_BURST (50,000) messages at full speed, a 200 ms pause, then SIGKILL; with
#      spindown-logger's default flush interval (0.5 s) and with --flush-interval 0.1. What
#      spindown-logger must keep: every message sent more than one flush interval before the kill
#      (counted from the publisher's first/last send time, the burst's rate being uniform).
# Each line also gives the datagrams the kernel dropped at that logger's socket (its receive
# buffer full: /proc/net/udp "drops"): traffic the logger never saw, as opposed to traffic it
# read and lost.
# Usage: bench/logger_vs_lcm_logger.sh [BIN_DIR]   (default build/bin)
# ONLY=K runs scenario K alone.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BIN=${1:-${SPINDOWN_BIN_DIR:-$ROOT/build/bin}}
for p in spindown-logger spindown-lcm-publish spindown-log-summary; do
  [[ -x $BIN/$p ]] || { echo "missing $BIN/$p (build it first)" >&2; exit 2; }
done
command -v lcm-logger >/dev/null || { echo "lcm-logger not installed" >&2; exit 2; }
if [[ -z "${SPINDOWN_IN_NETNS:-}" ]]; then exec env SPINDOWN_IN_NETNS=1 unshare -n bash "$0" "$BIN"; fi
ip link set lo up
ip route add 224.0.0.0/4 dev lo
# What the loggers' receive buffers can be: the kernel caps what each asks for (spindown-logger: its
# --recv-buf) at this.
echo "net.core.rmem_max = $(cat /proc/sys/net/core/rmem_max)"
URL='udpm://239.255.76.67:7667?ttl=0'
WORK=$(mktemp -d /tmp/spindown-logger-bench.XXXXXX)
PIDS=()
trap 'for p in "${PIDS[@]}"; do kill -KILL "$p" 2>/dev/null || true; done; rm -rf "$WORK"' EXIT

count() {  # count FILE...: SAMPLE messages in LCM logs
  "$BIN/spindown-log-summary" "$@" | python3 -c 'import json,sys; print(json.load(sys.stdin)["sample_messages"])'
}
cpu_ticks() { awk '{print $14 + $15}' "/proc/$1/stat"; }
# socket_inodes PID: the inodes of the sockets PID holds (its LCM receive socket among them).
socket_inodes() {
  local fd link
  for fd in /proc/"$1"/fd/*; do
    link=$(readlink "$fd") || continue
    if [[ $link == socket:\[*\] ]]; then link=${link#socket:[}; echo "${link%]}"; fi
  done
}
# kernel_drops VAR INODE...: sets VAR to the datagrams the kernel dropped at these UDP sockets
# (/proc/net/udp "drops"). Read while the sockets exist, before their process ends; no fork, so
# it delays nothing measurable.
kernel_drops() {
  local -n total=$1; shift
  local f inode
  total=0
  while read -r -a f; do
    for inode in "$@"; do
      if [[ ${f[9]} == "$inode" ]]; then total=$((total + f[${#f[@]} - 1])); fi
    done
  done </proc/net/udp
}
start_both() {  # start_both DIR [FLUSH_INTERVAL_S]
  mkdir -p "$1/ours" "$1/theirs"
  "$BIN/spindown-logger" --lcm-url "$URL" --dir "$1/ours" ${2:+--flush-interval "$2"} -q 2>"$1/ours.err" &
  OURS=$!
  lcm-logger -q --lcm-url="$URL" -c 'SPINDOWN\..*' "$1/theirs/lcmlog.lcm" 2>"$1/theirs.err" &
  THEIRS=$!
  PIDS+=("$OURS" "$THEIRS")
  sleep 1
  mapfile -t OURS_SOCKETS < <(socket_inodes "$OURS")
  mapfile -t THEIRS_SOCKETS < <(socket_inodes "$THEIRS")
}
read_drops() {  # read_drops: OURS_DROPS and THEIRS_DROPS, the kernel's drops at each logger's sockets
  kernel_drops OURS_DROPS "${OURS_SOCKETS[@]}"
  kernel_drops THEIRS_DROPS "${THEIRS_SOCKETS[@]}"
}
stop_both() {  # stop_both SIGNAL
  kill "-$1" "$OURS" "$THEIRS"
  wait "$OURS" 2>/dev/null || true
  wait "$THEIRS" 2>/dev/null || true
}

now_us() { date +%s%6N; }
json_field() { python3 -c "import json,sys; print(json.load(open(sys.argv[1]))[sys.argv[2]])" "$1" "$2"; }

kill_after_burst() {  # kill_after_burst DIR FLUSH_S (empty = the logger's default, 0.5 s)
  local n=${KILL_BURST:-50000} flush=${2:-0.5}
  start_both "$1" "$2"
  "$BIN/spindown-lcm-publish" --lcm-url "$URL" --bench burst --count "$n" --rate 0 >"$1/pub.json"
  read_drops  # final already: loopback delivers (or drops) each datagram within the sender's call
  sleep 0.2
  local kill_us; kill_us=$(now_us)
  stop_both KILL
  local first last protected
  first=$(json_field "$1/pub.json" first_utime)
  last=$(json_field "$1/pub.json" last_utime)
  # Sent before kill − flush interval, at the burst's uniform rate.
  protected=$(python3 -c "
n, first, last, edge = $n, $first, $last, $kill_us - $flush * 1e6
print(n if edge >= last else max(0, int(n * (edge - first) / max(last - first, 1))))")
  printf '   flush %-4s s  burst %.3f s, kill %.3f s after its end; %d sent > one flush interval before the kill\n' \
    "$flush" "$(awk "BEGIN{print ($last - $first) / 1e6}")" "$(awk "BEGIN{print ($kill_us - $last) / 1e6}")" "$protected"
  printf '   %-16s %8s of %d, %d dropped by the kernel\n' spindown-logger "$(count "$1"/ours/*.lcm)" "$n" "$OURS_DROPS"
  printf '   %-16s %8s of %d, %d dropped by the kernel\n' lcm-logger "$(count "$1"/theirs/*)" "$n" "$THEIRS_DROPS"
}

if [[ ${ONLY:-} == K ]]; then
  echo "K  ${KILL_BURST:-50000} messages at full speed, 200 ms pause, SIGKILL"
  kill_after_burst "$WORK/k1" ""
  kill_after_burst "$WORK/k2" 0.1
  exit 0
fi

N=${BURST:-20000}
echo "A  burst of $((4 * N)) messages (4 benches, publisher at full speed), SIGTERM right after"
start_both "$WORK/a"
"$BIN/spindown-lcm-publish" --lcm-url "$URL" --benches 4 --count "$N" --rate 0 >/dev/null
read_drops
stop_both TERM
printf '   %-16s %8s of %d, %d dropped by the kernel\n' spindown-logger "$(count "$WORK"/a/ours/*.lcm)" $((4 * N)) "$OURS_DROPS"
printf '   %-16s %8s of %d, %d dropped by the kernel\n' lcm-logger "$(count "$WORK"/a/theirs/*)" $((4 * N)) "$THEIRS_DROPS"

echo "B  200 messages at 100 Hz, 2 s of silence, then SIGKILL"
start_both "$WORK/b"
"$BIN/spindown-lcm-publish" --lcm-url "$URL" --bench quiet --count 200 --rate 100 >/dev/null
sleep 2
read_drops
stop_both KILL
printf '   %-16s %8s of 200, %d dropped by the kernel\n' spindown-logger "$(count "$WORK"/b/ours/*.lcm)" "$OURS_DROPS"
printf '   %-16s %8s of 200, %d dropped by the kernel\n' lcm-logger "$(count "$WORK"/b/theirs/*)" "$THEIRS_DROPS"

echo "C  100 benches at 50 Hz for 10 s, SIGTERM after"
start_both "$WORK/c"
o0=$(cpu_ticks "$OURS"); t0=$(cpu_ticks "$THEIRS")
"$BIN/spindown-lcm-publish" --lcm-url "$URL" --benches 100 --count 500 --rate 50 >"$WORK/c/pub.json"
o1=$(cpu_ticks "$OURS"); t1=$(cpu_ticks "$THEIRS")
read_drops
stop_both TERM
hz=$(getconf CLK_TCK)
sent=$(python3 -c "import json; print(json.load(open('$WORK/c/pub.json'))['sample_messages'])")
secs=10
printf '   %-16s %8s of %s messages, %d dropped by the kernel, CPU %.1f %% of one core\n' spindown-logger \
  "$(count "$WORK"/c/ours/*.lcm)" "$sent" "$OURS_DROPS" "$(awk "BEGIN{print 100 * ($o1 - $o0) / $hz / $secs}")"
printf '   %-16s %8s of %s messages, %d dropped by the kernel, CPU %.1f %% of one core\n' lcm-logger \
  "$(count "$WORK"/c/theirs/*)" "$sent" "$THEIRS_DROPS" "$(awk "BEGIN{print 100 * ($t1 - $t0) / $hz / $secs}")"

echo "K  ${KILL_BURST:-50000} messages at full speed, 200 ms pause, SIGKILL"
kill_after_burst "$WORK/k1" ""
kill_after_burst "$WORK/k2" 0.1
