#!/usr/bin/env bash
# Two labs on one network (issue 31, case 3), as namespaces on one bridge device (ttl=1): lab A
# ("lab-a") and lab B ("lab-b") each have a bench called bench-1 — different motors — and the
# same port; lab B changed only the group (239.255.76.68 for 239.255.76.67). One PC (the "lab"
# namespace) serves both: lab A's fitter, logger and watch and lab B's fitter run there, so Linux
# hands both groups to every socket on that port (the trap docs/lab-setup.md describes); lab B's
# logger runs on a PC of its own. For a while a second lab-A fitter with the default instance
# name runs on lab B's PC. Checks, against each virtual bench's truth:
#   - each lab's fitter fitted exactly its own bench-1's runs (cuts within 0.2 s of its truth),
#     never the other lab's: the other lab's messages reached it and were counted (other_lab);
#   - lab A's log, refitted for lab A, has lab A's runs only; each lab's log refitted without
#     --lab has that lab's runs only (the lab its logger served);
#   - `spindown doctor` on the shared PC names lab B's traffic on lab A's group and port;
#   - the two lab-A fitters named each other, and watch showed it.
source "$(dirname "$0")/lab_common.bash"

URL_A='udpm://239.255.76.67:7667?ttl=1'
URL_B='udpm://239.255.76.68:7667?ttl=1'
lab_netns_up "sd2l$$" 3 || fail "could not build the namespaces"
NS_A1=${LAB_NS_BENCH[0]} NS_B1=${LAB_NS_BENCH[1]} NS_B=${LAB_NS_BENCH[2]}
mkdir -p "$LAB_WORK/log-a" "$LAB_WORK/log-b"
lab_start "$LAB_NS_LAB" logger-a "$LAB_BIN/spindown-logger" --lcm-url "$URL_A" --lab lab-a --dir "$LAB_WORK/log-a" \
  --prefix lab --flush-interval 0.2
lab_start "$LAB_NS_LAB" fitter "$LAB_BIN/spindown-fitter" --lcm-url "$URL_A" --lab lab-a --status-period 0.5 -v
lab_start "$LAB_NS_LAB" fitter-b "$LAB_BIN/spindown-fitter" --lcm-url "$URL_B" --lab lab-b --status-period 0.5 -v
lab_start "$LAB_NS_LAB" watch "$LAB_BIN/spindown" watch --lcm-url "$URL_A" --lab lab-a --plain --interval 5 --duration 250
lab_start "$NS_B" logger-b "$LAB_BIN/spindown-logger" --lcm-url "$URL_B" --lab lab-b --dir "$LAB_WORK/log-b" \
  --prefix lab --flush-interval 0.2
lab_wait "grep -q channels '$LAB_WORK/logger-a.err' && grep -q channels '$LAB_WORK/logger-b.err' &&
          grep -q 'fitting benches' '$LAB_WORK/fitter.err' && grep -q 'fitting benches' '$LAB_WORK/fitter-b.err' &&
          grep -q listening '$LAB_WORK/watch.out'" 30 || fail "the labs' services did not start"

# bench-1 of each lab: lab A's the students' motor (profile 1), lab B's an oily 1000 rpm/V one (profile 3).
SPEED=10
start_bench() {  # NS LAB URL PROFILE NAME
  lab_profile "$4" "$5"
  lab_start "$1" "$5.bench" "$LAB_BIN/spindown-virtual-bench" "${LAB_BENCH_ARGS[@]}" --runs 2 --speed "$SPEED" \
    --idle 1.0 --link "$LAB_WORK/$5.tty" --truth "$LAB_WORK/$5.truth.json" --wait-reader 30 --linger 1
  lab_wait "[[ -L '$LAB_WORK/$5.tty' ]]" 15 || fail "$5 made no pty"
  lab_start "$1" "$5.bridge" "$LAB_BIN/spindown-bridge" --device "$LAB_WORK/$5.tty" --bench bench-1 --lcm-url "$3" \
    --lab "$2" --config "$LAB_WORK/$5.toml"
}
start_bench "$NS_A1" lab-a "$URL_A" 1 a-bench-1
start_bench "$NS_B1" lab-b "$URL_B" 3 b-bench-1

