#!/usr/bin/env bash
# A class's workflow, end to end, as README's instructor section gives it: four benches' reference
# runs -> a baseline per bench; a week's recordings by four students (one on a worn motor: 2.2x the
# Coulomb friction, 1.5x the viscous) named by a roster, then by a file-name pattern; one table row
# per run (CSV and JSON), the worn motor flagged against its own bench's baseline and the others
# not, every coefficient within its errors of the simulator's truth; one report over the four
# benches; export of a text recording; a file the roster does not list said, not dropped; a bad
# roster refused naming its line. No network.
set -euo pipefail
bin="${SPINDOWN_BIN_DIR:?}/spindown"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
cd "$work"
mkdir -p ref week3 benches

# ---- the term's start: reference runs on each bench, a baseline each ------------------------------
for b in 1 2 3 4; do
  "$bin" simulate --runs 3 --seed $((10 + b)) -o ref/bench$b.txt
  "$bin" baseline --bench bench$b -o benches/bench$b.toml ref/bench$b.txt >baseline$b.out
done

# ---- week 3: four students; Carol's bench 3 has a worn motor ---------------------------------------
"$bin" simulate --runs 2 --seed 101 -o week3/alice.txt --truth week3/alice.truth.json
"$bin" simulate --runs 2 --seed 102 -o week3/bob.txt --truth week3/bob.truth.json
"$bin" simulate --runs 2 --seed 103 --coulomb 2.5e-4 --viscous 2.7e-7 -o week3/carol.txt --truth week3/carol.truth.json
"$bin" simulate --runs 2 --seed 104 -o week3/dan.txt --truth week3/dan.truth.json
cat >roster.csv <<'R'
file,bench,student
week3/alice.txt,bench1,Alice
week3/bob.txt,bench2,Bob
week3/carol.txt,bench3,"Carol, C."
week3/dan.txt,bench4,Dan
R

