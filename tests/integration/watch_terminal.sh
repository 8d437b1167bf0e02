#!/bin/bash
# `spindown watch` on real terminals of a given size, with a live lab feeding it:
#  - spindown-fitter (with bench files, so every fit carries a health verdict) and
#    spindown-run-publisher (3 benches with long ids, 3 runs each, sequence gaps so that events
#    come often and long) on a private LCM URL in a network namespace (ttl=0);
#  - two `spindown watch` at once, each on its own pseudo-terminal sized with TIOCSWINSZ before it
#    starts: 80 columns × 32 rows and 120 × 40.
# The bytes each watch wrote go through a small terminal model (cursor, autowrap, scrolling,
# ESC[H, ESC[2J): every frame (the screen just before the next redraw clears it) must show the
# title on the first row, the header and one row per bench; no line written may be wider than the
# terminal (a wrapped line would push the table up); every bench row holds the combined model's c3
# and c4 with their errors and the health verdict the fitter published (at 80 columns too), and at
# 120 columns nothing of a row is cut. Bounded: the watches stop after --duration, every wait ends.
source "$(dirname "${BASH_SOURCE[0]}")/netns_common.bash"

mkdir -p "$T/benches"
for i in 000 001 002; do
  cat >"$T/benches/teaching-lab-bench-$i.toml" <<EOF
bench_id = "teaching-lab-bench-$i"

[baseline]
c_viscous_n_m_s = 1.8e-07
c_viscous_stderr = 2.0e-09
c_coulomb_n_m = 1.14e-04
c_coulomb_stderr = 4.0e-07
runs = 3
date = "2024-09-14"
EOF
done

"$B/spindown-fitter" --lcm-url "$URL" --status-period 0.3 --bench-config "$T/benches" -v 2>"$T/fitter.err" &
PIDS+=($!)
FITTER=$!

python3 - "$B/spindown" "$URL" "$T" <<'EOF' &
import fcntl, json, os, pty, select, struct, subprocess, sys, termios, time

spindown, url, work = sys.argv[1:4]
sizes = [(80, 32), (120, 40)]
procs = []
for cols, rows in sizes:
    master, slave = pty.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", rows, cols, 0, 0))
    p = subprocess.Popen([spindown, "watch", "--lcm-url", url, "--interval", "0.25", "--duration", "24"],
                         stdin=slave, stdout=slave, stderr=open(os.path.join(work, "watch%d.err" % cols), "wb"),
                         close_fds=True)
    os.close(slave)
    procs.append((cols, rows, master, p, bytearray()))
deadline = time.monotonic() + 40
while time.monotonic() < deadline and any(p.poll() is None or m >= 0 for _, _, m, p, _ in procs):
    fds = [m for _, _, m, _, _ in procs if m >= 0]
    if not fds:
        break
    ready, _, _ = select.select(fds, [], [], 0.5)
    for k, (cols, rows, m, p, buf) in enumerate(procs):
        if m in ready:
            try:
                data = os.read(m, 65536)
            except OSError:
                data = b""
            if not data:
                os.close(m)
                procs[k] = (cols, rows, -1, p, buf)
            else:
                buf += data
for cols, rows, m, p, buf in procs:
    try:
        p.wait(timeout=5)
    except subprocess.TimeoutExpired:
        p.kill()
    with open(os.path.join(work, "watch%d.bytes" % cols), "wb") as f:
        f.write(bytes(buf))
EOF
WATCHES=$!
PIDS+=($WATCHES)
sleep 1.5
"$B/spindown-run-publisher" --lcm-url "$URL" --benches 3 --runs 3 --speed 20 --stagger 0.4 \
  --prefix teaching-lab-bench- --gap-every 40 --wait-fits 15 --report "$T/report.json" \
  >"$T/publisher.out" 2>"$T/publisher.err" || fail "spindown-run-publisher"
for _ in $(seq 400); do kill -0 "$WATCHES" 2>/dev/null || break; sleep 0.1; done
kill -0 "$WATCHES" 2>/dev/null && fail "the watches did not end after --duration"
wait "$WATCHES" || fail "the pty driver failed"
stop "$FITTER"

python3 - "$T" <<'EOF' || fail "watch on 80x32 and 120x40 terminals"
import json, re, sys, unicodedata

work = sys.argv[1]
report = json.load(open(work + "/report.json"))
fits = report["fit_list"]
benches = sorted({f["bench"] for f in fits})
assert len(benches) == 3 and report["fits"] >= 9, report


