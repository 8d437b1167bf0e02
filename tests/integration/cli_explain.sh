#!/usr/bin/env bash
# spindown explain end to end: the lab's story on the sample data (text, §5 JSON, SVG), a hidden
# windage effect named from the lab's belief, fit's vocabulary (the base model is fit's model of the
# same name: c1, ω0, the reading noise σ, --lab-units), Coulomb friction not mistaken for a sensor
# offset below zero on a recording cut off before its stop (rpm), bad usage (exit 2), an unusable
# file (exit 1, the other files still explained); --bench-config as fit takes it (explain, export),
# a bench file whose K_b and datasheet disagree named; the viscous term of a Coulomb-only motor said
# to be unneeded.
set -euo pipefail
bin="${SPINDOWN_BIN_DIR:?}/spindown"
data="${SPINDOWN_SAMPLE_DATA:?}"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

# Text: the story names the missing effect, the disagreement and the gap.
timeout 60 "$bin" explain "$data/seed-3v-run1.tsv" > "$work/story.txt"
grep -q "base model: viscous" "$work/story.txt" || fail "no base model in the story"
grep -q "missing effect: coulomb" "$work/story.txt" || fail "coulomb not named"
grep -q "after the cut (speed" "$work/story.txt" || fail "no time/speed ranges"
grep -q "gap: RMSE" "$work/story.txt" || fail "no gap before/after"

# JSON per design §5, and the SVG figure.
timeout 60 "$bin" explain "$data/windage-example.tsv" "$data/viscous-only.tsv" --json --svg "$work/fig.svg" > "$work/out.json"
python3 - "$work/out.json" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
files = d["files"]
assert len(files) == 2, files
w = files[0]["runs"][0]
for key in ("run", "base", "steps", "final", "rmse_base", "rmse_final"):
    assert key in w, key
assert w["base"] == ["viscous"], w["base"]
assert "windage" in w["final"] and "coulomb" in w["final"], w["final"]
for s in w["steps"]:
    for key in ("added", "rmse_before", "rmse_after", "where", "why"):
        assert key in s, key
    for where in s["where"]:
        assert set(("t_from_s", "t_to_s", "mean_residual")) <= set(where), where
assert w["rmse_final"] < w["rmse_base"] / 10, (w["rmse_base"], w["rmse_final"])
v = files[1]["runs"][0]
assert v["steps"] == [] and v["final"] == ["viscous"], (v["steps"], v["final"])
PY
grep -q "<svg" "$work/fig.svg" && grep -q "</svg>" "$work/fig.svg" || fail "no SVG written"
grep -q "time after the cut (s)" "$work/fig.svg" || fail "SVG without axis labels"

# An LCM log of two benches: every run names its bench in the text, the JSON and the figure's titles,
# and each figure draws the base and every step with its RMSE.
if [ -x "${SPINDOWN_BIN_DIR}/make_lcm_log" ]; then
  "${SPINDOWN_BIN_DIR}/make_lcm_log" "$work/two.lcm" 6000 2 > /dev/null
  timeout 60 "$bin" explain "$work/two.lcm" --svg "$work/two.svg" > "$work/two.txt" 2> /dev/null
  grep -q "^run 1 of bench bench000: " "$work/two.txt" && grep -q "^run 1 of bench bench001: " "$work/two.txt" ||
    fail "the log's runs do not name their bench: $(grep '^run' "$work/two.txt")"
  timeout 60 "$bin" explain "$work/two.lcm" --json 2> /dev/null | python3 -c '
import json, sys
runs = json.load(sys.stdin)["files"][0]["runs"]
assert {r["bench"] for r in runs} == {"bench000", "bench001"}, [r.get("bench") for r in runs]' || fail "JSON without the bench"
  grep -q "two.lcm bench bench001 - run 1: base viscous" "$work/two.svg" || fail "SVG titles without the bench"
  [ "$(grep -c 'class="model" data-step="1"' "$work/two.svg")" -ge 4 ] || fail "SVG without each run's step curve"
