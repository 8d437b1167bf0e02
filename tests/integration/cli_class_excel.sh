#!/usr/bin/env bash
# README's class workflow with the files a class on Windows really hands in: the roster as a German
# Excel saves it ("CSV (Trennzeichen-getrennt)": Windows-1252, ';', CR LF, ';;;;' rows for the
# sheet's empty rows), students' recordings saved by Windows tools (Notepad's "Unicode" UTF-16 with
# a byte-order mark, a German Excel's CSV of "Zeit [µs];Spannung [mV]" with decimal commas in
# Windows-1252, a PuTTY log ending in DOS's Ctrl-Z), and an .xlsx handed in by mistake. Checks,
# against the simulator's truth: every file read (the Ctrl-Z without a warning), names right in
# the table (CSV with a byte-order mark that pandas.read_csv reads, --csv-locale de with ';' and
# decimal commas, JSON), the text and the HTML report, the worn motor flagged, c3/c4 within 4 errors
# of the truth, export's CSV (default, and --csv-locale de with its mark) read back by pandas, and
# the .xlsx named as a workbook to save as CSV (UTF-8), not "binary data". No network.
set -euo pipefail
bin="${SPINDOWN_BIN_DIR:?}/spindown"
PY=${SPINDOWN_PYTHON:-/usr/bin/python3}
work=$(mktemp -d)
trap '[ -n "${KEEP:-}" ] || rm -rf "$work"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
"$PY" -c 'import pandas' 2>/dev/null || fail "$PY has no pandas (deploy/setup --tests: python3-pandas)"
cd "$work"
mkdir -p ref week3 benches

# ---- the term's start: a baseline per bench ----------------------------------------------------------
for b in 1 2 3 4; do
  "$bin" simulate --runs 3 --seed $((10 + b)) -o ref/bench$b.txt
  "$bin" baseline --bench bench$b -o benches/bench$b.toml ref/bench$b.txt >/dev/null
done

# ---- week 3: what four students' Windows PCs saved -----------------------------------------------------
"$bin" simulate --runs 2 --seed 101 -o sim-mueller.txt --truth week3/mueller.truth.json --putty-header
"$bin" simulate --runs 2 --seed 102 -o sim-weiss.txt --truth week3/weiss.truth.json
"$bin" simulate --runs 2 --seed 103 --coulomb 2.5e-4 --viscous 2.7e-7 -o sim-schaefer.txt \
  --truth week3/schaefer.truth.json
"$bin" simulate --runs 2 --seed 104 -o sim-dubois.txt --truth week3/dubois.truth.json
"$PY" - <<'PY'
import io, zipfile

def lab_lines(path):
    return [l.rstrip("\r\n") for l in open(path, encoding="ascii") if l.strip()]

# Müller: a PuTTY log (CR LF) that a DOS-era editor closed with Ctrl-Z.
open("week3/mueller.txt", "wb").write(open("sim-mueller.txt", "rb").read().replace(b"\r\n", b"\n").replace(b"\n", b"\r\n") + b"\x1a")
# Weiß: the serial monitor pasted into Notepad and saved as "Unicode": UTF-16 LE, a BOM, CR LF.
text = "\r\n".join(lab_lines("sim-weiss.txt")) + "\r\n"
open("week3/weiss.txt", "wb").write(b"\xff\xfe" + text.encode("utf-16-le"))
# Schäfer: pasted into a German Excel, converted to µs and mV, saved as CSV (Trennzeichen-getrennt):
# Windows-1252, ';', decimal commas, CR LF, the sheet's empty rows as ';'.
rows = ["Zeit [\u00b5s];Spannung [mV]"]
for l in lab_lines("sim-schaefer.txt"):
    ms, v = l.split("\t")
    rows.append("%d;%s" % (int(ms) * 1000, ("%.1f" % (float(v) * 1000)).replace(".", ",")))
rows += [";"] * 4
open("week3/schaefer.csv", "wb").write(("\r\n".join(rows) + "\r\n").encode("cp1252"))
# Dubois: a plain recording.
open("week3/dubois.txt", "wb").write(open("sim-dubois.txt", "rb").read())
# The roster, as a German Excel saves it.
students = [("week3/mueller.txt", "bench1", "M\u00fcller, J\u00fcrgen"), ("week3/weiss.txt", "bench2", "Anna Wei\u00df"),
            ("week3/schaefer.csv", "bench3", "Bj\u00f6rn Sch\u00e4fer"), ("week3/dubois.txt", "bench4", "Ren\u00e9e Dubois")]