# A second lab-A fitter, started with the default instance name on another PC (fitting nothing).
sleep 2
lab_start "$NS_B" fitter-dup "$LAB_BIN/spindown-fitter" --lcm-url "$URL_A" --lab lab-a --status-period 0.5 --bench none
# The shared PC's doctor, while both labs run.
ip netns exec "$LAB_NS_LAB" "$LAB_BIN/spindown" doctor --lcm-url "$URL_A" --lab lab-a --checks lab --listen 3 \
  >"$LAB_WORK/doctor.out" 2>"$LAB_WORK/doctor.err" || true
lab_stop fitter-dup 10 || fail "the second fitter: exit code $? on SIGTERM"

for b in a-bench-1 b-bench-1; do
  rc=0
  lab_wait_exit "$b.bench" 150 || rc=$?
  ((rc == 0)) || fail "virtual bench $b ended with code $rc"
done
A_RUNS=$(lab_truth_runs "$LAB_WORK/a-bench-1.truth.json")
B_RUNS=$(lab_truth_runs "$LAB_WORK/b-bench-1.truth.json")
fits_of() { grep -c ' fitted: ' "$LAB_WORK/$1.err" 2>/dev/null || true; }
lab_wait "(( \$(fits_of fitter) >= $A_RUNS && \$(fits_of fitter-b) >= $B_RUNS ))" 60 ||
  echo "note: fitter A published $(fits_of fitter) fits, fitter B $(fits_of fitter-b)"
sleep 1.2
for b in a-bench-1 b-bench-1; do lab_stop "$b.bridge" 5 || fail "$b bridge: exit code $? on SIGTERM"; done
for f in fitter fitter-b; do lab_stop "$f" 10 || fail "$f: exit code $? on SIGTERM"; done
sleep 0.5
lab_stop watch 5 || fail "watch: exit code $? on SIGTERM"
for l in logger-a logger-b; do lab_stop "$l" 15 || fail "$l: exit code $? on SIGTERM"; done
LOG_A=$(lab_only_log "$LAB_WORK/log-a")
LOG_B=$(lab_only_log "$LAB_WORK/log-b")
[[ -n $LOG_A && -n $LOG_B ]] || fail "a lab's log is missing"
for f in fitter fitter-b; do echo "$f: $(grep 'spindown-fitter: sources:' "$LAB_WORK/$f.err" | sed 's/^spindown-fitter: //')"; done

# 1. Each fitter fitted its own lab's motor only (lab A's FITs from lab A's log, lab B's from B's).
"$LAB_BIN/spindown" refit "$LOG_A" --live --json --lab lab-a >"$LAB_WORK/live-a.json" 2>/dev/null || fail "refit --live A"
"$LAB_BIN/spindown" refit "$LOG_B" --live --json --lab lab-b >"$LAB_WORK/live-b.json" 2>/dev/null || fail "refit --live B"
python3 "$src/deploy/lab/lab_fits.py" check-runs "$LAB_WORK/live-a.json" "bench-1=$LAB_WORK/a-bench-1.truth.json" ||
  fail "lab A's fitter: its runs are not exactly lab A's"
python3 "$src/deploy/lab/lab_fits.py" check-runs "$LAB_WORK/live-b.json" "bench-1=$LAB_WORK/b-bench-1.truth.json" ||
  fail "lab B's fitter: its runs are not exactly lab B's"
# The motors differ (lab B's is oily: mostly viscous): each lab's dry friction c4 is nearer its own
# motor's truth than the other lab's motor's.
python3 - "$LAB_WORK/live-a.json" "$LAB_WORK/a-bench-1.truth.json" "$LAB_WORK/live-b.json" \
  "$LAB_WORK/b-bench-1.truth.json" <<'PY' || fail "a lab's friction is the other lab's"
