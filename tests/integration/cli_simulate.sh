#!/usr/bin/env bash
# `spindown simulate`: a known-answer recording. fit finds the friction it was made with (within
# its standard errors), explain names an effect it was given, the truth file says what was
# simulated, the same seed gives the same bytes on stdout and in a file, faults show up as
# fit's warnings, other rigs' recordings are found right, and an existing file is never
# overwritten.
set -euo pipefail
bin="${SPINDOWN_BIN_DIR:?}/spindown"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

timeout 60 "$bin" simulate -o "$work/run.tsv" --truth "$work/run.json" --putty-header \
  --viscous 2.5e-7 --coulomb 9e-5 --seed 4
head -1 "$work/run.tsv" | grep -q "PuTTY log" || fail "no PuTTY header"
timeout 60 "$bin" fit --json "$work/run.tsv" > "$work/fit.json"
python3 - "$work/fit.json" "$work/run.json" <<'PY' || fail "fit does not find the simulated friction"
import json, sys
fit, truth = (json.load(open(p)) for p in sys.argv[1:3])
assert truth["c_v"] == 2.5e-7 and truth["c_c"] == 9e-5, truth
runs = fit["files"][0]["runs"]
assert len(runs) == 1 and runs[0]["best"] == "combined", runs
p = {m["name"]: m for m in runs[0]["models"]}["combined"]["params"]
for name, true in (("c3", 2.5e-7), ("c4", 9e-5)):
    z = (p[name]["value"] - true) / p[name]["stderr"]
    assert abs(z) < 4, (name, p[name], true, z)
    print(f"{name} = {p[name]['value']:.5g} ± {p[name]['stderr']:.2g} (truth {true:g}, {z:+.1f} se)")
PY

# An effect given to the simulator is the effect explain names.
timeout 60 "$bin" simulate -o "$work/offset.tsv" --offset 0.06 --seed 5
timeout 120 "$bin" explain "$work/offset.tsv" --base viscous,coulomb > "$work/offset.txt"
grep -q "missing effect: sensor_offset" "$work/offset.txt" || fail "explain did not name the simulated offset"

# Same seed, same bytes, to stdout or a file.
timeout 60 "$bin" simulate --seed 4 --viscous 2.5e-7 --coulomb 9e-5 --putty-header > "$work/stdout.tsv"
cmp -s "$work/stdout.tsv" "$work/run.tsv" || fail "stdout and -o differ for the same seed"

# Faults the lab meets come out as fit's warnings, the rest still fitted.
timeout 60 "$bin" simulate -o "$work/garbage.tsv" --garbage-every 100 --seed 6
timeout 60 "$bin" fit "$work/garbage.tsv" > "$work/garbage.out" 2> "$work/garbage.err"
grep -q "warning" "$work/garbage.err" || fail "garbage lines gave no warning"
grep -q "best: combined" "$work/garbage.out" || fail "the run with garbage lines was not fitted"

# Other rigs' recordings, as a user meets them: a hand spin's cut is the peak, a recording that
# starts mid-coast is partial and said so, dropouts are left out with a warning, a sensor that
# gives up is "signal lost", and every run says where its window ends and why (text and JSON).
timeout 60 "$bin" simulate -o "$work/hand.tsv" --truth "$work/hand.json" --lead-in spin-up --spin-up-s 0.3 \
  --glitches 4 --seed 7
timeout 60 "$bin" fit --json "$work/hand.tsv" > "$work/hand.fit.json" 2> "$work/hand.err"
grep -q "4 single-sample outlier" "$work/hand.err" || fail "dropouts not said: $(cat "$work/hand.err")"
python3 - "$work/hand.fit.json" "$work/hand.json" <<'PY' || fail "hand spin: cut not at the peak"
import json, sys
fit, truth = (json.load(open(p)) for p in sys.argv[1:3])
run = fit["files"][0]["runs"][0]
cut = truth["runs"][0]["cut_device_us"] / 1e6  # the cut on the device's clock, as the file has it
assert run["lead_in"] == "spin-up" and abs(run["t_cut_s"] - cut) < 0.05, (run["lead_in"], run["t_cut_s"], cut)
assert run["end"] == "stopped" and run["t_end_s"] > run["t_stop_s"], (run["end"], run["t_end_s"])
PY
timeout 60 "$bin" simulate -o "$work/mid.tsv" --start-s 4 --seed 8
timeout 60 "$bin" fit "$work/mid.tsv" > "$work/mid.out" 2> "$work/mid.err"
grep -q "coast from t = .* (its cut was not recorded).*lead-in: none" "$work/mid.out" || fail "a recording that starts mid-coast: $(head -3 "$work/mid.out")"
grep -q "starts mid-coast" "$work/mid.err" || fail "a partial coast without a warning"
timeout 60 "$bin" simulate -o "$work/lost.tsv" --pulses-per-rev 1 --pulse-timeout-s 0.5 --seed 3
timeout 60 "$bin" fit "$work/lost.tsv" > "$work/lost.out" 2> "$work/lost.err"
grep -q "(signal lost)" "$work/lost.out" || fail "a sensor that gave up: $(head -3 "$work/lost.out")"
grep -q "signal lost below" "$work/lost.err" || fail "signal lost without a warning"

# An existing file is refused (exit 2), and left as it was; bad physics is bad usage.
code=0
timeout 60 "$bin" simulate -o "$work/run.tsv" --seed 9 2> "$work/exists.err" || code=$?
[ $code -eq 2 ] || fail "existing -o gave exit $code"
grep -q "the file exists" "$work/exists.err" || fail "existing -o not explained"
cmp -s "$work/stdout.tsv" "$work/run.tsv" || fail "an existing file was changed"
code=0
timeout 60 "$bin" simulate --inertia -1 > /dev/null 2> "$work/bad.err" || code=$?
[ $code -eq 2 ] || fail "negative J gave exit $code: $(cat "$work/bad.err")"
# Impossible physics is bad usage, said at once: a NaN used to make the simulator run forever.
for bad in "--viscous nan" "--coulomb inf" "--coulomb -1e-4" "--noise -1" "--lead-in-s -1" "--reset-at -3" \
           "--stribeck-static 2e-4"; do
  code=0
  # shellcheck disable=SC2086  # the option and its value are two words
  timeout 20 "$bin" simulate $bad > /dev/null 2> "$work/bad.err" || code=$?
  [ $code -eq 2 ] || fail "simulate $bad gave exit $code: $(head -c 200 "$work/bad.err")"
  grep -qF -- "${bad%% *}" "$work/bad.err" || fail "simulate $bad: $(cat "$work/bad.err")"
done
# The recording and its truth, both or neither: a truth that cannot be written leaves no
# recording behind (which -o would then refuse to overwrite).
code=0
timeout 60 "$bin" simulate -o "$work/alone.tsv" --truth "$work/no/such/dir/t.json" 2> "$work/truth.err" || code=$?
[ $code -eq 1 ] || fail "unwritable --truth gave exit $code"
[ ! -e "$work/alone.tsv" ] || fail "the recording was written without its truth"
ls "$work" | grep -q '\.part$' && fail "a .part file was left behind"
echo "cli_simulate: ok"
