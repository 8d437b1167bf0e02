#!/usr/bin/env bash
# Wall clocks that step back in a signed lab (issue 42 item 3), in a lab of namespaces (ttl=1):
# the bench PC's clock steps back 120 s (twice the replay window) while run 1 coasts, then the lab
# PC's clock (its fitter and logger) steps back 600 s while run 2 coasts — an NTP correction, a
# laptop waking. libfaketime steps CLOCK_REALTIME only (the monotonic clock runs on), of those
# processes only; the virtual bench (the Arduino) is not touched. Checks, against its truth:
#   - nothing is refused: the fitter counts 0 unsigned, 0 badly signed, 0 replayed;
#   - every run has its live FIT, whole, none closed "silent"; the refit of the log with the key
#     gives every run too.
source "$(dirname "$0")/lab_common.bash"

FAKETIME_LIB=""
for f in /usr/lib/x86_64-linux-gnu/faketime/libfaketime.so.1 /usr/lib/faketime/libfaketime.so.1; do
  [[ -r $f ]] && { FAKETIME_LIB=$f; break; }
done
[[ -n $FAKETIME_LIB ]] || fail "libfaketime is not installed (deploy/setup --tests installs faketime)"
# stepped FILE: the env command line that offsets a program's wall clock by what FILE says ("+0",
# "-120"), re-read every second, the monotonic clock untouched.
stepped() {
  STEPPED=(env LD_PRELOAD="$FAKETIME_LIB" FAKETIME_TIMESTAMP_FILE="$1" FAKETIME_CACHE_DURATION=1
           DONT_FAKE_MONOTONIC=1 FAKETIME_DONT_FAKE_MONOTONIC=1)
}

lab_netns_up "sdcs$$" 1 || fail "could not build the namespaces"
KEY=$LAB_WORK/lab.key
"$LAB_BIN/spindown" keygen -o "$KEY" >/dev/null || fail "spindown keygen"
echo "+0" >"$LAB_WORK/bench-clock"
echo "+0" >"$LAB_WORK/lab-clock"
mkdir -p "$LAB_WORK/log"
stepped "$LAB_WORK/lab-clock"
lab_start "$LAB_NS_LAB" logger "${STEPPED[@]}" "$LAB_BIN/spindown-logger" --lcm-url "$URL" \
  --dir "$LAB_WORK/log" --prefix lab --flush-interval 0.2 --key "$KEY"
lab_start "$LAB_NS_LAB" fitter "${STEPPED[@]}" "$LAB_BIN/spindown-fitter" --lcm-url "$URL" \
  --status-period 0.5 -v --key "$KEY"
lab_wait "grep -qs channels '$LAB_WORK/logger.err' && grep -qs 'fitting benches' '$LAB_WORK/fitter.err'" 30 ||
  fail "the lab services did not start"
lab_profile 1 bench-1
lab_start "${LAB_NS_BENCH[0]}" bench-1.bench "$LAB_BIN/spindown-virtual-bench" "${LAB_BENCH_ARGS[@]}" --runs 3 \
  --speed 2 --idle 2 --link "$LAB_WORK/bench-1.tty" --truth "$LAB_WORK/bench-1.truth.json" --wait-reader 30 --linger 1
lab_wait "[[ -L '$LAB_WORK/bench-1.tty' ]]" 15 || fail "the virtual bench made no pty"
stepped "$LAB_WORK/bench-clock"
lab_start "${LAB_NS_BENCH[0]}" bench-1.bridge "${STEPPED[@]}" "$LAB_BIN/spindown-bridge" \
  --device "$LAB_WORK/bench-1.tty" --bench bench-1 --lcm-url "$URL" --config "$LAB_WORK/bench-1.toml" --key "$KEY"

lab_wait "grep -q 'bench-1 run 1 coasting' '$LAB_WORK/fitter.err'" 90 || fail "run 1 never started coasting"
sleep 1.5
echo "-120" >"$LAB_WORK/bench-clock"; echo "bench PC: wall clock 120 s back"
lab_wait "grep -q 'bench-1 run 2 coasting' '$LAB_WORK/fitter.err'" 90 || fail "run 2 never started coasting"
sleep 1.5
echo "-600" >"$LAB_WORK/lab-clock"; echo "lab PC: wall clock 600 s back"
rc=0
lab_wait_exit bench-1.bench 150 || rc=$?
((rc == 0)) || fail "the virtual bench ended with code $rc"
lab_wait "(( \$(lab_fits_published) >= 3 ))" 30 || echo "note: $(lab_fits_published) fits published"
sleep 1.2
lab_stop bench-1.bridge 5 || fail "bridge: exit code $? on SIGTERM"
lab_stop fitter 10 || fail "fitter: exit code $? on SIGTERM"
lab_stop logger 15 || fail "logger: exit code $? on SIGTERM"
echo "fitter: $(grep 'spindown-fitter: sources:' "$LAB_WORK/fitter.err" | sed 's/^spindown-fitter: //')"

grep -q "not used: 0 of another lab, 0 unsigned, 0 badly signed, 0 replayed" "$LAB_WORK/fitter.err" ||
  fail "the fitter refused messages after a clock step"
grep -q " 0 silent benches" "$LAB_WORK/fitter.err" || fail "a run was closed as silent"
LOG=$(lab_only_log "$LAB_WORK/log")
"$LAB_BIN/spindown" refit "$LOG" --live --json --key "$KEY" >"$LAB_WORK/live.json" 2>/dev/null || fail "refit --live --key"
python3 "$src/deploy/lab/lab_fits.py" check-runs "$LAB_WORK/live.json" "bench-1=$LAB_WORK/bench-1.truth.json" ||
  fail "a run has no live FIT after a clock step"
"$LAB_BIN/spindown" refit "$LOG" --json --key "$KEY" >"$LAB_WORK/refit.json" 2>/dev/null || fail "refit --key"
python3 "$src/deploy/lab/lab_fits.py" check-runs "$LAB_WORK/refit.json" "bench-1=$LAB_WORK/bench-1.truth.json" ||
  fail "the log does not refit whole after the clock steps"
echo "PROMISE clock steps: bench PC -120 s and lab PC -600 s mid-coast, signed: 0 refused, $(lab_fits_published) of 3 runs fitted live, refit whole"