# ---- one row per run, CSV ----------------------------------------------------------------------------
"$bin" fit --roster roster.csv --bench-config benches --table csv -o class.csv week3/*.txt 2>class.err ||
  fail "fit --table csv exited $?: $(cat class.err)"
python3 - class.csv week3 <<'PY' || fail "the class table is wrong"
import csv, json, sys
assert open(sys.argv[1], "rb").read(3) == b"\xef\xbb\xbf", "a CSV file for Excel starts with a byte-order mark"
rows = list(csv.DictReader(open(sys.argv[1], encoding="utf-8-sig")))
assert len(rows) == 8, f"{len(rows)} rows, want 8 (4 files x 2 runs)"
who = {"alice": ("bench1", "Alice"), "bob": ("bench2", "Bob"), "carol": ("bench3", "Carol, C."), "dan": ("bench4", "Dan")}
for r in rows:
    name = r["file"].split("/")[-1].split(".")[0]
    assert (r["bench"], r["student"]) == who[name], (r["file"], r["bench"], r["student"])
    truth = json.load(open(f"{sys.argv[2]}/{name}.truth.json"))
    for col, key in (("c3", "c_v"), ("c4", "c_c")):
        z = (float(r[col]) - truth[key]) / float(r[col + "_total_stderr"])
        assert abs(z) < 4, f"{r['file']} run {r['run']}: {col} = {r[col]} is {z:.1f} errors from the truth {truth[key]}"
    worn = name == "carol"
    assert r["best"] == "combined" and r["trust"] == "ok", (r["file"], r["best"], r["trust"], r["doubts"])
    if worn:
        assert r["health"] in ("check", "service"), f"the worn motor is '{r['health']}': {r['health_reason']}"
        assert "baseline" in r["health_reason"], r["health_reason"]
    else:
        assert r["health"] == "ok", f"{r['file']}: '{r['health']}': {r['health_reason']}"
print("class table: 8 rows, benches and students from the roster, worn motor flagged, c3/c4 within 4 errors of truth")
PY

# ---- the same by a file-name pattern, and as JSON ----------------------------------------------------
mkdir -p named
cp week3/alice.txt named/bench1_alice.txt
cp week3/carol.txt named/bench3_carol.txt
"$bin" fit --bench-pattern '(bench[0-9]+)_([a-z]+)' --bench-config benches --table json named/*.txt >named.json ||
  fail "fit --table json exited $?"
python3 - named.json <<'PY' || fail "the JSON table is wrong"
import json, sys
rows = json.load(open(sys.argv[1]))
assert [(r["bench"], r["student"]) for r in rows] == [("bench1", "alice")] * 2 + [("bench3", "carol")] * 2, rows
assert [r["health"] for r in rows][2:] != ["ok", "ok"], "the worn motor passed"
assert rows[0]["t_stop_s"] is not None and isinstance(rows[0]["c4"], float)
PY

# ---- a file the roster does not list: said, still fitted under its own name ---------------------------
cp week3/dan.txt week3/eve.txt
"$bin" fit --roster roster.csv --table csv week3/eve.txt >eve.csv 2>eve.err || fail "fit on an unlisted file exited $?"
grep -q "week3/eve.txt: warning: bench: not in the roster roster.csv" eve.err || fail "no warning for an unlisted file: $(cat eve.err)"
[ "$(tail -n +2 eve.csv | cut -d, -f2 | sort -u)" = "eve" ] || fail "an unlisted file is not under its own name: $(cat eve.csv)"

# ---- a bad roster: refused, naming the line ----------------------------------------------------------
printf 'file,bench\nweek3/alice.txt,bench 1\n' >bad.csv
set +e
"$bin" fit --roster bad.csv week3/alice.txt >/dev/null 2>bad.err
rc=$?
set -e
[ $rc -eq 2 ] || fail "a bad roster gave exit $rc, want 2"
grep -q "bad.csv:2: bench 'bench 1'" bad.err || fail "the bad roster's message does not name its line: $(cat bad.err)"

# ---- one report over the four benches ----------------------------------------------------------------
"$bin" report --roster roster.csv --bench-config benches -o class.html --no-progress week3/alice.txt week3/bob.txt \
  week3/carol.txt week3/dan.txt >report.out 2>report.err || fail "report exited $?: $(cat report.err)"
grep -q "8 runs on 4 benches from 4 files" report.out || fail "report: $(cat report.out)"
python3 - class.html <<'PY' || fail "the report does not show the class"
import re, sys
page = open(sys.argv[1]).read()
summary = page[page.index('id="summary"'):page.index('id="files"')]
badge = {}
for row in re.findall(r"<tr>(.*?)</tr>", summary, re.S):
    m = re.search(r'>(bench[0-9])</a>.*?class="badge [a-z_]+">([A-Z ]+)<', row, re.S)
    if m: badge[m.group(1)] = m.group(2)
assert badge == {"bench1": "OK", "bench2": "OK", "bench3": badge.get("bench3"), "bench4": "OK"}, badge
assert badge["bench3"] in ("CHECK", "SERVICE"), f"bench3 is not flagged: {badge}"
assert "<th>student</th>" in page and "Carol, C." in page, "no student column"
PY

# ---- a student's recording exported for MATLAB/Python -------------------------------------------------
"$bin" export week3/carol.txt --roster roster.csv -o carol.csv 2>export.err || fail "export exited $?: $(cat export.err)"
python3 - carol.csv carol.fits.csv class.csv <<'PY' || fail "the export is wrong"
import csv, sys
samples = list(csv.DictReader(open(sys.argv[1], encoding="utf-8-sig")))
fits = list(csv.DictReader(open(sys.argv[2], encoding="utf-8-sig")))
table = [r for r in csv.DictReader(open(sys.argv[3], encoding="utf-8-sig")) if r["bench"] == "bench3"]
lines = sum(1 for l in open("week3/carol.txt") if l.strip())
assert len(samples) == lines, f"{len(samples)} samples exported from {lines} lines"
assert {s["bench"] for s in samples} == {"bench3"}
best = [f for f in fits if f["best"] == "1"]
assert len(best) == 2 and all(f["model"] == "combined" for f in best), best
for f, t in zip(best, table):
    assert abs(float(f["c4"]) / float(t["c4"]) - 1) < 1e-9, (f["c4"], t["c4"])  # export fits as fit does
PY

# ---- baseline over the class's files: only its own bench's ------------------------------------------
"$bin" baseline --bench bench2 --roster roster.csv week3/*.txt >b2.out 2>b2.err || fail "baseline exited $?: $(cat b2.err)"
grep -q "skipped  week3/alice.txt: bench bench1" b2.out || fail "baseline took another bench's file: $(cat b2.out)"
grep -q "from 2 of 2 runs" b2.out || fail "baseline of bench2: $(cat b2.out)"
echo "PASS: class workflow (roster, pattern, table csv/json, report, export, baseline)"
