#!/usr/bin/env bash
# Changing the lab key (issue 42 item 5; docs/security.md "Changing the key"), in a lab of
# namespaces (ttl=1): a bench PC (virtual bench on a pty, spindown-bridge) and the lab PC
# (spindown-fitter, spindown-logger), all signing with the old key. Between runs, as the procedure
# says, every program is restarted three times: with --key OLD,NEW (sign old, accept both), then
# --key NEW,OLD (sign new, accept both), then --key NEW. Checks, against the virtual bench's truth:
#   - nothing was refused by any fitter (0 unsigned, 0 badly signed, 0 replayed) and every run of
#     the bench has its live FIT, whole;
#   - the session's logs (one per logger) refit whole with --key NEW,OLD;
#   - with the new key alone, the refit names the old key and how to give both.
source "$(dirname "$0")/lab_common.bash"

lab_netns_up "sdkr$$" 1 || fail "could not build the namespaces"
BENCH_NS=${LAB_NS_BENCH[0]}
OLD=$LAB_WORK/old.key NEW=$LAB_WORK/new.key
"$LAB_BIN/spindown" keygen -o "$OLD" >/dev/null || fail "spindown keygen (old)"
"$LAB_BIN/spindown" keygen -o "$NEW" >/dev/null || fail "spindown keygen (new)"
mkdir -p "$LAB_WORK/log"

# start_step STEP KEYS: the lab PC's logger and fitter and the bench PC's bridge, all with --key KEYS.
start_step() {
  local step=$1 keys=$2
  lab_start "$LAB_NS_LAB" "logger-$step" "$LAB_BIN/spindown-logger" --lcm-url "$URL" --dir "$LAB_WORK/log" \
    --prefix "lab-$step" --flush-interval 0.2 --key "$keys"
  lab_start "$LAB_NS_LAB" "fitter-$step" "$LAB_BIN/spindown-fitter" --lcm-url "$URL" --status-period 0.5 -v \
    --key "$keys"
  lab_wait "grep -qs channels '$LAB_WORK/logger-$step.err' && grep -qs 'fitting benches' '$LAB_WORK/fitter-$step.err'" 30 ||
    fail "step $step: the lab services did not start"
  lab_start "$BENCH_NS" "bridge-$step" "$LAB_BIN/spindown-bridge" --device "$LAB_WORK/bench-1.tty" --bench bench-1 \
    --lcm-url "$URL" --config "$LAB_WORK/bench-1.toml" --key "$keys"
}
stop_step() {
  local step=$1
  lab_stop "bridge-$step" 5 || fail "bridge-$step: exit code $? on SIGTERM"
  lab_stop "fitter-$step" 10 || fail "fitter-$step: exit code $? on SIGTERM"
  lab_stop "logger-$step" 15 || fail "logger-$step: exit code $? on SIGTERM"
}
fits() { cat "$LAB_WORK"/fitter-*.err 2>/dev/null | grep -c ' fitted: ' || true; }

lab_profile 1 bench-1
lab_start "$BENCH_NS" bench-1.bench "$LAB_BIN/spindown-virtual-bench" "${LAB_BENCH_ARGS[@]}" --runs 4 --speed 4 \
  --idle 16 --link "$LAB_WORK/bench-1.tty" --truth "$LAB_WORK/bench-1.truth.json" --wait-reader 30 --linger 1
lab_wait "[[ -L '$LAB_WORK/bench-1.tty' ]]" 15 || fail "the virtual bench made no pty"
start_step 0 "$OLD"
steps=("$OLD,$NEW" "$NEW,$OLD" "$NEW")
for i in 1 2 3; do
  lab_wait "(( \$(fits) >= $i ))" 90 || fail "run $i was not fitted before step $i"
  stop_step $((i - 1))
  start_step "$i" "${steps[i - 1]}"
  echo "step $i: every program restarted with --key ${steps[i - 1]//$LAB_WORK\//} after $(fits) fits"
done
rc=0
lab_wait_exit bench-1.bench 150 || rc=$?
((rc == 0)) || fail "the virtual bench ended with code $rc"
lab_wait "(( \$(fits) >= 4 ))" 30 || echo "note: $(fits) fits published"
sleep 1.2
stop_step 3

# 1. No fitter refused anything, and every run has its live FIT, whole.
for f in "$LAB_WORK"/fitter-*.err; do
  grep -q "not used: 0 of another lab, 0 unsigned, 0 badly signed, 0 replayed" "$f" ||
    fail "$(basename "$f" .err) refused messages: $(grep 'sources:' "$f")"
done
mapfile -t LOGS < <(ls "$LAB_WORK"/log/*.lcm)
((${#LOGS[@]} == 4)) || fail "want 4 log files (one per logger), got ${#LOGS[@]}"
"$LAB_BIN/spindown" refit "${LOGS[@]}" --live --json --key "$NEW,$OLD" >"$LAB_WORK/live.json" 2>"$LAB_WORK/live.err" ||
  fail "refit --live with both keys"
python3 "$src/deploy/lab/lab_fits.py" check-runs "$LAB_WORK/live.json" "bench-1=$LAB_WORK/bench-1.truth.json" ||
  fail "a run has no live FIT (a key change lost or cut one)"

# 2. The session refits whole with both keys.
"$LAB_BIN/spindown" refit "${LOGS[@]}" --json --key "$NEW,$OLD" >"$LAB_WORK/refit.json" 2>"$LAB_WORK/refit.err" ||
  { cat "$LAB_WORK/refit.err"; fail "refit with both keys"; }
python3 "$src/deploy/lab/lab_fits.py" check-runs "$LAB_WORK/refit.json" "bench-1=$LAB_WORK/bench-1.truth.json" ||
  fail "the session does not refit whole with --key NEW,OLD"

# 3. With the new key alone, the old key's messages are named, with the way to give both.
rc=0
"$LAB_BIN/spindown" refit "${LOGS[@]}" --key "$NEW" >"$LAB_WORK/refit-new.out" 2>"$LAB_WORK/refit-new.err" || rc=$?
echo "refit with the new key alone: exit $rc"
grep -q -- "--key NEW,OLD" "$LAB_WORK/refit-new.out" "$LAB_WORK/refit-new.err" ||
  fail "refit with the new key alone does not say how to give both"
echo "PROMISE key rotation: 3 restarts of every program between runs (OLD,NEW / NEW,OLD / NEW): 0 refused, $(fits) of 4 runs fitted live, 4 logs refitted whole with --key NEW,OLD"