lines = ["file;bench;student;;"] + ["%s;%s;%s;;" % s for s in students] + [";;;;"] * 6
open("roster.csv", "wb").write(("\r\n".join(lines) + "\r\n").encode("cp1252"))
# A hand-in saved as an Excel workbook: a real .xlsx (Office Open XML zip).
buf = io.BytesIO()
with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as z:
    z.writestr("[Content_Types].xml", '<?xml version="1.0"?><Types xmlns="http://schemas.openxmlformats.org/package/2006/content-types"/>')
    z.writestr("xl/workbook.xml", '<?xml version="1.0"?><workbook/>')
    z.writestr("xl/worksheets/sheet1.xml", "<worksheet><sheetData>" + "".join(
        '<row r="%d"><c r="A%d"><v>%d</v></c></row>' % (i, i, 20 * i) for i in range(1, 400)) + "</sheetData></worksheet>")
open("week3/weiss_run2.xlsx", "wb").write(buf.getvalue())
PY
files=(week3/mueller.txt week3/weiss.txt week3/schaefer.csv week3/dubois.txt)

# ---- every file read; the Ctrl-Z is no warning -----------------------------------------------------------
"$bin" fit --roster roster.csv --bench-config benches "${files[@]}" >class.txt 2>class.err ||
  fail "fit exited $?: $(cat class.err)"
grep -q "warning" class.err && fail "warnings on the class's files: $(cat class.err)"
for name in "Müller, Jürgen" "Anna Weiß" "Björn Schäfer" "Renée Dubois"; do
  grep -qF "student $name)" class.txt || fail "the text does not name $name: $(grep '^==' class.txt)"
done

# ---- the table for Excel: a byte-order mark, UTF-8 names, pandas reads it ---------------------------
"$bin" fit --roster roster.csv --bench-config benches --table csv -o week3.csv "${files[@]}" 2>table.err ||
  fail "fit --table csv -o exited $?: $(cat table.err)"
"$bin" fit --roster roster.csv --bench-config benches --table csv --csv-locale de -o week3-de.csv "${files[@]}" \
  2>/dev/null || fail "fit --table csv --csv-locale de exited $?"
"$bin" fit --roster roster.csv --bench-config benches --table json "${files[@]}" >week3.json 2>/dev/null ||
  fail "fit --table json exited $?"
"$PY" - <<'PY' || fail "the class table is wrong"
import csv, json
import pandas as pd
raw = open("week3.csv", "rb").read()
assert raw.startswith(b"\xef\xbb\xbf"), "no UTF-8 byte-order mark: Excel would read the names as Windows-1252"
raw.decode("utf-8")
t = pd.read_csv("week3.csv")
assert list(t.columns[:3]) == ["file", "bench", "student"], list(t.columns[:5])
de = pd.read_csv("week3-de.csv", sep=";", decimal=",")
assert open("week3-de.csv", "rb").read(3) == b"\xef\xbb\xbf"
assert list(de.columns) == list(t.columns) and len(de) == len(t) == 8, (len(de), len(t))
for col in ("c3", "c4", "c3_total_stderr", "t_cut_s", "omega0"):
    assert de[col].dtype.kind == "f", f"--csv-locale de: {col} is not read as numbers by pandas (decimal=',')"
    assert (abs(de[col] - t[col]) <= 1e-9 * abs(t[col])).all(), (col, list(de[col]), list(t[col]))
rows = json.load(open("week3.json"))
who = {"mueller": ("bench1", "Müller, Jürgen"), "weiss": ("bench2", "Anna Weiß"),
       "schaefer": ("bench3", "Björn Schäfer"), "dubois": ("bench4", "Renée Dubois")}
for table in (t.to_dict("records"), rows):
    for r in table:
        name = r["file"].split("/")[-1].split(".")[0]
        assert (r["bench"], r["student"]) == who[name], (r["file"], r["bench"], r["student"])
        truth = json.load(open(f"week3/{name}.truth.json"))
        for col, key in (("c3", "c_v"), ("c4", "c_c")):
            z = (float(r[col]) - truth[key]) / float(r[col + "_total_stderr"])
            assert abs(z) < 4, f"{r['file']} run {r['run']}: {col} = {r[col]} is {z:.1f} errors from the truth {truth[key]}"
        assert r["trust"] == "ok", (r["file"], r["doubts"])
        if name == "schaefer":
            assert r["health"] in ("check", "service"), f"the worn motor is '{r['health']}'"
        else:
            assert r["health"] == "ok", (r["file"], r["health"], r["health_reason"])
