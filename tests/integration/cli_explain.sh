#!/usr/bin/env bash
# spindown explain end to end: the lab's story on the sample data (text, §5 JSON, SVG), a hidden
# windage effect named from the lab's belief, bad usage (exit 2), an unusable file (exit 1, the
# other files still explained).
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

# Base given as a list; bad usage exits 2; a missing file exits 1 but the good one is explained.
timeout 60 "$bin" explain "$data/offset-example.tsv" --base viscous,coulomb > "$work/offset.txt"
grep -q "missing effect: sensor_offset" "$work/offset.txt" || fail "offset not named"
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
echo "cli_explain: ok"
