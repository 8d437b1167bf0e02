#!/usr/bin/env bash
# Two builds of `spindown fit --json` on the same 1000 generated runs, run in alternation so that
# a VM's drift (±15 % within minutes here) falls on both alike: wall best and median of each, and
# byte-identity of their stdout and stderr.
# Usage: bench/fit_ab.sh OLD_BIN_DIR NEW_BIN_DIR   (env ROUNDS=20 RUNS=1000 KEEP=DIR)
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
# shellcheck source=bench/bench_common.bash
source "$ROOT/bench/bench_common.bash"
OLD=${1:?usage: fit_ab.sh OLD_BIN_DIR NEW_BIN_DIR}
NEW=${2:?usage: fit_ab.sh OLD_BIN_DIR NEW_BIN_DIR}
ROUNDS=${ROUNDS:-20}
RUNS=${RUNS:-1000}
((ROUNDS >= 1 && ROUNDS <= 1000)) || { echo "ROUNDS must be 1..1000" >&2; exit 2; }
for b in "$OLD" "$NEW"; do [[ -x $b/spindown ]] || { echo "missing $b/spindown" >&2; exit 2; }; done
[[ -x $NEW/make_runs ]] || { echo "missing $NEW/make_runs (build it first)" >&2; exit 2; }
bench_work_dir fit-ab
generated_runs "$NEW" "$RUNS" >/dev/null

run() {  # run BIN TAG: wall in microseconds; stdout and stderr kept per tag
  : >"$WORK/$2.err"
  wall_us "$WORK/$2.json" "$WORK/$2.err" "$1/spindown" fit --json "${FILES[@]}"
}
old=() new=()
for ((r = 0; r < ROUNDS; r++)); do
  old+=("$(run "$OLD" old)")
  new+=("$(run "$NEW" new)")
done
stats() { printf '%s\n' "$@" | sort -n | awk '{a[NR] = $1} END {printf "best %.1f ms, median %.1f ms", a[1] / 1000, a[int((NR + 1) / 2)] / 1000}'; }
echo "machine: $(lscpu | sed -n 's/^Model name: *//p'), $(nproc) cores; load average $(cut -d' ' -f1-3 /proc/loadavg)"
echo "old $OLD: $(stats "${old[@]}")  (${#FILES[@]} files, $ROUNDS rounds)"
echo "new $NEW: $(stats "${new[@]}")"
if cmp -s "$WORK/old.json" "$WORK/new.json" && cmp -s "$WORK/old.err" "$WORK/new.err"; then
  echo "output: byte-identical (stdout and stderr)"
else
  echo "output: DIFFERS (compare $WORK/old.json and $WORK/new.json; KEEP=DIR keeps them)"
fi