else
  echo "cli_explain: make_lcm_log not built, the LCM-log part skipped"
fi

# Base given as a list; bad usage exits 2; a missing file exits 1 but the good one is explained.
timeout 60 "$bin" explain "$data/offset-example.tsv" --base viscous,coulomb > "$work/offset.txt"
grep -q "missing effect: sensor_offset" "$work/offset.txt" || fail "offset not named"
grep -q "zero level 0.06 V at standstill: spindown fit subtracts it" "$work/offset.txt" || fail "fit's zero level not said"

# One vocabulary (issue 22): on one run, explain's base model is fit's viscous model (same c1, ω0,
# RMSE, units), the noise is the reading noise σ in both, and --lab-units gives fit's conversion.
timeout 60 "$bin" fit "$data/stribeck-example.tsv" --lab-units > "$work/fit.txt"
timeout 60 "$bin" explain "$data/stribeck-example.tsv" --lab-units > "$work/vocab.txt"
c1=$(grep -o 'c1 = ([0-9.]* ± [0-9.]*)e-07 N·m·s/rad' "$work/fit.txt" | head -1)
[ -n "$c1" ] || fail "no c1 in fit's output"
grep -qF "$c1" "$work/vocab.txt" || fail "explain's base is not fit's viscous ($c1): $(grep -A2 'base model' "$work/vocab.txt")"
w0=$(grep -o 'ω0 = [0-9.]* ± [0-9.]* rad/s' "$work/fit.txt" | head -1)
grep -qF "$w0" "$work/vocab.txt" || fail "explain's ω0 is not fit's ($w0)"
rmse=$(awk '$1 == "viscous" { for (i = 1; i <= NF; ++i) if ($i == "V" && $(i-1) ~ /^0\./) { print $(i-1); exit } }' "$work/fit.txt")
grep -q "base model: viscous - spindown fit's viscous model   RMSE $rmse V" "$work/vocab.txt" || fail "base RMSE is not fit's $rmse"
sigma=$(grep -o 'reading noise σ [0-9.]* V' "$work/fit.txt" | head -1)
[ -n "$sigma" ] && grep -qF "$sigma" "$work/vocab.txt" || fail "the reading noise σ differs: '$sigma'"
grep -q 'c_v\|c_c\|omega0\|N\*m' "$work/vocab.txt" && fail "a second vocabulary in explain's text"
# Coulomb added to the viscous base is fit's combined model: its c3, in SI and in the lab's units.
lab=$(grep -o 'c3 = ([0-9.]* ± [0-9.]*)e-0[0-9] N·m·s/rad = [0-9.]* ± [0-9.]* g·cm²·s⁻¹' "$work/fit.txt" | head -1)
[ -n "$lab" ] || fail "no c3 in lab units in fit's output"
grep -qF "$lab" "$work/vocab.txt" || fail "explain --lab-units does not give fit's combined c3 ($lab)"
timeout 60 "$bin" explain "$data/seed-3v-run1.tsv" --json --lab-units > "$work/lab.json"
python3 - "$work/lab.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))["files"][0]["runs"][0]
p = r["final_params"]
assert set(p) == {"c3", "c4", "omega0"}, p
assert p["c3"]["unit"] == "N*m*s/rad" and p["c4"]["unit"] == "N*m", p
assert abs(p["c4"]["lab"]["value"] - 1e7 * p["c4"]["value"]) < 1e-9 * p["c4"]["lab"]["value"], p["c4"]
assert p["c4"]["lab"]["unit"] == "g*cm^2*rad/s^2", p["c4"]
assert "noise_level" not in r and r["reading_noise"] > 0 and r["bin_samples"] > 0, r
assert r["base_params"].keys() == {"c1", "omega0"}, r["base_params"]
PY