class Screen:
    """The terminal as the watch's bytes leave it: autowrap at the last column, scrolling at the
    last row, CR, LF, ESC[H and ESC[2J (what the watch writes); a frame is the screen just before
    each ESC[2J."""

    def __init__(self, cols, rows):
        self.cols, self.rows = cols, rows
        self.clear()
        self.frames, self.scrolled, self.lines_written = [], 0, []

    def clear(self):
        self.cells = [[" "] * self.cols for _ in range(self.rows)]
        self.r = self.c = 0

    def feed(self, text):
        i, line = 0, ""
        while i < len(text):
            ch = text[i]
            if text.startswith("\x1b[H", i):
                self.r = self.c = 0
                i += 3
                continue
            if text.startswith("\x1b[2J", i):
                self.frames.append(["".join(row).rstrip() for row in self.cells])
                self.clear()
                i += 4
                continue
            if ch == "\r":
                self.c = 0
            elif ch == "\n":
                self.lines_written.append(line)
                line = ""
                self.down()
            else:
                if self.c >= self.cols:  # autowrap: the line was wider than the terminal
                    self.c = 0
                    self.down()
                self.cells[self.r][self.c] = ch
                self.c += 1
                line += ch
            i += 1
        self.frames.append(["".join(row).rstrip() for row in self.cells])

    def down(self):
        if self.r == self.rows - 1:
            self.cells = self.cells[1:] + [[" "] * self.cols]
            self.scrolled += 1
        else:
            self.r += 1


def health_words(verdict):
    return verdict.replace("_", " ").upper()


last_fit = {}
for f in fits:
    last_fit[f["bench"]] = dict(f)
# The verdicts as the fitter published them (its -v lines: "BENCH run N health: LEVEL — reason").
for line in open(work + "/fitter.err", encoding="utf-8", errors="replace"):
    m = re.match(r"spindown-fitter: (\S+) run (\d+) health: (\S+) ", line)
    if m and m.group(1) in last_fit and int(m.group(2)) == last_fit[m.group(1)]["run"]:
        last_fit[m.group(1)]["verdict"] = m.group(3)
problems = []
for cols, rows in [(80, 32), (120, 40)]:
    raw = open("%s/watch%d.bytes" % (work, cols), "rb").read().decode("utf-8", "replace")
    s = Screen(cols, rows)
    s.feed(raw)
    wide = [l for l in s.lines_written if len(l) > cols]
    if wide:
        problems.append("%dx%d: %d lines wider than the terminal, e.g. %r" % (cols, rows, len(wide), wide[0][:150]))
    if s.scrolled:
        problems.append("%dx%d: the screen scrolled %d times (the title pushed off)" % (cols, rows, s.scrolled))
    frames = [f for f in s.frames if any(l.strip() for l in f)]
    if len(frames) < 10:
        problems.append("%dx%d: only %d frames drawn" % (cols, rows, len(frames)))
        continue
    complete = 0
    for frame in frames:
        if not frame[0].startswith("spindown watch"):
            problems.append("%dx%d: a frame whose first row is not the title: %r" % (cols, rows, frame[0]))
            break
    # The frames once every bench has its last fit: the rows hold what the fitter published.
    for frame in frames:
        rows_of = {}
        header = next((i for i, l in enumerate(frame) if l.startswith("BENCH")), None)
        if header is None:
            continue
        for l in frame[header + 1:]:
            for b in benches:
                if l.startswith(b + " "):
                    rows_of[b] = l
        head = frame[header]
        # The FIT column's run number (its header's place in the row): "3 " anywhere in a row also
        # matches "3 coast" or an age of "0.3 s", before any fit.
        fit_at = head.find("FIT")
        def fit_run(row):
            words = row[fit_at:].split() if fit_at >= 0 else []
            return words[0] if words else ""
        if len(rows_of) != 3 or not all(fit_run(rows_of[b]) == str(last_fit[b]["run"]) for b in benches):
            continue
        ok = True
        for col in ("c3", "c4", "HEALTH"):
            if col not in head:
                problems.append("%dx%d: header has no %s: %r" % (cols, rows, col, head))
                ok = False
        for b in benches:
            row = rows_of[b]
            if row.count("±") < 2:
                problems.append("%dx%d: %s row has not both c3 and c4 with errors: %r" % (cols, rows, b, row))
                ok = False
            want = health_words(last_fit[b].get("verdict", ""))
            if not want or not row.rstrip().endswith(want):
                problems.append("%dx%d: %s row does not end in its health %r: %r" % (cols, rows, b, want, row))
                ok = False
            if cols == 120 and ("BRIDGE" not in head or "RMSE" not in head):
                problems.append("120 columns: columns dropped that fit: %r" % head)
                ok = False
        if not ok:
            break
        complete += 1
        if complete == 1:
            print("%dx%d, a frame with every bench fitted:" % (cols, rows))
            for l in frame:
                if l.strip():
                    print("  |" + l)
    if complete == 0:
        problems.append("%dx%d: no frame shows all three benches with their last fit" % (cols, rows))
    events = [l for f in frames for l in f if l.startswith("recent events")]
    if not events:
        problems.append("%dx%d: no frame had room for events" % (cols, rows))
if problems:
    print("\n".join(problems[:12]))
    sys.exit(1)
print("watch: 80x32 and 120x40 frames keep title, header and every bench row with c3, c4 and health; "
      "no line wider than the terminal, no scrolling")
EOF
echo "PASS watch_terminal"