import json, sys
truth = {k: json.load(open(p))["c_c"] for k, p in (("A", sys.argv[2]), ("B", sys.argv[4]))}
ok = True
for lab, live in (("A", sys.argv[1]), ("B", sys.argv[3])):
    other = "B" if lab == "A" else "A"
    for f in json.load(open(live))["files"]:
        for r in f["runs"]:
            c4 = [m["params"]["c4"]["value"] for m in r["models"] if m["name"] == "combined"][0]
            good = abs(c4 - truth[lab]) < abs(c4 - truth[other])
            ok &= good
            print(f"lab {lab} run {r['run']}: c4 {c4:.4g} N·m; lab {lab}'s motor {truth[lab]:.4g}, lab {other}'s "
                  f"{truth[other]:.4g} -> {'its own' if good else 'THE OTHER LAB'}")
sys.exit(0 if ok else 1)
PY
"$LAB_BIN/spindown" refit "$LOG_A" --lab lab-a --compare >"$LAB_WORK/compare-a.out" 2>/dev/null ||
  { cat "$LAB_WORK/compare-a.out"; fail "lab A: refit --compare found differences"; }
grep -q "$A_RUNS runs refitted, $A_RUNS live FIT messages: $A_RUNS identical, 0 different" "$LAB_WORK/compare-a.out" ||
  { cat "$LAB_WORK/compare-a.out"; fail "lab A's log refitted for lab A has another lab's runs"; }

# 1b. Refit as a user would, without --lab (issue 42 item 4): a log refits the lab its logger
# served (its heartbeat in the log says which), so lab A's log, which holds lab B's traffic too,
# gives lab A's runs only; lab B's log lab B's. Before, both took the default lab name.
for l in a b; do
  log_var="LOG_${l^^}"
  "$LAB_BIN/spindown" refit "${!log_var}" --json >"$LAB_WORK/refit-$l.json" 2>"$LAB_WORK/refit-$l.err" ||
    { cat "$LAB_WORK/refit-$l.err"; fail "refit of lab ${l^^}'s log without --lab failed"; }
  grep -q "recorded by the logger of lab 'lab-$l'" "$LAB_WORK/refit-$l.err" ||
    { cat "$LAB_WORK/refit-$l.err"; fail "refit of lab ${l^^}'s log did not say whose log it is"; }
  python3 "$src/deploy/lab/lab_fits.py" check-runs "$LAB_WORK/refit-$l.json" "bench-1=$LAB_WORK/$l-bench-1.truth.json" ||
    fail "lab ${l^^}'s log refitted without --lab: its runs are not exactly lab ${l^^}'s"
done

# 2. Each fitter heard the other lab (one PC, one port) and used none of it.
for f in fitter fitter-b; do
  grep -Eq 'sources: 0 new sources, 0 two sources at once .* not used: [1-9][0-9]* of another lab' "$LAB_WORK/$f.err" ||
    fail "$f: the other lab's messages were not counted as another lab's (or were taken as a second source)"
done
grep -q "a message of lab 'lab-b', this program serves lab 'lab-a'" "$LAB_WORK/fitter.err" ||
  fail "lab A's fitter did not name lab B's traffic"

# 3. The shared PC's doctor names lab B on lab A's group and port.
cat "$LAB_WORK/doctor.out"
grep -q "warn  lab traffic .*another lab's traffic on $URL_A .*lab 'lab-b'" "$LAB_WORK/doctor.out" ||
  fail "doctor did not name lab B's traffic"

# 4. The two lab-A fitters named each other; watch showed it.
for f in fitter fitter-dup; do
  grep -q "two fitters with the same instance name 'fitter' on this lab at once" "$LAB_WORK/$f.err" ||
    fail "$f did not name the other lab-A fitter"
done
grep -q "two fitters with the same instance name 'fitter' on this lab at once" "$LAB_WORK/watch.out" || fail "watch did not show the collision"
echo "PASS lab_two_labs: lab A $A_RUNS of $A_RUNS runs, lab B $B_RUNS of $B_RUNS, each only its own; lab B named on lab A's port; the fitter collision named"