# Coulomb friction, not a sensor offset of minus hundreds of rpm: a viscous coast with a little
# Coulomb friction in rpm, the recording cut off before the stop (the two fit it identically).
timeout 60 "$bin" simulate --viscous 1.2e-6 --coulomb 3e-5 --seed 7 -o "$work/tie.tsv" --truth "$work/tie.json"
python3 - "$work/tie.tsv" "$work/tie.json" "$work/tie.csv" <<'PY'
import json, math, sys
truth = json.load(open(sys.argv[2]))
kb, run = truth["kb_v_s_per_rad"], truth["runs"][0]
cut = run["cut_device_us"] / 1e3
end = cut + 0.6 * 1e3 * run["t_stop_s"]
with open(sys.argv[3], "w") as out:
    out.write("time_ms,speed_rpm\n")
    for line in open(sys.argv[1]):
        f = line.split()
        if len(f) == 2 and float(f[0]) <= end:
            out.write(f"{f[0]},{float(f[1]) / kb * 60 / (2 * math.pi):.1f}\n")
PY
timeout 60 "$bin" explain "$work/tie.csv" --value-unit rpm > "$work/tie.txt" 2>/dev/null
grep -q "missing effect: coulomb" "$work/tie.txt" || fail "coulomb not named on the cut-off rpm run: $(grep 'missing effect' "$work/tie.txt")"
grep -q "rejected sensor_offset: not physical here: a sensor offset of -" "$work/tie.txt" || fail "the offset below zero not rejected with its reason"
set +e
"$bin" explain "$data/seed-3v-run1.tsv" --base friction > /dev/null 2> "$work/usage.err"; code=$?
[ $code -eq 2 ] || fail "bad --base gave exit $code"
grep -q "unknown effect 'friction'" "$work/usage.err" || fail "bad --base not explained"
timeout 60 "$bin" explain "$work/missing.tsv" "$data/seed-3v-run1.tsv" > "$work/mixed.txt" 2> "$work/mixed.err"; code=$?
set -e
[ $code -eq 1 ] || fail "missing file gave exit $code"
grep -q "missing.tsv" "$work/mixed.err" || fail "missing file not named"
grep -q "missing effect: coulomb" "$work/mixed.txt" || fail "the good file was not explained"
# An empty file's error is said once (by its "not used" line), as spindown fit says it.
: > "$work/empty.tsv"
code=0
timeout 60 "$bin" explain "$work/empty.tsv" > /dev/null 2> "$work/empty.err" || code=$?
[ $code -eq 1 ] || fail "empty file gave exit $code"
[ "$(grep -c "the file is empty" "$work/empty.err")" -eq 1 ] || fail "empty file's error said $(grep -c "the file is empty" "$work/empty.err") times"
# A figure that cannot be written says why.
code=0
timeout 60 "$bin" explain "$data/seed-3v-run1.tsv" --svg "$work/no/such/dir/fig.svg" > /dev/null 2> "$work/svg.err" || code=$?
[ $code -eq 1 ] || fail "unwritable --svg gave exit $code"
grep -q "cannot write the figure: No such file or directory" "$work/svg.err" || fail "unwritable --svg: $(cat "$work/svg.err")"
# A bench with its own flywheel (J twice the lab's, by geometry in its bench file): explain and export
# take --bench-config as fit does, so all three give the truth's c3 (the default J would halve it).
cat > "$work/bench5.toml" <<'TOML'
bench_id = "bench5"
[bench]
flywheel_radius_m = 0.02
flywheel_height_m = 0.03
flywheel_density_kg_m3 = 2700
rotor_inertia_kg_m2 = 1.09e-6
speed_constant_rpm_per_v = 1180
[motor]
speed_constant_rpm_per_v = 1416
TOML
J5=$(python3 -c 'import math; print(2700*math.pi*0.02**2*0.03*0.02**2/2 + 1.09e-6)')
timeout 60 "$bin" simulate --runs 1 --seed 5 --inertia "$J5" --viscous 2.6e-7 --coulomb 1.25e-4 \
  -o "$work/bench5_ida.txt" > /dev/null 2>&1 || fail "simulate the flywheel bench"
