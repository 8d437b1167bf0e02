# Shared by tests/integration/lab_outage.sh and fitter_freeze.sh (sourced; not a test itself):
# the lab network of lab_common.bash (benches in their own namespaces, joined by veth to the
# lab namespace with the fitter and the logger; ttl=1), started without the watch, and the
# judge of a log's FIT messages against the virtual benches' truth.
source "$(dirname "${BASH_SOURCE[0]}")/lab_common.bash"

# lab_faults_start BENCH...: namespaces, the logger and the fitter (-v, --status-period 0.5,
# FITTER_OPTS…), then a virtual bench (profile 1, 2, … at --speed 1, LAB_RUNS runs) and its
# bridge per bench.
lab_faults_start() {
  local i
  LAB_BENCHES=("$@")
  lab_netns_up "sdf$$" "${#LAB_BENCHES[@]}" || fail "could not build the namespaces"
  mkdir -p "$LAB_WORK/log"
  lab_start "$LAB_NS_LAB" logger "$LAB_BIN/spindown-logger" --lcm-url "$URL" --dir "$LAB_WORK/log" --prefix lab \
    --flush-interval 0.2
  lab_start "$LAB_NS_LAB" fitter "$LAB_BIN/spindown-fitter" --lcm-url "$URL" --status-period 0.5 -v \
    "${FITTER_OPTS[@]}"
  lab_wait "grep -q channels '$LAB_WORK/logger.err' && grep -q 'fitting benches' '$LAB_WORK/fitter.err'" 30 ||
    fail "the lab services did not start"
  for ((i = 0; i < ${#LAB_BENCHES[@]}; ++i)); do
    lab_start_bench "${LAB_NS_BENCH[i]}" "${LAB_BENCHES[i]}" "$((i % 3 + 1))" "$URL" "$LAB_RUNS" 1 ||
      fail "bench ${LAB_BENCHES[i]} did not start"
  done
}

# lab_faults_wait_coasting BENCH RUN [SECONDS]: until the fitter says BENCH's run RUN is coasting.
lab_faults_wait_coasting() {
  lab_wait "grep -q 'spindown-fitter: $1 run $2 coasting' '$LAB_WORK/fitter.err'" "${3:-90}" ||
    fail "the fitter never said $1 run $2 coasting"
}

# lab_faults_finish: the benches play to their end; everything stops (SIGTERM); LOG is the log
# and $LAB_WORK/live.json its FIT messages (refit --live --json).
lab_faults_finish() {
  local b
  for b in "${LAB_BENCHES[@]}"; do
    lab_wait_exit "$b.bench" 200 || fail "virtual bench $b did not end well (code $?)"
  done
  sleep 3  # the last runs' tails and fits
  for b in "${LAB_BENCHES[@]}"; do lab_stop "$b.bridge" 5 || true; done
  [[ -n ${LAB_PID[fitter]:-} ]] && { lab_stop fitter 10 || fail "fitter: exit code $? on SIGTERM"; }
  sleep 0.5
  lab_stop logger 15 || fail "logger: exit code $? on SIGTERM"
  LOG=$(lab_only_log "$LAB_WORK/log")
  [[ -n $LOG ]] || fail "no log written"
  "$LAB_BIN/spindown" refit "$LOG" --live --json >"$LAB_WORK/live.json" 2>"$LAB_WORK/refit-live.err" ||
    fail "refit --live: $(cat "$LAB_WORK/refit-live.err")"
}

# lab_faults_judge NAME [PYTHON]: the FIT messages in the log against every bench's truth. A FIT
# that claims a cut (lead-in other than "none") must be within 1.5 sample periods of a true cut (a
# floating pin's: its connection, where the coast enters the readings)
# of its bench: 0 invented cuts, or the test fails. Prints "PROMISE NAME: …" with what was
# measured; PYTHON (optional) asserts more with fits, whole, partial and truth in scope.
lab_faults_judge() {
  local args=() b
  for b in "${LAB_BENCHES[@]}"; do args+=("$b=$LAB_WORK/$b.truth.json"); done
  python3 - "$LAB_WORK/live.json" "$1" "${2:-}" "${args[@]}" <<'PY' || fail "$1: judged against the truth"
import json, sys
doc = json.load(open(sys.argv[1]))
name, extra = sys.argv[2], sys.argv[3]
truth = {}
for arg in sys.argv[4:]:
    bench, _, path = arg.partition("=")
    truth[bench] = json.load(open(path))
fits = [r for f in doc["files"] for r in f["runs"]]
whole, partial, invented = [], [], []
for f in fits:
    t = truth[f["bench"]["id"]]
    # The cut a reader of the readings can see: a floating pin's connection (to its last sample of
    # contact bounce, which may hold the coast's first sample up), else the power cut.
    P = t["period_s"]
    cuts = [(r.get("connect_device_us", r["cut_device_us"]) / 1e6 - 1.5 * P,
             r.get("connect_device_us", r["cut_device_us"]) / 1e6 + (len(r.get("bounce_bench_s", [])) + 1.5) * P)
            for r in t["runs"] if "cut_device_us" in r]
    if f["lead_in"] == "none":
        partial.append(f)
    elif any(lo <= f["t_cut_s"] <= hi for lo, hi in cuts):
        whole.append(f)
    else:
        invented.append(f)
for f in fits:
    print(f"  FIT {f['bench']['id']} run {f['run']}: cut {f['t_cut_s']:.3f} s ({f['lead_in']}), end {f['end']} at "
          f"{f['t_end_s']:.3f} s, {f['samples']} samples")
true_runs = sum(len([r for r in t["runs"] if "cut_device_us" in r]) for t in truth.values())
assert not invented, "invented cuts: " + ", ".join(
    f"{f['bench']['id']} run {f['run']} cut {f['t_cut_s']:.3f} s ({f['lead_in']})" for f in invented)
exec(extra)
print(f"PROMISE {name}: {true_runs} true runs; {len(fits)} FITs: {len(whole)} with their true cut, "
      f"{len(partial)} partial, 0 invented cuts; ends: " +
      ", ".join(sorted({f['end'] for f in fits})))
PY
}
