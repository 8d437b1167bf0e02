#!/usr/bin/env bash
# `spindown refit` throughput and memory on generated LCM logs of two sizes (bench/make_lcm_log:
# 4 lab benches, one sample per SAMPLE message as the lab bridge publishes, CONFIG every 3 s,
# a run every ~30 s per bench). Target: ≥ 5 M samples/s on one core, peak memory flat in the
# log's size. Wall and CPU time and max RSS from /usr/bin/time -v; the log is in the page cache.
# Usage: bench/refit_throughput.sh [BIN_DIR]   (default build/bin; env SIZES="1000000 10000000"
#        BATCH=1 FORMAT=--json|"" KEEP=DIR)
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
# shellcheck source=bench/bench_common.bash
source "$ROOT/bench/bench_common.bash"
BIN=${1:-${SPINDOWN_BIN_DIR:-$ROOT/build/bin}}
SIZES=${SIZES:-1000000 10000000}
BATCH=${BATCH:-1}
FORMAT=${FORMAT---json}
for p in spindown make_lcm_log; do
  [[ -x $BIN/$p ]] || { echo "missing $BIN/$p (build it first)" >&2; exit 2; }
done
[[ -x /usr/bin/time ]] || { echo "/usr/bin/time not installed (Debian package time)" >&2; exit 2; }
bench_work_dir refit-bench

echo "machine: $(lscpu | sed -n 's/^Model name: *//p'), $(nproc) cores; load average $(cut -d' ' -f1-3 /proc/loadavg)"
printf '%-12s %9s %9s %8s %8s %12s %12s %9s %6s\n' samples "log MB" messages "wall s" "CPU s" "samples/s" "per CPU s" \
  "max RSS" runs
for n in $SIZES; do
  log="$WORK/lab-$n-b$BATCH.lcm"
  [[ -s $log ]] || "$BIN/make_lcm_log" "$log" "$n" 4 "$BATCH" >"$WORK/make-$n.txt"
  cat "$log" >/dev/null  # page cache
  /usr/bin/time -v -o "$WORK/time-$n.txt" "$BIN/spindown" refit $FORMAT "$log" >"$WORK/refit-$n.out" 2>"$WORK/refit-$n.err" || true
  wall=$(awk -F': ' '/Elapsed \(wall clock\)/ {n = split($2, a, ":"); s = 0; for (i = 1; i <= n; i++) s = s * 60 + a[i]; print s}' "$WORK/time-$n.txt")
  cpu=$(awk -F': ' '/User time/ {u = $2} /System time/ {s = $2} END {print u + s}' "$WORK/time-$n.txt")
  rss=$(awk -F': ' '/Maximum resident/ {printf "%.1f MB", $2 / 1024}' "$WORK/time-$n.txt")
  if [[ $FORMAT == --json ]]; then
    runs=$(/usr/bin/python3 -c "import json,sys; print(sum(len(f['runs']) for f in json.load(open(sys.argv[1]))['files']))" "$WORK/refit-$n.out")
  else
    runs=-
  fi
  msgs=$(awk '{for (i = 1; i <= NF; i++) if ($i == "SAMPLE") print $(i - 1)}' "$WORK/make-$n.txt" 2>/dev/null || echo -)
  printf '%-12s %9.1f %9s %8.2f %8.2f %12.0f %12.0f %9s %6s\n' "$n" "$(stat -c %s "$log" | awk '{print $1 / 1e6}')" \
    "$msgs" "$wall" "$cpu" "$(awk "BEGIN{print $n / $wall}")" "$(awk "BEGIN{print $n / $cpu}")" "$rss" "$runs"
done
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