bench_opts=(--bench-config "$work/bench5.toml" --bench-pattern '(bench[0-9]+)_([a-z]+)')
timeout 60 "$bin" fit --json "${bench_opts[@]}" "$work/bench5_ida.txt" > "$work/b5fit.json" 2> "$work/b5fit.err" || fail "fit --bench-config"
timeout 60 "$bin" explain --json --base combined "${bench_opts[@]}" "$work/bench5_ida.txt" > "$work/b5explain.json" 2> "$work/b5explain.err" ||
  fail "explain --bench-config: $(cat "$work/b5explain.err")"
timeout 60 "$bin" export "$work/bench5_ida.txt" -o "$work/b5.csv" "${bench_opts[@]}" 2> "$work/b5export.err" ||
  fail "export --bench-config: $(cat "$work/b5export.err")"
python3 - "$work" "$J5" <<'PY'
import csv, json, sys
work, J = sys.argv[1], float(sys.argv[2])
fit = json.load(open(work + "/b5fit.json"))["files"][0]["runs"][0]
fit_c3 = next(m for m in fit["models"] if m["name"] == "combined")["params"]["c3"]["value"]
ex = json.load(open(work + "/b5explain.json"))["files"][0]["runs"][0]
ex_c3 = ex["base_params"]["c3"]["value"]
rows = [r for r in csv.DictReader(open(work + "/b5.fits.csv")) if r["model"] == "combined"]
exp_c3 = float(rows[0]["c3"])
assert abs(fit["bench"]["J"] / J - 1) < 1e-9 and abs(ex["inertia_kg_m2"] / J - 1) < 1e-9, (fit["bench"], ex["inertia_kg_m2"])
assert abs(float(rows[0]["J_kg_m2"]) / J - 1) < 1e-9, rows[0]["J_kg_m2"]
for name, c3 in (("fit", fit_c3), ("explain", ex_c3), ("export", exp_c3)):
    assert abs(c3 / 2.6e-7 - 1) < 0.05, (name, c3)
assert abs(ex_c3 / fit_c3 - 1) < 1e-3 and abs(exp_c3 / fit_c3 - 1) < 1e-6, (fit_c3, ex_c3, exp_c3)
print("bench file honoured: c3 fit %.4g, explain %.4g, export %.4g (truth 2.6e-07, J %.4g)" % (fit_c3, ex_c3, exp_c3, J))
PY
# The file's [bench] K_b (1180 rpm/V) and [motor] speed constant (1416 rpm/V) disagree: every
# command that reads it says so, and which one it uses.
for f in b5fit b5explain b5export; do
  grep -q "bench5.toml: warning: \[bench\] speed_constant_rpm_per_v = 1180 rpm/V .* and \[motor\] speed_constant_rpm_per_v = 1416 rpm/V .* disagree by 20 %.*the fits use \[bench\]'s K_b" "$work/$f.err" ||
    fail "$f: no warning naming the K_b disagreement: $(cat "$work/$f.err")"
done

# A motor with Coulomb friction alone: explain says the viscous term is not needed, from the lab's
# belief (viscous) and from fit's combined model.
timeout 60 "$bin" simulate --runs 1 --seed 9 --viscous 0 --coulomb 1.2e-4 -o "$work/coulomb.txt" > /dev/null 2>&1
timeout 60 "$bin" explain "$work/coulomb.txt" > "$work/coulomb.out" 2>&1 || fail "explain a Coulomb-only motor"
grep -q "removed viscous: not needed once coulomb is in" "$work/coulomb.out" || fail "viscous not said to be unneeded: $(cat "$work/coulomb.out")"
grep -q "final model: coulomb" "$work/coulomb.out" || fail "Coulomb-only motor's final model"
timeout 60 "$bin" explain --base combined "$work/coulomb.txt" > "$work/coulomb2.out" 2>&1 || fail "explain --base combined"
grep -q "step 1: viscous not needed" "$work/coulomb2.out" || fail "from combined, viscous not said to be unneeded: $(cat "$work/coulomb2.out")"
echo "cli_explain: ok"
