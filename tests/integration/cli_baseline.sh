#!/bin/bash
# Motor health end to end. `spindown baseline` makes a baseline from three generated good runs
# and writes it into a bench file in place (its other keys and comments kept); `spindown fit
# --bench-config` then says "service" for a run with 2.5× the Coulomb friction and "ok" for
# another good run (text and --json). spindown-fitter --bench-config DIR publishes the verdict in
# the FIT message (read back from the log by `spindown refit --live --json`). Private network
# namespace, ttl=0.
source "$(dirname "${BASH_SOURCE[0]}")/netns_common.bash"
SRC=${SPINDOWN_SOURCE_DIR:?}

# ---- generated Arduino logs: the lab's bench, combined friction, noise, 2 decimals ---------------
python3 - "$T" <<'EOF'
import math, random, sys
J, Kb = 1.12687602e-5, 1 / 123.569311
def run(path, cv, cc, e0, seed):
    rnd = random.Random(seed)
    w0 = e0 / Kb
    t_stop = J / cv * math.log(1 + cv * w0 / cc)
    lines, t = [], 5234.0
    for k in range(150):                       # 3 s at rest before the cut (pin reads 0)
        lines.append((t, 0.0)); t += 20
    t_cut = t - 10
    while t - t_cut < (t_stop + 3) * 1000:     # coast, then 3 s at rest
        tau = (t - t_cut) / 1000
        w = max(-cc / cv + (w0 + cc / cv) * math.exp(-cv * tau / J), 0.0)
        v = max(Kb * w + rnd.gauss(0, 0.004), 0.0)
        lines.append((t, v)); t += 20 + rnd.choice((-1, 0, 0, 1))
    with open(path, "w") as f:
        for t, v in lines: f.write("%d\t%.2f\r\n" % (t, v))
cv, cc = 1.822e-7, 1.1389e-4
run(sys.argv[1] + "/good1.tsv", cv, cc, 2.8, 1)
run(sys.argv[1] + "/good2.tsv", cv, cc, 3.2, 2)
run(sys.argv[1] + "/good3.tsv", cv, cc, 2.6, 3)
run(sys.argv[1] + "/good4.tsv", cv, cc, 3.0, 4)
run(sys.argv[1] + "/worn.tsv", cv, 2.5 * cc, 3.0, 5)
EOF

cat >"$T/b1.toml" <<'EOF'
# bench b1, by the window
bench_id = "b1"   # the one with the blue flywheel

[serial]
device = "/dev/ttyACM0"

[baseline]
# an old baseline, to be replaced
c_viscous_n_m_s = 1e-7
c_coulomb_n_m = 1e-4

# thresholds agreed with the lab
[health]
service_ratio = 2.2
EOF

# ---- 1. spindown baseline --update: in place, comments and other keys kept ---------------------------
"$B/spindown" baseline "$T/good1.tsv" "$T/good2.tsv" "$T/good3.tsv" --bench b1 --update "$T/b1.toml" \
  --date 2024-09-14 >"$T/baseline.out" 2>"$T/baseline.err" || fail "spindown baseline --update"
grep -q "baseline of bench b1 from 3 of 3 runs" "$T/baseline.out" || fail "baseline summary"
grep -q "updated in place" "$T/baseline.out" || fail "not updated in place"
for kept in "# bench b1, by the window" "# the one with the blue flywheel" 'device = "/dev/ttyACM0"' \
  "# thresholds agreed with the lab" "service_ratio = 2.2" "runs = 3" 'date = "2024-09-14"'; do
  grep -qF "$kept" "$T/b1.toml" || { cat "$T/b1.toml"; fail "b1.toml lost or lacks: $kept"; }
done
if grep -q "an old baseline" "$T/b1.toml"; then fail "old [baseline] still there"; fi
python3 - "$T/b1.toml" <<'EOF' || fail "baseline values"
import sys, tomllib
b = tomllib.load(open(sys.argv[1], "rb"))["baseline"]
assert abs(b["c_coulomb_n_m"] / 1.1389e-4 - 1) < 0.05, b
assert abs(b["c_viscous_n_m_s"] / 1.822e-7 - 1) < 0.3, b
assert 0 < b["c_coulomb_stderr"] < 0.05 * b["c_coulomb_n_m"], b
print("baseline: c_c = %.4g ± %.2g N*m from %d runs" % (b["c_coulomb_n_m"], b["c_coulomb_stderr"], b["runs"]))
EOF

# -o: a new file; refused when it exists (exit 2).
"$B/spindown" baseline "$T/good1.tsv" --bench b1 -o "$T/new.toml" --date 2024-09-14 >"$T/new.out" 2>&1 \
  || fail "baseline -o"