# Python's csv module reads it with the byte-order mark's encoding.
names = [r["student"] for r in csv.DictReader(open("week3.csv", encoding="utf-8-sig"))]
assert "Björn Schäfer" in names, names
print("class table: names right in CSV (BOM), German CSV, JSON; worn motor flagged; c3/c4 within 4 errors")
PY

# ---- the report shows the names -------------------------------------------------------------------------
"$bin" report --roster roster.csv --bench-config benches -o class.html --no-progress "${files[@]}" >/dev/null \
  2>report.err || fail "report exited $?: $(cat report.err)"
"$PY" - <<'PY' || fail "the report garbles the names"
import html
page = html.unescape(open("class.html", "rb").read().decode("utf-8"))
for name in ("Müller, Jürgen", "Anna Weiß", "Björn Schäfer", "Renée Dubois"):
    assert name in page, name
assert "\ufffd" not in page and "Ã" not in page, "replacement or mojibake characters in the page"
PY

# ---- export for MATLAB/Python: a byte-order mark on the files, pandas reads them ---------------------------
"$bin" export week3/schaefer.csv --roster roster.csv -o schaefer-samples.csv 2>export.err ||
  fail "export exited $?: $(cat export.err)"
"$bin" export week3/schaefer.csv --roster roster.csv --csv-locale de -o schaefer-de.csv 2>/dev/null ||
  fail "export --csv-locale de exited $?"
"$PY" - <<'PY' || fail "the export is wrong"
import json
import numpy as np
import pandas as pd
# For Excel (--csv-locale) with a byte-order mark; the default for MATLAB and Python (ASCII) without.
for f in ("schaefer-de.csv", "schaefer-de.fits.csv"):
    assert open(f, "rb").read(3) == b"\xef\xbb\xbf", f + ": no byte-order mark"
for f in ("schaefer-samples.csv", "schaefer-samples.fits.csv"):
    raw = open(f, "rb").read()
    assert not raw.startswith(b"\xef\xbb\xbf") and raw.decode("ascii"), f
s = pd.read_csv("schaefer-samples.csv")
f = pd.read_csv("schaefer-samples.fits.csv")
sd = pd.read_csv("schaefer-de.csv", sep=";", decimal=",")
fd = pd.read_csv("schaefer-de.fits.csv", sep=";", decimal=",")
assert list(s.columns[:3]) == ["bench", "seq", "device_time_s"], list(s.columns)
assert set(s["bench"]) == {"bench3"} and set(s["unit"]) == {"V"}
lab = [l for l in open("sim-schaefer.txt") if l.strip()]
assert len(s) == len(lab), (len(s), len(lab))
# µs and mV with decimal commas, read back in s and V: the simulator's own numbers.
for i in (0, len(lab) // 2, len(lab) - 1):
    ms, v = lab[i].split("\t")
    assert abs(s["device_time_s"][i] - int(ms) / 1000) < 1e-9 and abs(s["value"][i] - float(v)) < 1e-9, (i, lab[i])
assert (abs(sd["value"] - s["value"]) < 1e-12).all() and (abs(sd["device_time_s"] - s["device_time_s"]) < 1e-9).all()
best = f[f["best"] == 1]
truth = json.load(open("week3/schaefer.truth.json"))
assert len(best) == 2 and (abs(best["c4"] / truth["c_c"] - 1) < 0.05).all(), best[["c3", "c4"]]
for col in ("c3", "c4", "omega0", "t_cut_s"):  # the same numbers with decimal commas (empty cells: NaN)
    assert np.allclose(fd[col], f[col], rtol=1e-9, atol=0, equal_nan=True), col
PY

# ---- an .xlsx handed in: named, with what to do; the other files still fitted ---------------------------------
set +e
"$bin" fit --roster roster.csv week3/weiss_run2.xlsx week3/dubois.txt >xlsx.out 2>xlsx.err
rc=$?
set -e
[ $rc -eq 1 ] || fail "an .xlsx among the files gave exit $rc, want 1"
grep -q "weiss_run2.xlsx: error: not used: no samples: an Excel workbook (.xlsx), not a text file: .*save it as CSV (UTF-8)" xlsx.err ||
  fail "the .xlsx is not named as a workbook: $(cat xlsx.err)"
grep -qi "binary" xlsx.err && fail "the .xlsx is called binary data: $(cat xlsx.err)"
grep -q "^run 2:" xlsx.out || fail "the other file was not fitted beside the .xlsx: $(cat xlsx.out)"
echo "PASS: a class's Windows files (Excel roster cp1252, UTF-16, Ctrl-Z, µs/mV CSV, xlsx) end to end"
