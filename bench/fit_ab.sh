#!/usr/bin/env bash
# Two builds of `spindown fit --json` on the same 1000 generated runs, run in alternation so that
# a VM's drift (±15 % within minutes here) falls on both alike: best and median wall and CPU time
# (user + system, every thread) of each, and byte-identity of their stdout and stderr.
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

run() {  # run BIN TAG: "wall_ms cpu_ms" (cpu: user + system, of all its threads); stdout and stderr kept per tag
  : >"$WORK/$2.err"
  local TIMEFORMAT='%R %U %S'
  { time "$1/spindown" fit --json "${FILES[@]}" >"$WORK/$2.json" 2>>"$WORK/$2.err"; } 2>&1 |
    awk '{printf "%.3f %.3f\n", $1 * 1000, ($2 + $3) * 1000}'
}
old=() new=() old_cpu=() new_cpu=()
for ((r = 0; r < ROUNDS; r++)); do  # alternate which goes first: a VM's drift falls on both alike
  if ((r % 2)); then read -r nw nc < <(run "$NEW" new); read -r ow oc < <(run "$OLD" old)
  else read -r ow oc < <(run "$OLD" old); read -r nw nc < <(run "$NEW" new); fi
  old+=("$ow") new+=("$nw") old_cpu+=("$oc") new_cpu+=("$nc")
done
stats() { printf '%s\n' "$@" | sort -n | awk '{a[NR] = $1} END {printf "best %.1f ms, median %.1f ms", a[1], a[int((NR + 1) / 2)]}'; }
echo "machine: $(lscpu | sed -n 's/^Model name: *//p'), $(nproc) cores; load average $(cut -d' ' -f1-3 /proc/loadavg)"
echo "old $OLD: wall $(stats "${old[@]}"); CPU $(stats "${old_cpu[@]}")  (${#FILES[@]} files, $ROUNDS rounds)"
echo "new $NEW: wall $(stats "${new[@]}"); CPU $(stats "${new_cpu[@]}")"
if cmp -s "$WORK/old.json" "$WORK/new.json" && cmp -s "$WORK/old.err" "$WORK/new.err"; then
  echo "output: byte-identical (stdout and stderr)"
else
  echo "output: DIFFERS (compare $WORK/old.json and $WORK/new.json; KEEP=DIR keeps them)"
fi
