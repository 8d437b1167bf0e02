# Shared by the "using the data elsewhere" tests (java_matlab_route.sh, python_reader.sh;
# sourced, not a test itself): on top of logger_common.bash (private network namespace, WORK,
# PIDS, fail), make_lab_log records a real log of a small lab and exports it as spindown export
# --csv writes it.
source "$(dirname "${BASH_SOURCE[0]}")/logger_common.bash"
SRC=${SPINDOWN_SOURCE_DIR:-$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)}

# make_lab_log DIR: spindown-logger records spindown-run-publisher (3 benches, one spin-down each,
# SAMPLE and CONFIG as the bridges publish them) and spindown-fitter (RUN, FIT, EXPLAIN and its
# STATUS); the logger's own STATUS is in the log too. Sets LAB_LOG to the log and LAB_CSV to its
# `spindown export --csv` (fits beside it in LAB_FITS_CSV).
make_lab_log() {
  local dir=$1
  mkdir -p "$dir/log"
  start_logger lab-logger --lcm-url "$URL" --dir "$dir/log" --prefix lab --flush-interval 0.2
  local logger=$LOGGER_PID
  wait_for_log "$dir/log"
  "$BIN/spindown-fitter" --lcm-url "$URL" --status-period 0.5 >"$WORK/lab-fitter.out" 2>"$WORK/lab-fitter.err" &
  local fitter=$!
  PIDS+=("$fitter")
  sleep 0.3
  timeout 120 "$BIN/spindown-run-publisher" --lcm-url "$URL" --benches 3 --runs 1 --speed 40 --batch 4 --stagger 0.3 \
    --wait-fits 30 --report "$dir/report.json" >"$WORK/lab-publisher.out" 2>"$WORK/lab-publisher.err" ||
    fail "spindown-run-publisher: $(tail -5 "$WORK/lab-publisher.err")"
  sleep 0.5   # the fitter's last STATUS
  kill -TERM "$fitter"
  for _ in $(seq 100); do kill -0 "$fitter" 2>/dev/null || break; sleep 0.1; done
  stop_logger "$logger"
  [[ $LOGGER_RC == 0 ]] || fail "the logger exited with $LOGGER_RC"
  local logs=("$dir"/log/*.lcm)
  (( ${#logs[@]} == 1 )) || fail "want one log, got ${#logs[@]}"
  LAB_LOG=${logs[0]}
  python3 -c 'import json,sys; r=json.load(open(sys.argv[1])); n=len(r["fit_list"]); assert n == 3, n' \
    "$dir/report.json" || fail "the fitter did not fit the 3 runs: $(cat "$dir/report.json")"
  LAB_CSV=$dir/samples.csv
  LAB_FITS_CSV=$dir/samples.fits.csv
  "$BIN/spindown" export "$LAB_LOG" --csv -o "$LAB_CSV" 2>"$WORK/lab-export.err" ||
    fail "spindown export: $(cat "$WORK/lab-export.err")"
  echo "lab log: $LAB_LOG ($(stat -c %s "$LAB_LOG") bytes), $(( $(wc -l <"$LAB_CSV") - 1 )) samples exported"
}
