# Shared by cli_baseline.sh, cli_report.sh, fitter_faults.sh and fitter_live_refit.sh (sourced;
# not a test itself): re-runs the calling script inside a private network namespace with
# multicast on loopback (ttl=0, design §7), and gives it B (the bin directory), a work directory
# T, the LCM URL, PIDS (killed on exit), fail and stop.
if [ -z "${SPINDOWN_IN_NETNS:-}" ]; then
  exec unshare -n env SPINDOWN_IN_NETNS=1 bash "$0" "$@"
fi
set -euo pipefail
ip link set lo up
ip route add 224.0.0.0/4 dev lo

B=${SPINDOWN_BIN_DIR:?}
T=$(mktemp -d "/tmp/spindown-$(basename "$0" .sh | tr _ -).XXXXXX")
URL='udpm://239.255.76.67:7667?ttl=0'
PIDS=()
cleanup() {
  for p in "${PIDS[@]}"; do kill "$p" 2>/dev/null || true; done
  wait 2>/dev/null || true
  [ -n "${SPINDOWN_KEEP_WORK:-}" ] && echo "work kept in $T" >&2 || rm -rf "$T"
}
trap cleanup EXIT
# fail MESSAGE: says what failed, shows the end of every program's output, exits 1.
fail() {
  echo "FAIL: $*" >&2
  for f in "$T"/*.err "$T"/*.out; do [ -f "$f" ] && { echo "--- $f" >&2; tail -20 "$f" >&2; }; done
  exit 1
}
# stop PID: SIGTERM, then wait at most 10 s for the process to end.
stop() {
  kill -TERM "$1" 2>/dev/null || true
  for _ in $(seq 100); do kill -0 "$1" 2>/dev/null || return 0; sleep 0.1; done
  fail "process $1 did not stop on SIGTERM"
}
