#!/usr/bin/env bash
# The server's switch port down mid-coast, and its route lost (issue 31): two virtual benches in
# their own network namespaces, joined by veth to a bridge in the lab namespace that holds the
# fitter and the logger (ttl=1), at real speed.
#   outage  every bench's port on the lab's bridge down for 21 s while bench-1 coasts (the
#           fitter's --silent is 10 s): the run is closed "silent" with its true cut, and what
#           resumes of that coast on the same clock is never given a cut (at most a partial run)
#   route   in run 2, the lab namespace's interface down and up (which drops its 224.0.0.0/4
#           route) and the route put back 6 s later: the fitter says on stderr that it cannot
#           publish, counts publish_failures, and that count reaches the log once the route is back
# Judged against the benches' truth: 0 invented cuts; every run of bench-2 whole.
source "$(dirname "$0")/lab_faults_common.bash"

LAB_RUNS=2
FITTER_OPTS=(--silent 10)
lab_faults_start bench-1 bench-2

# --- outage: the ports down 21 s mid-coast of bench-1's run 1 -----------------------------------
lab_faults_wait_coasting bench-1 1
sleep 3
for i in 1 2; do ip -n "$LAB_NS_LAB" link set "vb$i" down; done
echo "outage: ports down at $(date +%T.%N | cut -c1-12)"
sleep 21
for i in 1 2; do ip -n "$LAB_NS_LAB" link set "vb$i" up; done
echo "outage: ports up at $(date +%T.%N | cut -c1-12)"

# --- route: the lab's interface down and up mid-coast of run 2 ----------------------------------
# (bench-1's second cut the fitter saw: the rest of run 1 may have been a partial run before it)
lab_wait "(( \$(grep -c 'spindown-fitter: bench-1 run [0-9]* coasting: cut (lead-in' '$LAB_WORK/fitter.err') >= 2 ))" 120 ||
  fail "the fitter never saw bench-1's second cut"
sleep 2
ip -n "$LAB_NS_LAB" link set labnet down
sleep 1
ip -n "$LAB_NS_LAB" link set labnet up
ip -n "$LAB_NS_LAB" route show | grep -q '^224.0.0.0/4' && fail "the route survived the interface going down"
sleep 6
ip -n "$LAB_NS_LAB" route add 224.0.0.0/4 dev labnet
echo "route: put back at $(date +%T.%N | cut -c1-12)"
lab_faults_finish

lab_faults_judge outage '
b1 = [f for f in fits if f["bench"]["id"] == "bench-1"]
b2 = [f for f in fits if f["bench"]["id"] == "bench-2"]
assert b1[0]["end"] == "silent" and b1[0]["lead_in"] != "none", b1[0]
n2 = len([r for r in truth["bench-2"]["runs"] if "cut_device_us" in r])
assert len([f for f in b2 if f["lead_in"] != "none"]) == n2, "bench-2 lost a whole run"
end, rest = b1[0]["t_end_s"], len([f for f in b1 if f["lead_in"] == "none"])
print(f"outage: bench-1 run 1 closed silent at {end:.2f} s with its true cut; {rest} partial FITs of the rest of its coast")
'
grep -q "rest of run 1's coast" "$LAB_WORK/fitter.err" || echo "note: the rest of the coast was no run of its own"

# The route: said on stderr, counted, and the count reached the log.
grep -q "spindown-fitter: cannot publish on SPINDOWN\..*: Network is unreachable" "$LAB_WORK/fitter.err" ||
  fail "route: the fitter did not say it cannot publish"
grep -q "spindown-fitter: publishing works again" "$LAB_WORK/fitter.err" || fail "route: no word when publishing works again"
"$LAB_BIN/spindown-log-summary" "$LOG" >"$LAB_WORK/summary.json" || fail "spindown-log-summary"
failures=$(grep -o '[0-9]* publish failures' "$LAB_WORK/fitter.err" | tail -1 | grep -o '^[0-9]*')
((failures > 0)) || fail "route: the fitter's summary counts no publish failure"
PYTHONPATH=${SPINDOWN_PYTHON_DIR:?} "${SPINDOWN_PYTHON:-python3}" - "$LOG" "$failures" <<'PY' ||
import sys
import spindown_log
beats = [m.message for m in spindown_log.SpindownLog(sys.argv[1]).messages(kinds={"STATUS"}, bench="fitter")]
counts = [dict(zip(b.counter_name, b.counter_value)).get("publish_failures", 0) for b in beats]
assert counts and max(counts) > 0, f"no heartbeat in the log counts a publish failure ({len(beats)} heartbeats)"
first = next(i for i, c in enumerate(counts) if c > 0)
assert counts[first - 1] == 0 if first > 0 else True
print(f"PROMISE route: the interface down and up dropped the route for 7 s: {sys.argv[2]} sends failed, said on "
      f"stderr; the first heartbeat logged after the route came back counts {counts[first]} publish_failures")
PY
  fail "route: the count of publish failures did not reach the log"
echo "PASS lab_outage"
