#!/bin/bash
# Held-out cases for issue 31 (a bench's stream has an identity: replugs, outages, two labs,
# spoofers). Live lab over real LCM UDP multicast between network namespaces joined by veth
# pairs and a Linux bridge (a lab switch), ttl=1. Needs root (ip netns), lcm-logplayer (liblcm-bin).
#
# usage: run.sh BIN_DIR [SCRATCH_DIR]
# prints one PASS/FAIL line per case, then SUMMARY; exit 1 if any case failed.
set -u
if [ $# -lt 1 ] || [ ! -x "$1/spindown" ]; then
  echo "usage: $0 BIN_DIR [SCRATCH_DIR]  (BIN_DIR holds spindown, spindown-fitter, …)" >&2
  exit 2
fi
BIN=$(cd "$1" && pwd)
W=${2:-$(mktemp -d /tmp/h31.XXXXXX)}
mkdir -p "$W"; W=$(cd "$W" && pwd)
HERE=$(cd "$(dirname "$0")" && pwd)
PY=/usr/bin/python3
export PYTHONDONTWRITEBYTECODE=1
H31_TAG=$(printf '%x' $$)
START=$(date +%s)
RUNNER_LIMIT=290     # seconds: every case is killed past this (the whole runner < 5 min)
CASE_LIMIT=200       # seconds a case may take

for t in ip unshare lcm-logplayer; do
  command -v $t >/dev/null || { echo "FAIL setup: $t not installed"; echo "SUMMARY: 0/1 passed"; exit 1; }
done
if [ "$(id -u)" != 0 ]; then echo "FAIL setup: needs root (network namespaces)"; echo "SUMMARY: 0/1 passed"; exit 1; fi

. "$HERE/topo.sh"

# ---------------------------------------------------------------- helpers
now() { date +%s.%N; }
# sleep_until T0 OFFSET: sleep until OFFSET seconds after T0
sleep_until() {
  local d; d=$(awk -v a="$1" -v b="$2" -v n="$(date +%s.%N)" 'BEGIN{d=a+b-n; if(d<0)d=0; if(d>120)d=120; printf "%.3f", d}')
  sleep "$d"
}
# wait_for CMD TIMEOUT_S: poll CMD every 0.05 s, bounded
wait_for() {
  local cmd=$1 n; n=$(awk -v t="$2" 'BEGIN{printf "%d", t/0.05}')
  local i; for ((i=0; i<n; i++)); do eval "$cmd" && return 0; sleep 0.05; done
  return 1
}
# bg CASE HOST HOSTNAME OUT ERR CMD...: start in the background; LASTPID is its pid
bg() {
  local c=$1 h=$2 hn=$3 out=$4 err=$5; shift 5
  on "$c" "$h" "$hn" "$@" > "$out" 2> "$err" &
  LASTPID=$!
  H31_PIDS+=("$LASTPID")
}
# wait_exit PID TIMEOUT_S
wait_exit() {
  local p=$1 n; n=$(awk -v t="$2" 'BEGIN{printf "%d", t/0.1}')
  local i; for ((i=0; i<n; i++)); do kill -0 "$p" 2>/dev/null || return 0; sleep 0.1; done
  return 1
}
# stop PID: SIGTERM and wait (bounded), then SIGKILL
stop() { kill -TERM "$1" 2>/dev/null; wait_exit "$1" 5 || kill -KILL "$1" 2>/dev/null; wait "$1" 2>/dev/null; }
# bench CASE HOST HOSTNAME NAME ARGS...: a virtual bench; its pty path in $NAME.tty once printed
# (NAME may have a directory: A/bench-1); its pid in PID_VB_<NAME with _ for other characters>
bench() {
  local c=$1 h=$2 hn=$3 n=$4; shift 4
  bg "$c" "$h" "$hn" "$n.vb.out" "$n.vb.err" "$BIN/spindown-virtual-bench" --truth "$PWD/$n.truth.json" "$@"
  eval "PID_VB_${n//[^A-Za-z0-9]/_}=$LASTPID"
  wait_for "[ -s $n.vb.out ]" 5 || echo "bench $n printed no pty" >&2
  head -1 "$n.vb.out" > "$n.tty"
}
# bridge CASE HOST HOSTNAME BENCH DEVICE URL TAG: a spindown-bridge; pid in LASTPID
bridge() {
  bg "$1" "$2" "$3" "$4.$7.br.out" "$4.$7.br.err" "$BIN/spindown-bridge" --device "$5" --bench "$4" --lcm-url "$6"
}
# bridge_t0 ... (as bridge): start the first bridge of a bench and wait until it has opened the
# port (the virtual bench starts its clock then); T0 is that moment (±0.05 s)
bridge_t0() {
  bridge "$@"
  wait_for "grep -q connected $4.$7.br.err" 5 || echo "bridge of $4 did not connect" >&2
  T0=$(now)
}
# results: each case writes its line(s) to $W/results/<case>.txt
mkdir -p "$W/results"
result() { echo "$1" >> "$W/results/$CASE_FILE.txt"; }
runner_fail() { result "FAIL $1: runner: $2"; }

# fit_jsons ID LOG...: the live FITs (refit --live --json) and the refit (refit --json) of LOGs
fit_jsons() {
  local id=$1; shift
  timeout 60 "$BIN/spindown" refit --live --json "$@" > "$id.live.json" 2> "$id.live.err"
  timeout 60 "$BIN/spindown" refit --json "$@" > "$id.refit.json" 2> "$id.refit.err"
}
# judge_fits ID LOG SPEC... [opts]: judge.py fits over the log's live FITs and its refit
judge_fits() {
  local id=$1 log=$2; shift 2
  fit_jsons "$id" $log
  $PY "$HERE/judge.py" fits "$id" "$id.live.json" "$id.refit.json" "$@"
}

# ================================================================ cases
. "$HERE/cases.sh"

# ================================================================ main
CASES=(replug outage_cut frozen sigterm rotated replay twolabs_onepc twolabs_instance route_gone)
GROUPS_=("replug outage_cut frozen" "sigterm rotated replay" "twolabs_onepc twolabs_instance route_gone")
if [ -n "${H31_ONLY:-}" ]; then GROUPS_=("$H31_ONLY"); fi

master_cleanup() {
  local ns p
  for p in $(jobs -p); do kill -TERM "$p" 2>/dev/null; done
  sleep 0.5
  for ns in $(ip netns list 2>/dev/null | awk '{print $1}' | grep "^h31-$H31_TAG-"); do
    for p in $(ip netns pids "$ns" 2>/dev/null); do kill -KILL "$p" 2>/dev/null; done
    ip netns del "$ns" 2>/dev/null
  done
}
trap master_cleanup EXIT
trap 'exit 1' INT TERM

for grp in "${GROUPS_[@]}"; do
  pids=()
  for c in $grp; do
    (
      CASE_FILE=$c
      H31_PIDS=(); H31_NETNS=()
      trap cleanup_all EXIT
      mkdir -p "$W/$c" && cd "$W/$c" || exit 1
      "case_$c" > "$W/$c/case.log" 2>&1
    ) &
    pids+=($!)
  done
  for p in "${pids[@]}"; do
    left=$(( RUNNER_LIMIT - ($(date +%s) - START) ))
    [ $left -gt $CASE_LIMIT ] && left=$CASE_LIMIT
    [ $left -lt 1 ] && left=1
    if ! wait_exit "$p" "$left"; then
      kill -TERM "$p" 2>/dev/null; wait_exit "$p" 5 || kill -KILL "$p" 2>/dev/null
    fi
    wait "$p" 2>/dev/null
  done
done

pass=0; total=0; failed=0
for c in "${CASES[@]}"; do
  f="$W/results/$c.txt"
  if [ -n "${H31_ONLY:-}" ] && ! [[ " $H31_ONLY " == *" $c "* ]]; then continue; fi
  if [ ! -s "$f" ]; then
    echo "FAIL $c: runner: the case produced no verdict (timed out or crashed; see $W/$c/case.log)"
    total=$((total+1)); failed=1; continue
  fi
  while IFS= read -r line; do
    echo "$line"
    total=$((total+1))
    case "$line" in PASS*) pass=$((pass+1));; *) failed=1;; esac
  done < "$f"
done
echo "SUMMARY: $pass/$total passed"
echo "(scratch: $W; run time $(( $(date +%s) - START )) s)" >&2
[ $failed = 0 ] && exit 0 || exit 1
