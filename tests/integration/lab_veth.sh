#!/usr/bin/env bash
# The lab over a (virtual) lab network: three benches in their own network namespaces, each a
# virtual bench on a pty + spindown-bridge, joined by veth to a bridge device in a "lab"
# namespace holding spindown-fitter, spindown-logger and spindown watch; LCM udpm with ttl=1
# and a multicast route in every namespace (deploy/lab/lab_netns.bash). Checks:
#   - every run of every bench gets its fit (cut within 0.2 s of the bench's truth), published
#     live and recorded in the log;
#   - the log holds every sample: per bench, SAMPLE seq 0..N-1 with no gap, N = what the bench
#     sent;
#   - `spindown refit` of the log equals the live fits (timing fields aside);
#   - spindown watch, in the lab namespace, showed each fit, and every bench and service in its
#     last table.
# Everything runs inside `unshare -n` and namespaces it creates; nothing touches the host's
# network. Bounded waits everywhere.
source "$(dirname "$0")/lab_common.bash"

BENCHES=(bench-1 bench-2 bench-3)
RUNS=2
lab_session "$RUNS" 20 "${BENCHES[@]}"

# 1. Every run of every bench has its fit, recorded in the log.
"$LAB_BIN/spindown" refit "$LOG" --live --json >"$LAB_WORK/live.json" 2>"$LAB_WORK/refit-live.err" ||
  fail "refit --live"
python3 "$src/deploy/lab/lab_fits.py" check-runs "$LAB_WORK/live.json" "${TRUTH_ARGS[@]}" ||
  fail "some run has no live fit"

# 2. The log holds every sample the benches sent: seq 0..N-1, no gap, per bench.
"$LAB_BIN/spindown-log-summary" "$LOG" >"$LAB_WORK/summary.json" || fail "spindown-log-summary"
python3 - "$LAB_WORK/summary.json" "${TRUTH_ARGS[@]}" <<'PY' || fail "the log misses samples"
import json, sys
benches = json.load(open(sys.argv[1])).get("benches", {})
bad = False
for arg in sys.argv[2:]:
    bench, _, path = arg.partition("=")
    sent = json.load(open(path))["samples"]
    s = benches.get(bench)
    if s is None:
        print(f"{bench}: no SAMPLE in the log"); bad = True; continue
    first, nxt = s.get("first_seq"), s.get("next_seq")
    ok = first == 0 and nxt == sent and s["samples"] == sent and s["gaps"] == 0 and s["missing"] == 0
    print(f"{bench}: sent {sent} samples; log holds seq {first}..{nxt - 1} ({s['samples']} samples, "
          f"{s['gaps']} gaps, {s['repeats']} repeats) -> {'complete' if ok else 'INCOMPLETE'}")
    bad |= not ok
sys.exit(1 if bad else 0)
PY

# 3. The refit of the log equals the live fits.
"$LAB_BIN/spindown" refit "$LOG" --compare >"$LAB_WORK/compare.out" 2>"$LAB_WORK/compare.err" ||
  { cat "$LAB_WORK/compare.out"; fail "refit --compare found differences"; }
grep -q "$EXPECTED runs refitted, $EXPECTED live FIT messages: $EXPECTED identical, 0 different" \
  "$LAB_WORK/compare.out" || { cat "$LAB_WORK/compare.out"; fail "refit --compare counts"; }
echo "refit == live: $(tail -1 "$LAB_WORK/compare.out" | sed 's|^.*: \([0-9]* runs refitted\)|\1|')"

# 4. The watch in the lab namespace saw every fit, every bench and the services.
for b in "${BENCHES[@]}"; do
  for ((r = 1; r <= RUNS; ++r)); do
    grep -q "  $b: run $r fit: best " "$LAB_WORK/watch.out" || fail "watch did not show $b run $r's fit"
  done
  grep -q "  $b: bridge connected" "$LAB_WORK/watch.out" || fail "watch did not show $b's bridge connecting"
  # The row: its last run stopped, the bridge's lines, the last fit's model, the combined model's
  # c3 and c4 with their errors.
  watch_last_table | grep -Eq "^  $b  +$RUNS stopped .* [0-9]+/0 .* run $RUNS [a-z]+ .*[0-9]±[0-9.]+ +[0-9.()e-]+±[0-9]" ||
    fail "watch's last table has no row for $b with its last run stopped and fitted"
done
watch_last_table | grep -q "^  fitter fitter  " || fail "watch's last table has no fitter row"
watch_last_table | grep -q "^  logger " || fail "watch's last table has no logger row"
echo "watch's last table:"
watch_last_table
echo "PASS lab_veth: $EXPECTED runs on ${#BENCHES[@]} benches in separate namespaces, all fitted, log complete, refit == live"
