#!/bin/bash
# `spindown report`: one self-contained HTML page from the lab's sample files (with a bench
# config whose baseline the motor is far above) and from a generated LCM log holding two
# benches (spindown-run-publisher -> spindown-logger in a private network namespace, ttl=0).
# Checks: exit codes, the page parses with balanced tags (python3 html.parser), no external
# references, text from files escaped, one run figure per run, ± coefficients, verdicts, the
# benches of the log grouped, and no progress output when stderr is not a terminal.
source "$(dirname "${BASH_SOURCE[0]}")/netns_common.bash"
D=${SPINDOWN_SAMPLE_DATA:?}

# The page parses, its tags balance, and it reaches nothing outside itself.
check_page() {
  python3 - "$1" <<'EOF'
import sys
from html.parser import HTMLParser
VOID = {"meta", "br", "link", "img", "input", "hr", "wbr", "source", "col", "area", "base", "embed", "track"}
class Check(HTMLParser):
    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.stack, self.errors, self.counts, self.text = [], [], {}, []
    def handle_starttag(self, tag, attrs):
        self.counts[tag] = self.counts.get(tag, 0) + 1
        for name, value in attrs:
            v = (value or "").lower()
            if name in ("src", "href", "xlink:href") and not v.startswith("#"):
                self.errors.append(f"external {name}={value!r} on <{tag}>")
            if v.startswith(("http:", "https:", "//")):
                self.errors.append(f"external reference {name}={value!r}")
        if tag in ("script", "iframe", "object", "link", "img"):
            self.errors.append(f"<{tag}> in the page")
        if tag not in VOID:
            self.stack.append((tag, self.getpos()))
    def handle_startendtag(self, tag, attrs):
        self.counts[tag] = self.counts.get(tag, 0) + 1
    def handle_endtag(self, tag):
        if not self.stack or self.stack[-1][0] != tag:
            self.errors.append(f"</{tag}> at {self.getpos()} closes {self.stack[-1] if self.stack else 'nothing'}")
            return
        self.stack.pop()
    def handle_data(self, data):
        self.text.append(data)
c = Check()
page = open(sys.argv[1], encoding="utf-8").read()
c.feed(page)
c.close()
if c.stack:
    c.errors.append(f"unclosed: {c.stack[:5]}")
low = page.lower()
for bad in ("http://", "https://", "url(", "@import"):
    if bad in low:
        c.errors.append(f"{bad} in the page")
if c.errors:
    print("\n".join(c.errors[:20]))
    sys.exit(1)
print(f"{sys.argv[1]}: parses, tags balance, self-contained ({c.counts.get('svg', 0)} svg, "
      f"{c.counts.get('table', 0)} tables)")
EOF
}
count() { grep -o -- "$2" "$1" | wc -l; }
no_progress() {  # stderr of a run whose stderr was a file: no progress line, no carriage return
  if grep -q $'\r' "$1" || grep -Eq 'ETA|/s  |runs [0-9]+/[0-9]+' "$1"; then fail "progress output in $1 (not a terminal)"; fi
}

