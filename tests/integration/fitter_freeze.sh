#!/usr/bin/env bash
# The fitter frozen mid-coast, and stopped mid-coast (issue 31): two virtual benches in their own
# network namespaces, joined by veth to the lab namespace with the fitter, the logger and
# `spindown watch` (ttl=1), at real speed.
#   freeze  SIGSTOP of the fitter for 15 s while both benches coast (--silent 10), then SIGCONT:
#           what waited in its socket is its backlog, not silence; no run is closed "silent",
#           no cut is invented, the frozen runs keep their true cuts
#   stop    SIGTERM of the fitter while bench-1 coasts its run 2: the open runs are published
#           abandoned ("fitter stopping") with a last STATUS, so watch never shows them coasting
# Judged against the benches' truth.
source "$(dirname "$0")/lab_faults_common.bash"

LAB_RUNS=2
FITTER_OPTS=(--silent 10)
lab_faults_start bench-1 bench-2
lab_start "$LAB_NS_LAB" watch "$LAB_BIN/spindown" watch --lcm-url "$URL" --plain --interval 1 --duration 250

# --- freeze ------------------------------------------------------------------------------------
lab_faults_wait_coasting bench-1 1
sleep 2
kill -STOP "${LAB_PID[fitter]}"
sleep 15
kill -CONT "${LAB_PID[fitter]}"
lab_wait "grep -q 'the backlog is handled' '$LAB_WORK/fitter.err'" 20 || fail "freeze: the fitter never handled its backlog"
grep "no message handled for\|backlog is handled" "$LAB_WORK/fitter.err"

# --- stop mid-coast ----------------------------------------------------------------------------
lab_faults_wait_coasting bench-1 2 120
sleep 2
lab_stop fitter 10 || fail "fitter: exit code $? on SIGTERM"
grep -q "spindown-fitter: bench-1 run 2 abandoned: fitter stopping" "$LAB_WORK/fitter.err" ||
  fail "stop: the fitter did not publish bench-1's run 2 abandoned"
sleep 2.5  # the watch prints a table or two
lab_stop watch 5 || true
lab_faults_finish

lab_faults_judge freeze '
assert not [f for f in fits if f["end"] == "silent"], "a run was closed silent: the backlog was taken for silence"
b1 = [f for f in fits if f["bench"]["id"] == "bench-1"]
assert b1 and b1[0]["lead_in"] != "none", b1
'
# The last STATUS said "stopping" with the runs it abandoned, and it reached the log.
PYTHONPATH=${SPINDOWN_PYTHON_DIR:?} "${SPINDOWN_PYTHON:-python3}" - "$LOG" <<'PY' || fail "stop: the log"
import sys
import spindown_log
log = spindown_log.SpindownLog(sys.argv[1])
beats = [m.message for m in log.messages(kinds={"STATUS"}, bench="fitter")]
last = beats[-1]
counters = dict(zip(last.counter_name, last.counter_value))
assert last.state == "stopping", last.state
assert counters["runs_abandoned"] >= 1, counters
stalls = max(dict(zip(b.counter_name, b.counter_value)).get("stalls", 0) for b in beats)
assert stalls >= 1, "the freeze was not counted"
runs = [m.message for m in log.messages(kinds={"RUN"}, bench="bench-1")]
last_run = runs[-1]
assert last_run.state == 3 and last_run.note.startswith("fitter stopping"), (last_run.state, last_run.note)
print(f"PROMISE stop: SIGTERM mid-coast: {counters['runs_abandoned']} open run(s) published abandoned "
      f"(\"{last_run.note[:40]}…\"), last STATUS \"stopping\"; the freeze counted as {stalls} stall(s)")
PY
# The watch's last table shows bench-1's run 2 abandoned, not coasting.
awk '/^spindown watch  /{t=""} {t=t $0 "\n"} END{printf "%s", t}' "$LAB_WORK/watch.out" >"$LAB_WORK/watch.last"
cat "$LAB_WORK/watch.last"
grep -Eq "^bench-1 +2 abandoned" "$LAB_WORK/watch.last" || fail "stop: watch does not show bench-1's run 2 abandoned"
echo "PASS fitter_freeze"
