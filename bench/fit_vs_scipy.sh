#!/usr/bin/env bash
# spindown fit beside the lab's SciPy analysis on the same 1000 generated runs (bench/make_runs:
# the virtual bench's simulator, lab friction, 4 mV noise, 1 % ripple, 10-bit ADC on 5 V,
# 2-decimal printing, ~1500 samples per PuTTY log). Whole-process wall time of each:
#   spindown:  `spindown fit --json` over all files in one process (reading, segmentation, the
#              three models with standard errors, best model, JSON out)
#   SciPy:     bench/scipy_lab_fits.py: np.loadtxt per file and curve_fit of the lab's three
#              curves on the coast, the cut and the stop given for free (Debian's python3-scipy)
# Best of REPEAT (3) runs each, files in the page cache; prints both, their ratio and the load.
# Usage: bench/fit_vs_scipy.sh [BIN_DIR]   (default build/bin; env RUNS=1000 REPEAT=3 KEEP=DIR)
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
# shellcheck source=bench/bench_common.bash
source "$ROOT/bench/bench_common.bash"
BIN=${1:-${SPINDOWN_BIN_DIR:-$ROOT/build/bin}}
RUNS=${RUNS:-1000}
REPEAT=${REPEAT:-3}
PY=/usr/bin/python3
for p in spindown make_runs; do
  [[ -x $BIN/$p ]] || { echo "missing $BIN/$p (build it first)" >&2; exit 2; }
done
$PY -c 'import scipy, numpy' 2>/dev/null || { echo "python3-scipy not installed" >&2; exit 2; }
bench_work_dir vs-scipy

generated_runs "$BIN" "$RUNS"

wall() {  # wall OUT CMD...: seconds of wall time, stdout to OUT
  awk "BEGIN{printf \"%.4f\", $(wall_us "$1" "$WORK/stderr.txt" "${@:2}") / 1e6}"
}
best() { printf '%s\n' "$@" | sort -g | head -1; }

ours=() theirs=()
for ((i = 0; i < REPEAT; i++)); do
  ours+=("$(wall "$WORK/spindown.json" "$BIN/spindown" fit --json "${FILES[@]}")")
  theirs+=("$(wall "$WORK/scipy.tsv" "$PY" "$ROOT/bench/scipy_lab_fits.py" fit "$WORK/runs")")
done
o=$(best "${ours[@]}") t=$(best "${theirs[@]}")

# Both sides must have fitted every run.
fitted=$($PY -c "import json,sys; d=json.load(open(sys.argv[1])); print(sum(1 for f in d['files'] for r in f['runs'] if r.get('best')))" "$WORK/spindown.json")
scipy_ok=$(awk -F'\t' 'NR > 1 && $4 != "nan" && $5 != "nan" {n++} END {print n + 0}' "$WORK/scipy.tsv")
split=$(grep '^{' "$WORK/stderr.txt" | tail -1)

echo "machine: $(lscpu | sed -n 's/^Model name: *//p'), $(nproc) cores; load average $(cut -d' ' -f1-3 /proc/loadavg)"
printf '%-44s %8s s  (%.2f ms per run; runs with a best model: %s/%s)\n' "spindown fit --json, $RUNS files, one process" \
  "$o" "$(awk "BEGIN{print 1000 * $o / $RUNS}")" "$fitted" "$RUNS"
printf '%-44s %8s s  (%.2f ms per run; combined fits converged: %s/%s)\n' "SciPy curve_fit x3 (scipy_lab_fits.py)" \
  "$t" "$(awk "BEGIN{print 1000 * $t / $RUNS}")" "$scipy_ok" "$RUNS"
echo "  SciPy's own split (last run): $split"
printf 'ratio SciPy / spindown: %.1fx  (best of %d; all: spindown %s, SciPy %s)\n' "$(awk "BEGIN{print $t / $o}")" \
  "$REPEAT" "${ours[*]}" "${theirs[*]}"