# --- 1. the lab's sample files, one of them against a baseline it is far above -------------
cat >"$T/seed.toml" <<'EOF'
bench_id = "seed-3v-run1"
[baseline]
c_viscous_n_m_s = 1.8e-7
c_viscous_stderr = 0.05e-7
c_coulomb_n_m = 4.0e-5
c_coulomb_stderr = 0.04e-5
runs = 4
date = "2026-01-12"
EOF
"$B/spindown" report "$D"/*.tsv --bench-config "$T/seed.toml" -o "$T/data.html" >"$T/data.out" 2>"$T/data.err" \
  || fail "report of the sample files exited $?"
check_page "$T/data.html" || fail "sample-file page"
no_progress "$T/data.err"
runs=$(ls "$D"/*.tsv | wc -l)
[ "$(count "$T/data.html" '<svg class="run-plot"')" -eq "$runs" ] || fail "want one run figure per file ($runs)"
[ "$(count "$T/data.html" '<table class="coef">')" -eq "$runs" ] || fail "want one coefficient table per run"
grep -q 'g·cm²·rad·s⁻²' "$T/data.html" || fail "no lab units"
grep -Eq '[0-9] ± [0-9.]+\)?(e-0[0-9])? N·m·s/rad' "$T/data.html" || fail "no SI coefficient ± error"
grep -q '<span class="badge service">SERVICE</span>' "$T/data.html" || fail "the bench above its baseline is not flagged"
grep -q "$T/seed.toml" "$T/data.html" || fail "the verdict does not name its reference"
grep -q 'no reference configured' "$T/data.html" || fail "benches without a config must say so"
grep -q 'Missing effect: <strong>coulomb</strong>' "$T/data.html" || fail "no explain story"
grep -q 'Summary across benches and runs' "$T/data.html" || fail "no summary"
# One viscous fit per run on the page (issue 22): the explain story's belief is the coefficient
# table's viscous model, with the same c1 and ω0, and the page names one noise figure.
python3 - "$T/data.html" <<'EOF' || fail "two different viscous fits of one run on the page"
import html, re, sys
page = html.unescape(open(sys.argv[1], encoding="utf-8").read())
runs = page.split('<article class="run"')[1:]
checked = 0
for run in runs:
    table = re.search(r'<td rowspan="\d+">viscous.*?<td>c1</td><td class="num">([^<]+)</td>.*?<td>ω0</td><td class="num">([^<]+)</td>', run, re.S)
    story = re.search(r'Starting from the belief <strong>viscous</strong> — the fit\'s viscous model above: c1 = (.+?) = [^,]+, ω0 = (.+?) \(RMSE', run)
    if not table or not story:
        continue
    assert table.group(1).strip() == story.group(1).strip(), (table.group(1), story.group(1))
    assert table.group(2).strip() == story.group(2).strip(), (table.group(2), story.group(2))
    checked += 1
assert checked >= 5, f"only {checked} runs compared"
assert "standstill noise" not in page and "reading noise σ" in page
print(f"one viscous fit per run: {checked} runs, the story's c1 and ω0 are the table's")
EOF
echo "sample files: $(cat "$T/data.out")"

# --- 2. text from files is escaped (a file name, a roster's student name) -------------------
cp "$D/seed-3v-run1.tsv" "$T/<b>bold & \"q\".tsv"
printf 'file,bench,student\n"<b>bold & ""q"".tsv",b1,<script>alert(1)</script>\n' >"$T/roster.csv"
"$B/spindown" report "$T/<b>bold & \"q\".tsv" --roster "$T/roster.csv" -o "$T/evil.html" \
  >"$T/evil.out" 2>"$T/evil.err" || fail "report of a strangely named file exited $?"
check_page "$T/evil.html" || fail "escaped page"
grep -q '<script>' "$T/evil.html" && fail "a student's name reached the page unescaped"
grep -q '<b>bold' "$T/evil.html" && fail "a file name reached the page unescaped"
grep -q '&lt;script&gt;alert(1)&lt;/script&gt;' "$T/evil.html" || fail "escaped student name missing"
# A bench id is one rule everywhere ([A-Za-z0-9_-], as channel names): --bench refuses markup.
"$B/spindown" report "$T/<b>bold & \"q\".tsv" --bench '<script>' -o "$T/never.html" 2>"$T/never.err" &&
  fail "report accepted --bench '<script>'"
grep -q "bench '<script>'" "$T/never.err" || fail "the refused --bench is not named: $(cat "$T/never.err")"
[ ! -e "$T/never.html" ] || fail "a refused report wrote its page"
grep -q '&lt;b&gt;bold &amp; &quot;q&quot;.tsv' "$T/evil.html" || fail "escaped file name missing"

# --- 3. a generated LCM log with two benches ----------------------------------------------
mkdir -p "$T/log"
"$B/spindown-logger" --lcm-url "$URL" --dir "$T/log" --prefix report --flush-interval 0.2 -q \
  >"$T/logger.out" 2>"$T/logger.err" &
LOGGER=$!; PIDS+=($LOGGER)
sleep 0.5
"$B/spindown-run-publisher" --lcm-url "$URL" --benches 2 --runs 2 --prefix lab- --speed 25 --batch 8 \
  --stagger 0.2 --wait-fits 0 >"$T/publisher.out" 2>"$T/publisher.err" || fail "publisher exited $?"
sleep 0.5
stop "$LOGGER"
LOG=$(ls "$T"/log/*.lcm | head -1)
[ -s "$LOG" ] || fail "no log written"
"$B/spindown" report "$LOG" -o "$T/log.html" >"$T/log.out" 2>"$T/log.err" || fail "report of the log exited $?"
check_page "$T/log.html" || fail "log page"
no_progress "$T/log.err"
[ "$(count "$T/log.html" '<section class="bench"')" -eq 2 ] || fail "want the log's two benches as two sections"
[ "$(count "$T/log.html" '<svg class="run-plot"')" -eq 4 ] || fail "want 4 run figures (2 benches x 2 runs)"
[ "$(count "$T/log.html" '<svg class="trend-plot"')" -eq 2 ] || fail "want a trend figure per bench"
grep -q 'id="bench-lab-000"' "$T/log.html" && grep -q 'id="bench-lab-001"' "$T/log.html" || fail "bench ids"
echo "LCM log: $(cat "$T/log.out")"

# J and K_b by one rule in fit and report: the log's CONFIG says J = 1.12687602e-5 (the lab's);
# a bench file for lab-000 says J = 2.5e-5 and no K_b. Both commands take J from the file and
# K_b from the CONFIG, and print the same friction.
cat >"$T/lab-000.toml" <<'EOF'
bench_id = "lab-000"
[bench]
inertia_kg_m2 = 2.5e-5
EOF
"$B/spindown" fit "$LOG" --bench-config "$T/lab-000.toml" --json >"$T/rule.json" 2>"$T/rule.err" ||
  fail "fit with a bench file exited $?: $(head -c 400 "$T/rule.err")"
"$B/spindown" report "$LOG" --bench-config "$T/lab-000.toml" --no-explain -o "$T/rule.html" >/dev/null 2>&1 ||
  fail "report with a bench file exited $?"
python3 - "$T/rule.json" "$T/rule.html" <<'EOF' || fail "fit and report take J and K_b by different rules"
import json, re, sys
doc = json.load(open(sys.argv[1]))
runs = [r for f in doc["files"] for r in f["runs"] if "lab-000" in json.dumps(r.get("bench", {})) or r.get("bench_id") == "lab-000"]
assert runs, "no run of lab-000 in fit --json"
js = {r["bench"]["J"] for r in runs}
assert js == {2.5e-5}, f"fit took J = {js}, not the bench file's"
page = open(sys.argv[2], encoding="utf-8").read()
sec = page[page.index('id="bench-lab-000"'):]
nxt = sec.find('<section class="bench"', 10)
sec = sec if nxt < 0 else sec[:nxt]
j_page = set(re.findall(r"J = ([0-9.e+-]+) kg·m²", sec))
assert j_page == {"2.5e-05"}, f"report took J = {j_page}"
print(f"fit and report agree: J = 2.5e-5 from the bench file (over the CONFIG), K_b from the CONFIG")
EOF

# Files of both kinds in one report; refit with --no-progress prints no progress either.
"$B/spindown" report "$LOG" "$D/seed-3v-run1.tsv" -o "$T/both.html" --no-progress >"$T/both.out" 2>"$T/both.err" \
  || fail "mixed report exited $?"
check_page "$T/both.html" || fail "mixed page"
[ "$(count "$T/both.html" '<svg class="run-plot"')" -eq 5 ] || fail "want 5 run figures in the mixed report"
"$B/spindown" refit "$LOG" >"$T/refit.out" 2>"$T/refit.err" || fail "refit exited $?"
no_progress "$T/refit.err"

# --- 4. a semester as an instructor prints it (issue 30) ------------------------------------
# Four weekly PuTTY logs of one bench whose dry friction rises 8 % a week: far apart beyond their
# errors, but in a line in time: wear, said as drift, not "check which runs belong to this motor".
# PuTTY's header time is the PC's local time, never called UTC; each run's figure shows the whole
# recording with the fitted window shaded; the page prints compactly.
for w in 0 1 2 3; do
  "$B/spindown" simulate --runs 1 --seed $((60 + w)) --putty-header --coulomb "$(python3 -c "print(1.1389e-4 * (1 + 0.08 * $w))")" \
    -o "$T/week$w.raw" >/dev/null 2>&1 || fail "simulate week $w"
  sed "1s/PuTTY log 2023.09.14/PuTTY log 2023.09.$(printf %02d $((1 + 7 * w)))/" "$T/week$w.raw" >"$T/bench9_week$w.txt"
done
"$B/spindown" report "$T"/bench9_week[0-3].txt --bench-pattern '(bench[0-9]+)_([a-z0-9]+)' --no-explain -o "$T/semester.html" \
  >"$T/semester.out" 2>"$T/semester.err" || fail "semester report exited $?"
check_page "$T/semester.html" || fail "semester page"
python3 - "$T/semester.html" <<'EOF' || fail "the semester page"
import html, re, sys
raw = open(sys.argv[1], encoding="utf-8").read()
text = html.unescape(re.sub(r"<[^>]+>", " ", raw))
assert re.search(r"dry friction rose \d+ % ± \d+ % over 21 days \(4 runs, 4 sessions\): drifting: friction rising "
                 r"steadily over 4 sessions: wear", text), re.findall(r"dry friction[^.]{0,200}", text)[:2]
assert "check which runs belong" not in text
assert "2023-09-01 10:2" in text and "local time" in text
assert not re.search(r"10:2\d:\d\d UTC", text), re.findall(r"\d\d:\d\d:\d\d UTC", text)
assert raw.count('<rect class="fitted-window"') == 4 and raw.count("recording outside the fitted window") == 4
css = raw[raw.index("@media print{"):raw.index("</style>")]
assert "section.bench" in css and "display:none" in css, css
assert raw.count('<table class="runs">') == 1 and len(re.findall(r"<tr><td>bench9</td>", raw)) == 4
print("semester: wear said as drift; PuTTY time local; 4 figures with the fitted window shaded; print stylesheet")
EOF
# An LCM log's times are UTC and say so.
grep -Eq '[0-9]{2}:[0-9]{2}:[0-9]{2} UTC' "$T/log.html" || fail "the LCM log's times are not labelled UTC"

# --- 5. exit codes -------------------------------------------------------------------------
set +e
"$B/spindown" report "$D/seed-3v-run1.tsv" >/dev/null 2>"$T/usage.err"; rc=$?
[ $rc -eq 2 ] || fail "no -o: want exit 2, got $rc"
printf 'bench_id = "x"\n[baseline\n' >"$T/broken.toml"
"$B/spindown" report "$D/seed-3v-run1.tsv" --bench-config "$T/broken.toml" -o "$T/x.html" >/dev/null 2>"$T/broken.err"; rc=$?
[ $rc -eq 2 ] || fail "a broken bench config: want exit 2, got $rc"
grep -q 'broken.toml' "$T/broken.err" || fail "the broken config's message does not name the file"
"$B/spindown" report "$D/seed-3v-run1.tsv" "$T/missing.tsv" -o "$T/partial.html" >/dev/null 2>"$T/partial.err"; rc=$?
[ $rc -eq 1 ] || fail "a missing file: want exit 1, got $rc"
grep -q 'missing.tsv' "$T/partial.err" || fail "the missing file is not named"
[ "$(count "$T/partial.html" '<svg class="run-plot"')" -eq 1 ] || fail "the usable file must still be reported"
"$B/spindown" report "$D/seed-3v-run1.tsv" -o "$T/no/such/dir/x.html" >/dev/null 2>"$T/write.err"; rc=$?
[ $rc -eq 1 ] || fail "unwritable output: want exit 1, got $rc"
set -e
check_page "$T/partial.html" || fail "partial page"
echo "cli_report: ok"