grep -q '^bench_id = "b1"' "$T/new.toml" && grep -q '^\[baseline\]' "$T/new.toml" || fail "new bench file"
set +e
"$B/spindown" baseline "$T/good1.tsv" --bench b1 -o "$T/new.toml" >"$T/exists.out" 2>&1; rc=$?
set -e
[ "$rc" = 2 ] && grep -q "file exists" "$T/exists.out" || fail "-o over an existing file: rc $rc"

# ---- 2. spindown fit --bench-config: service for the worn motor, ok for a good run -------------------
"$B/spindown" fit "$T/worn.tsv" --bench-config "$T/b1.toml" >"$T/worn.out" 2>"$T/worn.err" || fail "fit worn"
grep -q "health: SERVICE — dry friction 2\.[0-9]× the baseline" "$T/worn.out" || fail "worn run is not 'service'"
"$B/spindown" fit "$T/good4.tsv" --bench-config "$T/b1.toml" >"$T/good.out" 2>"$T/good.err" || fail "fit good"
grep -q "health: OK — friction as expected" "$T/good.out" || fail "good run is not 'ok'"
"$B/spindown" fit "$T/worn.tsv" "$T/good4.tsv" --bench-config "$T/b1.toml" --json >"$T/fit.json" 2>"$T/fit.err" \
  || fail "fit --json"
python3 - "$T/fit.json" <<'EOF' || fail "health in JSON"
import json, sys
files = json.load(open(sys.argv[1]))["files"]
worn, good = (f["runs"][0]["health"] for f in files)
assert worn["level"] == "service" and worn["has_reference"], worn
dry = [f for f in worn["findings"] if f["what"] == "dry friction"][0]
assert 2.2 < dry["ratio"] < 2.8 and dry["ratio_stderr"] > 0 and dry["unit"] == "N*m", dry
assert good["level"] == "ok", good
print("fit --json: worn %s (dry friction %.2f ± %.2f× baseline), good %s"
      % (worn["level"], dry["ratio"], dry["ratio_stderr"], good["level"]))
EOF
# Without a bench file: no verdict (nothing invented), and no "health" in the JSON.
"$B/spindown" fit "$T/worn.tsv" --json >"$T/plain.json" 2>/dev/null || fail "fit without bench file"
python3 -c 'import json,sys; r=json.load(open(sys.argv[1]))["files"][0]["runs"][0]; assert "health" not in r' \
  "$T/plain.json" || fail "health without a bench file"
# A bench file without datasheet or baseline: nothing is judged, and the verdict never says OK.
printf 'bench_id = "b2"\n' >"$T/b2.toml"
"$B/spindown" fit "$T/worn.tsv" --bench-config "$T/b2.toml" >"$T/noref.out" 2>&1 || fail "fit with empty bench file"
grep -q "health: NOT JUDGED — not judged: the bench file has no \[motor\] datasheet" "$T/noref.out" ||
  fail "no-reference verdict"
! grep -q "health: OK" "$T/noref.out" || fail "a run judged against nothing is called OK"
# A bad bench file: exit 2, the message names the file and the key.
printf '[motor]\nno_load_current_a = "45 mA"\n' >"$T/bad.toml"
set +e
"$B/spindown" fit "$T/worn.tsv" --bench-config "$T/bad.toml" >"$T/bad.out" 2>&1; rc=$?
set -e
[ "$rc" = 2 ] && grep -q "bad.toml: key 'motor.no_load_current_a': is not a number" "$T/bad.out" \
  || fail "bad bench file: rc $rc"

# ---- 3. spindown-fitter --bench-config DIR publishes the verdict in FIT ------------------------------
# spindown-run-publisher's bench000 has c_v = 0.80·1.822e-7, c_c = 0.95·1.1389e-4 and bench001
# c_v = 0.85·1.822e-7, c_c = 1.1389e-4: bench000's baseline is its own friction (ok), bench001's
# is a third of its Coulomb friction (service).
mkdir -p "$T/benches"
cat >"$T/benches/bench000.toml" <<'EOF'
[baseline]
c_viscous_n_m_s = 1.4576e-7
c_viscous_stderr = 3e-9
c_coulomb_n_m = 1.081955e-4
c_coulomb_stderr = 5e-7
runs = 3
EOF
cat >"$T/benches/bench001.toml" <<'EOF'
[baseline]
c_viscous_n_m_s = 1.54870e-7
c_viscous_stderr = 3e-9
c_coulomb_n_m = 3.79633e-5
c_coulomb_stderr = 5e-7
runs = 3
EOF
mkdir -p "$T/log"
"$B/spindown-logger" --lcm-url "$URL" --dir "$T/log" --prefix health --flush-interval 0.2 >"$T/logger.out" \
  2>"$T/logger.err" &
