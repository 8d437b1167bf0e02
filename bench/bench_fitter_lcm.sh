#!/bin/bash
# Fitter load benchmark with real LCM traffic: BENCHES benches at RATE Hz (one sample per
# message, as the bridge publishes the lab sketch), RUNS runs each, in real time, into one
# spindown-fitter, inside a private network namespace (ttl=0). Reports the fitter's CPU
# (utime+stime from /proc/<pid>/stat over the whole load), the detection-to-publish latency
# (fit_t.latency_s) and how long after each run's true stop its FIT arrived.
# Usage: bench/bench_fitter_lcm.sh [BIN_DIR] [BENCHES] [RATE_HZ] [RUNS]
if [ -z "${SPINDOWN_IN_NETNS:-}" ]; then exec unshare -n env SPINDOWN_IN_NETNS=1 bash "$0" "$@"; fi
set -euo pipefail
ip link set lo up; ip route add 224.0.0.0/4 dev lo
B=${1:-${SPINDOWN_BIN_DIR:-build/bin}}; N=${2:-100}; RATE=${3:-50}; RUNS=${4:-2}
URL='udpm://239.255.76.67:7667?ttl=0'
T=$(mktemp -d /tmp/spindown-bench-fitter.XXXXXX)
"$B/spindown-fitter" --lcm-url "$URL" 2>"$T/fitter.err" & F=$!
trap 'kill $F 2>/dev/null || true; rm -rf "$T"' EXIT
sleep 0.5
ticks() { awk '{print $14 + $15}' /proc/$F/stat; }
t0=$(date +%s.%N); c0=$(ticks)
"$B/spindown-run-publisher" --lcm-url "$URL" --benches "$N" --runs "$RUNS" --period "$(echo "1/$RATE" | bc -l)" \
  --speed 1 --wait-fits 30 --report "$T/report.json" >"$T/summary.json" 2>"$T/publisher.err"
t1=$(date +%s.%N); c1=$(ticks)
kill -INT $F; wait $F || true
python3 - "$T/summary.json" "$t0" "$t1" "$c0" "$c1" "$(getconf CLK_TCK)" "$N" "$RATE" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
t0, t1, c0, c1, hz = map(float, sys.argv[2:7])
cpu = (c1 - c0) / hz / (t1 - t0)
print(f"benches {sys.argv[7]} at {sys.argv[8]} Hz, {s['messages']} messages in {t1 - t0:.1f} s")
print(f"fits {s['fits']}/{s['expected_fits']} (matched to truth {s['matched']})")
print(f"fitter CPU: {100 * cpu:.2f} % of one core")
l = s["latency_s"]; a = s["after_true_stop_s"]
print(f"detection -> FIT published: p50 {1e3*l['p50']:.2f} ms, p95 {1e3*l['p95']:.2f} ms, max {1e3*l['max']:.2f} ms")
print(f"true stop -> FIT received:  p50 {a['p50']:.3f} s, p95 {a['p95']:.3f} s, max {a['max']:.3f} s")
PY
tail -1 "$T/fitter.err"
