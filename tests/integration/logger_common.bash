# Shared by tests/integration/logger_*.sh (sourced, not a test itself): re-runs the test inside
# a private network namespace (and mount namespace with SPINDOWN_NEED_MOUNT_NS=1) with multicast
# on loopback, and gives it a work directory, a cleanup of the processes it started and helpers.
set -euo pipefail
: "${SPINDOWN_BIN_DIR:?set SPINDOWN_BIN_DIR to the bin directory of a build}"
BIN=$SPINDOWN_BIN_DIR

if [[ -z "${SPINDOWN_IN_NETNS:-}" ]]; then
  flags=(-n)
  [[ "${SPINDOWN_NEED_MOUNT_NS:-}" == 1 ]] && flags+=(-m)
  if ! unshare "${flags[@]}" true 2>/dev/null; then
    echo "FAIL: cannot create a private namespace (unshare ${flags[*]}); these tests need root or user namespaces" >&2
    exit 1
  fi
  exec env SPINDOWN_IN_NETNS=1 unshare "${flags[@]}" bash "$0" "$@"
fi
ip link set lo up
ip route add 224.0.0.0/4 dev lo
URL='udpm://239.255.76.67:7667?ttl=0'

WORK=$(mktemp -d /tmp/spindown-logger-test.XXXXXX)
PIDS=()
cleanup() {
  for p in "${PIDS[@]}"; do kill -KILL "$p" 2>/dev/null || true; done
  if [[ "${KEEP_WORK:-}" == 1 ]]; then echo "work directory kept: $WORK"; else rm -rf "$WORK"; fi
}
trap cleanup EXIT

fail() { echo "FAIL: $*" >&2; exit 1; }
# json FILE EXPR: evaluate a Python expression over the JSON object d read from FILE.
json() { python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print($2)" "$1"; }
now_us() { echo $(( $(date +%s%N) / 1000 )); }

# Waits (at most 5 s) until a log file exists in DIR, then a little for the subscription.
wait_for_log() {
  local dir=$1
  for _ in $(seq 100); do
    compgen -G "$dir/*.lcm" >/dev/null && { sleep 0.3; return 0; }
    sleep 0.05
  done
  fail "no log file appeared in $dir"
}

# Starts spindown-logger in the background with the given arguments; its pid is in LOGGER_PID.
start_logger() {
  local name=$1; shift
  "$BIN/spindown-logger" "$@" >"$WORK/$name.out" 2>"$WORK/$name.err" &
  LOGGER_PID=$!
  PIDS+=("$LOGGER_PID")
}

# Stops the logger with SIGTERM and waits (at most 10 s); its exit code is in LOGGER_RC.
stop_logger() {
  local pid=$1
  kill -TERM "$pid"
  for _ in $(seq 200); do kill -0 "$pid" 2>/dev/null || break; sleep 0.05; done
  kill -0 "$pid" 2>/dev/null && fail "logger $pid did not stop within 10 s of SIGTERM"
  LOGGER_RC=0
  wait "$pid" || LOGGER_RC=$?
}

# Datagrams the kernel dropped in this network namespace because a UDP socket's receive buffer
# was full (Udp RcvbufErrors in /proc/net/snmp, nstat's UdpRcvbufErrors): traffic that never
# reached any process, as opposed to traffic a process read and then lost.
udp_rcvbuf_errors() {
  awk '$1 == "Udp:" { if (!col) { for (i = 2; i <= NF; i++) if ($i == "RcvbufErrors") col = i } else { print $col; exit } }' \
    /proc/net/snmp
}

# UDP sockets bound to PORT in this network namespace (/proc/net/udp): with one, the kernel's
# receive-buffer drops in the namespace are that socket's.
udp_sockets_on_port() {
  awk -v port="$(printf '%04X' "$1")" 'NR > 1 { split($2, a, ":"); if (a[2] == port) n++ } END { print n + 0 }' /proc/net/udp
}
