#!/usr/bin/env bash
# A board replugged in the live lab (issue 31, case 1), over a lab network of namespaces (veth
# to a bridge device, ttl=1; deploy/lab/lab_netns.bash): bench-1's Arduino is unplugged between
# its runs 2 and 3, its bridge exits (--exit-on-missing) and a new bridge process starts when the
# board is back — what udev's `systemctl try-restart spindown-bridge@bench-1` does. The new bridge
# starts at sequence 0 and the board's clock at 0. bench-2 runs on beside it. Checks, against
# the virtual benches' truth:
#   - every run of both benches has its live fit (cut within 0.2 s of the truth): the replugged
#     board's runs after the replug too (before issue 31: 2 of its 4, the rest "repeated");
#   - no sample was taken as "repeated"; the fitter and watch named the new source;
#   - the fits name the bridge session their samples came from (two for bench-1);
#   - `spindown refit` of the log equals the live fits.
source "$(dirname "$0")/lab_common.bash"

lab_netns_up "sdrp$$" 2 || fail "could not build the namespaces"
lab_start_services

# bench-1: 4 runs; the cable is pulled for 2 s (bench time) in the idle after run 2.
SPEED=20
UNPLUG_AT=${REPLUG_UNPLUG_AT:-78}
lab_profile 1 bench-1
lab_start "${LAB_NS_BENCH[0]}" bench-1.bench "$LAB_BIN/spindown-virtual-bench" "${LAB_BENCH_ARGS[@]}" --runs 4 \
  --speed "$SPEED" --idle 4.0 --link "$LAB_WORK/bench-1.tty" --truth "$LAB_WORK/bench-1.truth.json" \
  --wait-reader 30 --linger 1 --unplug-at "$UNPLUG_AT" --unplug-for 2
lab_wait "[[ -L '$LAB_WORK/bench-1.tty' ]]" 15 || fail "bench-1 made no pty"
lab_start "${LAB_NS_BENCH[0]}" bench-1.bridge "$LAB_BIN/spindown-bridge" --device "$LAB_WORK/bench-1.tty" \
  --bench bench-1 --lcm-url "$URL" --config "$LAB_WORK/bench-1.toml" --exit-on-missing
lab_start_bench "${LAB_NS_BENCH[1]}" bench-2 3 "$URL" 2 "$SPEED" || fail "bench-2 did not start"

# The board goes away: its bridge exits. When the board is back (a new pty), a new bridge starts.
rc=0
lab_wait_exit bench-1.bridge 120 || rc=$?
((rc == 1)) || fail "bench-1's bridge did not exit when its board went away (code $rc)"
lab_wait "(( \$(grep -c . '$LAB_WORK/bench-1.bench.out') >= 2 ))" 60 || fail "bench-1's board did not come back"
echo "bench-1 unplugged: its bridge exited; the board is back on $(tail -1 "$LAB_WORK/bench-1.bench.out"): a new bridge"
lab_start "${LAB_NS_BENCH[0]}" bench-1.bridge2 "$LAB_BIN/spindown-bridge" --device "$LAB_WORK/bench-1.tty" \
  --bench bench-1 --lcm-url "$URL" --config "$LAB_WORK/bench-1.toml"

for b in bench-1 bench-2; do
  rc=0
  lab_wait_exit "$b.bench" 150 || rc=$?
  ((rc == 0)) || fail "virtual bench $b ended with code $rc"
done
python3 - "$LAB_WORK/bench-1.truth.json" <<'PY' || fail "the unplug did not fall in the idle between runs 2 and 3"
import json, sys
t = json.load(open(sys.argv[1]))
runs, unplug = t["runs"], t["unplug"]["bench_s"]
stop2, cut3 = runs[1]["cut_bench_s"] + runs[1]["t_stop_s"], runs[2]["cut_bench_s"]
print(f"bench-1: unplugged at bench time {unplug:.2f} s, between run 2's stop ({stop2:.2f} s) and run 3's cut ({cut3:.2f} s)")
sys.exit(0 if stop2 < unplug and unplug + t["unplug"]["for_s"] < cut3 else 1)
PY
lab_end_session "$LAB_WORK/bench-1.truth.json" "$LAB_WORK/bench-2.truth.json" -- bench-1.bridge2 bench-2.bridge

# 1. Every run of both benches has its live fit, the replugged board's too.
"$LAB_BIN/spindown" refit "$LOG" --live --json >"$LAB_WORK/live.json" 2>"$LAB_WORK/refit-live.err" || fail "refit --live"
python3 "$src/deploy/lab/lab_fits.py" check-runs "$LAB_WORK/live.json" "bench-1=$LAB_WORK/bench-1.truth.json" \
  "bench-2=$LAB_WORK/bench-2.truth.json" || fail "a run of the replugged board (or of bench-2) has no live fit"

# 2. Nothing "repeated"; the new source named by the fitter and by watch.
grep -q 'stopped: .* 0 duplicates' "$LAB_WORK/fitter.err" || fail "the fitter took samples as repeated"
grep -q 'sources: 1 new sources, 0 two sources' "$LAB_WORK/fitter.err" || fail "the fitter did not count one new source"
grep -q 'SPINDOWN.bench-1.SAMPLE: a new source: host .* (the bridge restarted or the board was replugged)' \
  "$LAB_WORK/fitter.err" || fail "the fitter did not name the new source"
grep -q '  bench-1: a new source: host ' "$LAB_WORK/watch.out" || fail "watch did not show the new source"

# 3. The fits name the bridge session their samples came from: two for bench-1, one for bench-2.
"${SPINDOWN_PYTHON:-python3}" - "$LOG" <<'PY' || fail "the FIT messages do not name their bridge sessions"
import os, sys
sys.path.insert(0, os.environ["SPINDOWN_PYTHON_DIR"])
import spindown_log
s = {}
for m in spindown_log.SpindownLog(sys.argv[1]).messages(kinds={"FIT"}):
    s.setdefault(m.bench, set()).add((m.message.bridge_host, m.message.bridge_session))
print("bridge sessions named by the FITs:", {b: len(v) for b, v in s.items()})
sys.exit(0 if len(s.get("bench-1", [])) == 2 and len(s.get("bench-2", [])) == 1 else 1)
PY

# 4. The refit of the log equals the live fits.
"$LAB_BIN/spindown" refit "$LOG" --compare >"$LAB_WORK/compare.out" 2>"$LAB_WORK/compare.err" ||
  { cat "$LAB_WORK/compare.out"; fail "refit --compare found differences"; }
grep -q "$EXPECTED runs refitted, $EXPECTED live FIT messages: $EXPECTED identical, 0 different" "$LAB_WORK/compare.out" ||
  { cat "$LAB_WORK/compare.out"; fail "refit --compare counts"; }
echo "PASS lab_replug: $EXPECTED of $EXPECTED runs fitted live, the replugged board's 4 included; 0 repeated; refit == live"
