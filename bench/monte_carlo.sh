#!/usr/bin/env bash
# The accuracy study of issue 6: RUNS (500) simulated lab runs at the lab's noise and
# quantization (truth: data/seed-3v-run1, combined friction), fitted by spindown
# (bench/monte_carlo, as `spindown fit` does it) and by SciPy curve_fit of the lab's combined
# curve on the same printed files (bench/scipy_lab_fits.py, cut and stop given for free), with
# the Cramér–Rao bound for the same sampling and noise. Prints bias, spread, efficiency and the
# calibration of the reported standard errors for c3 (c_v) and c4 (c_c).
# Usage: bench/monte_carlo.sh [BIN_DIR]   (default build/bin; env RUNS=500 SEED=1 TRUTH=… KEEP=DIR
#        ADC_BITS=10 DECIMALS=2: ADC_BITS=0 DECIMALS=-1 takes the lab's quantization out)
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
# shellcheck source=bench/bench_common.bash
source "$ROOT/bench/bench_common.bash"
BIN=${1:-${SPINDOWN_BIN_DIR:-$ROOT/build/bin}}
RUNS=${RUNS:-500}
SEED=${SEED:-1}
DATA=${SPINDOWN_SAMPLE_DATA:-$ROOT/data}
TRUTH=${TRUTH:-$DATA/seed-3v-run1.tsv.truth.json}
[[ -x $BIN/monte_carlo ]] || { echo "missing $BIN/monte_carlo (build it first)" >&2; exit 2; }
[[ -r $TRUTH ]] || { echo "no truth file $TRUTH (set TRUTH=… or SPINDOWN_SAMPLE_DATA)" >&2; exit 2; }
bench_work_dir mc
"$BIN/monte_carlo" "$WORK" "$RUNS" "$SEED" "$TRUTH" "${ADC_BITS:-10}" "${DECIMALS:-2}" >/dev/null
/usr/bin/python3 "$ROOT/bench/scipy_lab_fits.py" fit "$WORK" >"$WORK/scipy.tsv" 2>"$WORK/scipy.err" || true
/usr/bin/python3 "$ROOT/bench/scipy_lab_fits.py" mc-summary "$WORK"