LOGGER=$!; PIDS+=($LOGGER)
"$B/spindown-fitter" --lcm-url "$URL" --bench-config "$T/benches" --no-explain -v 2>"$T/fitter.err" &
FITTER=$!; PIDS+=($FITTER)
sleep 0.5
"$B/spindown-run-publisher" --lcm-url "$URL" --benches 2 --runs 1 --speed 20 --batch 4 --wait-fits 20 \
  --report "$T/report.json" >"$T/publisher.out" 2>"$T/publisher.err" || fail "run publisher"
sleep 1
stop "$FITTER"; stop "$LOGGER"
grep -q "motor health verdicts for bench000, bench001" "$T/fitter.err" || fail "fitter did not load the bench files"
LOG=$(ls "$T"/log/*.lcm | head -1)
"$B/spindown" refit "$LOG" --live --json >"$T/live.json" 2>"$T/live.err" || fail "refit --live"
python3 - "$T/live.json" <<'EOF' || fail "verdicts in FIT messages"
import json, sys
runs = {r["bench"]["id"]: r for r in json.load(open(sys.argv[1]))["files"][0]["runs"]}
assert set(runs) == {"bench000", "bench001"}, list(runs)
ok, worn = runs["bench000"]["health"], runs["bench001"]["health"]
assert ok["level"] == "ok", ok
assert worn["level"] == "service" and "dry friction" in worn["reason"], worn
print("fitter FIT: bench000 %s; bench001 %s: %s" % (ok["level"], worn["level"], worn["reason"]))
EOF

# A worn run among good ones is set aside, named, and left out of the mean; two runs that
# disagree are refused rather than averaged.
"$B/spindown" baseline --bench b3 -o "$T/b3.toml" "$T/good1.tsv" "$T/good2.tsv" "$T/good3.tsv" "$T/worn.tsv" \
  >"$T/b3.out" 2>&1 || fail "baseline with a worn run among the good ones"
grep -q "set aside $T/worn.tsv run 1: dry friction 2.5× the others' median" "$T/b3.out" || fail "worn run not set aside"
grep -q "baseline of bench b3 from 3 of 4 runs" "$T/b3.out" || fail "the worn run is in the mean"
# Listed once, as set aside: never "used" (issue 30), and in fit's names.
if grep "worn.tsv" "$T/b3.out" | grep -vq "set aside"; then fail "the worn run is listed otherwise than set aside: $(grep worn.tsv "$T/b3.out")"; fi
[ "$(grep -c "^  used     $T/good[123].tsv run 1: c3 = .* N·m·s/rad, c4 = .* N·m$" "$T/b3.out")" -eq 3 ] || fail "the good runs not listed as used in c3/c4"
if grep -q "c_v\|c_c" "$T/b3.out"; then fail "baseline speaks of c_v/c_c, not fit's c3/c4"; fi
# Dated by the recordings, not by today: PuTTY logs of 2023.09.14 give that date; text files that
# tell no date are dated today, said on stderr.
for i in 1 2 3; do
  "$B/spindown" simulate --runs 1 --seed $((40 + i)) --putty-header -o "$T/putty$i.txt" >/dev/null 2>&1 || fail "simulate a PuTTY log"
done
head -1 "$T/putty1.txt" | grep -q "PuTTY log 2023.09.14" || fail "simulate's PuTTY header changed: $(head -1 "$T/putty1.txt")"
"$B/spindown" baseline --bench b5 -o "$T/b5.toml" "$T"/putty[123].txt >"$T/b5.out" 2>"$T/b5.err" || fail "baseline of PuTTY logs"
grep -q '^date = "2023-09-14"$' "$T/b5.toml" || fail "the baseline is not dated by the PuTTY logs: $(grep date "$T/b5.toml")"
grep -q "(recorded 2023-09-14)" "$T/b5.out" || fail "the date is not said"
"$B/spindown" baseline --bench b6 -o "$T/b6.toml" "$T/good1.tsv" "$T/good2.tsv" "$T/good3.tsv" >"$T/b6.out" 2>"$T/b6.err" || fail "baseline of undated files"
grep -q "no recording date in these files .* dated today, $(date -u +%Y-%m-%d); give the recordings' date with --date" "$T/b6.err" ||
  fail "an undated baseline is not said: $(cat "$T/b6.err")"
if "$B/spindown" baseline --bench b4 -o "$T/b4.toml" "$T/good1.tsv" "$T/worn.tsv" >"$T/b4.out" 2>&1; then
  fail "two runs that disagree made a baseline"
fi
grep -q "which one is the motor's normal cannot be told" "$T/b4.out" || fail "two disagreeing runs: no reason given"
echo "PASS cli_baseline"
