#!/usr/bin/env python3
"""Judge issue 43's held-out cases: python3 judge.py BIN_DIR SCRATCH_DIR

Prints one `PASS name: …` or `FAIL name: why` per case and `SUMMARY: N/M passed`; exits 1 if
any failed. Uses only the options README and docs/cli.md document. Whatever option a refusal or
a doubt proposes is followed (up to 4 rounds) and the result judged against the physics.
Also `judge.py --feed BIN FILE OUTDIR` (run inside `unshare -n`): one bridge on a pseudo-terminal
fed FILE's bytes, a logger recording what it publishes."""
import csv
import glob
import html
import io
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time
import unicodedata

HERE = os.path.dirname(os.path.abspath(__file__))
DEADLINE = time.monotonic() + 270.0          # the whole run stays under 5 minutes
URL = "udpm://239.255.76.67:7667?ttl=0"


class Fail(Exception):
    pass


def left():
    return DEADLINE - time.monotonic()


def run(cmd, cwd=None, timeout=60.0):
    t = max(1.0, min(timeout, left()))
    try:
        p = subprocess.run(cmd, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, timeout=t)
    except subprocess.TimeoutExpired:
        raise Fail("timed out after %.0f s: %s" % (t, " ".join(cmd[:4])))
    return p.returncode, p.stdout.decode("utf-8", "replace"), p.stderr.decode("utf-8", "replace")


def first_lines(text, n=2, width=300):
    ls = [l for l in text.splitlines() if l.strip()]
    s = " | ".join(ls[:n])
    return s[:width] + ("…" if len(s) > width else "")


def nfc(s):
    return unicodedata.normalize("NFC", s or "")


# ---------------------------------------------------------------- proposals, followed

_OPTS = None


def fit_options(spindown):
    """{option: takes_value} from `spindown fit --help` (CLI11: `--name TYPE …` takes a value)."""
    global _OPTS
    if _OPTS is None:
        _, out, _ = run([spindown, "fit", "--help"], timeout=20)
        opts = {}
        for line in out.splitlines():
            m = re.match(r"\s+(?:-\w,)?--([a-z][a-z0-9-]*)(?:\s+([A-Z]+)[^\s]*)?", line)
            if m:
                opts[m.group(1)] = bool(m.group(2)) and m.group(2) in ("TEXT", "FLOAT", "INT", "UINT")
        _OPTS = opts
    return _OPTS


def strip_parens(s):
    out, depth = [], 0
    for ch in s:
        if ch == "(":
            depth += 1
        elif ch == ")":
            depth = max(0, depth - 1)
        elif depth == 0:
            out.append(ch)
    return "".join(out)


VALUE_RE = re.compile(r"""^(?:[-+]?\d[\d.eE+-]*|ms|s|us|µs|V|mV|rpm|rev/s|rad/s|deg/s|tab|space|,|;|'[^']*'|"[^"]*"|`[^`]*`)$""")


def proposals(text, spindown):
    """Options a message proposes, in order: `--name value` (or a flag) outside parentheses,
    the value one that looks like a value (a number, a unit, a delimiter, a quoted name)."""
    known = fit_options(spindown)
    props = []
    for line in text.splitlines():
        body = strip_parens(line)
        toks = re.findall(r"--[a-z][a-z0-9-]*|[^\s]+", body)
        i = 0
        while i < len(toks):
            tk = toks[i]
            if re.fullmatch(r"--[a-z][a-z0-9-]*", tk):
                name = tk[2:]
                nxt = toks[i + 1].rstrip(",;.:") if i + 1 < len(toks) else ""
                if nxt.startswith("`") and not nxt.endswith("`"):
                    nxt = nxt.lstrip("`")
                takes = known.get(name)
                if takes is False:
                    props.append((name, None))
                elif nxt and not nxt.startswith("--") and VALUE_RE.match(nxt):
                    props.append((name, nxt.strip("'\"`")))
                    i += 1
                elif takes is None and not nxt:
                    props.append((name, None))
            i += 1
    return props


def as_args(opts):
    args = []
    for name, val in opts.items():
        args.append("--" + name)
        if val is not None:
            args.append(val)
    return args


def table_rows(out):
    try:
        rows = json.loads(out) if out.strip() else []
    except ValueError:
        raise Fail("--table json is not JSON: %r" % out[:200])
    return rows if isinstance(rows, list) else []


def close(val, err, truth, rel):
    if val is None or truth is None:
        return False
    return abs(val - truth) <= max(5.0 * (err or 0.0), rel * abs(truth))


def physics_ok(row, truth):
    """The combined model's c3, c4 at the truth (c4 within 5 % or 5 σ, c3 within 15 % or 5 σ)
    and the cut where it was."""
    why = []
    if not close(row.get("c4"), row.get("c4_stderr"), truth["c_c"], 0.05):
        why.append("c4 = %s (truth %.4g)" % (fmt(row.get("c4")), truth["c_c"]))
    if not close(row.get("c3"), row.get("c3_stderr"), truth["c_v_total"], 0.15):
        why.append("c3 = %s (truth %.4g)" % (fmt(row.get("c3")), truth["c_v_total"]))
    cut = truth.get("cut_device_s")
    if cut is not None and row.get("t_cut_s") is not None and abs(row["t_cut_s"] - cut) > 0.25:
        why.append("cut at %.3f s (truth %.3f s)" % (row["t_cut_s"], cut))
    return why


def fmt(x):
    return "%.4g" % x if isinstance(x, (int, float)) else str(x)


def best_row(rows, truth):
    cut = truth.get("cut_device_s")
    rows = [r for r in rows if r.get("c4") is not None] or rows
    if not rows:
        return None
    if cut is None:
        return rows[0]
    return min(rows, key=lambda r: abs((r.get("t_cut_s") or 1e18) - cut))


def follow(spindown, cwd, files, truth, base=(), judge_row=None, rounds=4):
    """Run fit --table json, follow every new option proposed, judge the result. Returns a
    PASS message or raises Fail."""
    opts = {}
    tried = set()
    history = []
    for rnd in range(rounds + 1):
        cmd = [spindown, "fit", "--table", "json"] + list(base) + as_args(opts) + files
        rc, out, err = run(cmd, cwd=cwd)
        taken = " ".join(as_args(opts)) or "(no options)"
        if rc == 2:
            raise Fail("%s is bad usage (exit 2): %s" % (
                "following the proposal " + taken if opts else "the plain command", first_lines(err)))
        rows = table_rows(out)
        row = best_row(rows, truth) if rows else None
        doubts = " ".join((r.get("doubts") or "") for r in rows)
        text = err + "\n" + doubts
        if row is not None:
            wrong = (judge_row or physics_ok)(row, truth)
            if not wrong:
                return "read right%s: c3 %s, c4 %s (truth %.4g, %.4g)" % (
                    "" if not opts else " after following " + taken, fmt(row.get("c3")), fmt(row.get("c4")),
                    truth["c_v_total"], truth["c_c"])
            if row.get("trust") != "doubtful":
                raise Fail("confidently wrong%s: %s, trust %s%s" % (
                    "" if not opts else " after following " + taken, "; ".join(wrong), row.get("trust"),
                    (", health " + row["health"]) if row.get("health") else ""))
        new = [(n, v) for n, v in proposals(text, spindown) if (n, v) not in tried]
        if new and rnd < rounds:
            for n, v in new:
                if n not in [m for m, _ in new[:new.index((n, v))]]:   # the first value of each option
                    opts[n] = v
                tried.add((n, v))
            history.append(first_lines(text, 1, 200))
            continue
        # nothing more proposed: the refusal or the doubt must name what it is (the file's own
        # name does not count)
        bare = text
        for f in files:
            bare = bare.replace(f, "FILE").replace(os.path.basename(f), "FILE")
        if re.search(truth["name_re"], bare):
            if row is not None:
                return "doubted and named%s: %s" % ("" if not opts else " after " + taken, first_lines(doubts or err, 1, 200))
            return "refused and named%s: %s" % ("" if not opts else " after " + taken, first_lines(err, 1, 200))
        if row is None:
            raise Fail("refused%s without naming what the file is: %s" % (
                "" if not opts else " after following " + taken, first_lines(err, 2)))
        raise Fail("doubted%s without a working proposal or the cause: %s" % (
            "" if not opts else " after following " + taken, first_lines(doubts, 1)))
    raise Fail("proposals did not converge after %d rounds: %s" % (rounds, " / ".join(history)))


def load_truth(d):
    with open(os.path.join(d, "truth.json"), encoding="utf-8") as f:
        return json.load(f)


def make_baseline(spindown, d, bench, ref, out):
    rc, o, e = run([spindown, "baseline", "--bench", bench, "-o", out, ref], cwd=d)
    if rc != 0 or not os.path.exists(os.path.join(d, out) if not os.path.isabs(out) else out):
        raise Fail("setup: spindown baseline of the motor's good runs failed (exit %d): %s" % (rc, first_lines(e + o)))


# ================================================================ formats and readers

def j_fmt_tek_tbs_csv(B, d):
    t = load_truth(d)
    return follow(B["spindown"], d, [t["file"]], t)


def j_fmt_raw_adc_counts(B, d):
    t = load_truth(d)
    return follow(B["spindown"], d, [t["file"]], t)


def j_fmt_pyserial_bytes_repr(B, d):
    t = load_truth(d)
    return follow(B["spindown"], d, [t["file"]], t)


def j_fmt_micros_clock(B, d):
    t = load_truth(d)
    make_baseline(B["spindown"], d, "bench-m", "ref/bench-m_good.log", "bench-m.toml")

    def judge_row(row, truth):
        wrong = physics_ok(row, truth)
        h = (row.get("health") or "").lower()
        if wrong and h in ("ok", "check", "service"):
            return wrong + ["health %s on numbers off by the clock's unit" % h.upper()]
        if not wrong and h != "ok":
            return ["the baseline's own motor judged %s: %s" % (h.upper() or "nothing", row.get("health_reason"))]
        return wrong
    return follow(B["spindown"], d, [t["file"]], t, base=["--bench-config", "bench-m.toml"], judge_row=judge_row)


# ================================================================ the same bytes live and offline

def export_samples(spindown, path, cwd):
    rc, out, err = run([spindown, "export", path, "--csv", "--no-fits"], cwd=cwd)
    if rc == 1 and "no samples" in err:
        return [], None
    if rc != 0:
        return None, "exit %d: %s" % (rc, first_lines(err))
    rows = []
    for r in csv.DictReader(io.StringIO(out)):
        try:
            rows.append((float(r["device_time_s"]), float(r["value"])))
        except (KeyError, ValueError):
            pass
    return rows, None


def feed(bindir, path, outdir):
    """Inside `unshare -n`: loopback up with a multicast route, a logger, a bridge on a pty."""
    import pty
    import tty
    subprocess.run(["ip", "link", "set", "lo", "up"], check=True)
    subprocess.run(["ip", "route", "add", "224.0.0.0/4", "dev", "lo"], check=True)
    os.makedirs(outdir, exist_ok=True)
    data = open(path, "rb").read()
    lg = subprocess.Popen([os.path.join(bindir, "spindown-logger"), "--lcm-url", URL, "--dir", outdir,
                           "--prefix", "live", "-q"], stderr=open(os.path.join(outdir, "logger.err"), "w"))
    m, s = pty.openpty()
    tty.setraw(s)
    name = os.ttyname(s)
    time.sleep(0.4)
    br = subprocess.Popen([os.path.join(bindir, "spindown-bridge"), "--device", name, "--bench", "live1",
                           "--lcm-url", URL, "--exit-on-missing"],
                          stderr=open(os.path.join(outdir, "bridge.err"), "w"))
    # wait (bounded) for the bridge to say it is connected
    t_end = time.monotonic() + 5.0
    while time.monotonic() < t_end:
        with open(os.path.join(outdir, "bridge.err"), errors="replace") as f:
            if "connected" in f.read():
                break
        time.sleep(0.05)
    time.sleep(0.3)
    # the device's bytes, about 40x real time, in USB-sized chunks
    for i in range(0, len(data), 64):
        os.write(m, data[i:i + 64])
        time.sleep(0.0015)
    time.sleep(2.5)
    for p in (br, lg):
        p.send_signal(signal.SIGTERM)
        try:
            p.wait(timeout=8)
        except subprocess.TimeoutExpired:
            p.kill()
            p.wait()
        time.sleep(0.3)
    os.close(m)
    os.close(s)


def can_netns():
    if os.geteuid() != 0:
        return "needs root for a private network namespace (unshare -n)"
    if not shutil.which("unshare") or not shutil.which("ip"):
        return "needs unshare and ip (util-linux, iproute2)"
    rc = subprocess.run(["unshare", "-n", "true"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL).returncode
    if rc != 0:
        return "unshare -n fails here (no CAP_SYS_ADMIN?)"
    return None


def j_live(B, d):
    t = load_truth(d)
    sp = B["spindown"]
    why = can_netns()
    if why:
        raise Fail(why)
    # offline: spindown fit reads the capture as it is
    rc, out, err = run([sp, "fit", "--table", "json", t["file"]], cwd=d)
    rows = table_rows(out) if rc != 2 else []
    if not rows:
        raise Fail("spindown fit does not read the device's bytes (exit %d): %s" % (rc, first_lines(err)))
    row = best_row(rows, t)
    if t.get("physics_checked", True):
        wrong = physics_ok(row, t)
        if wrong:
            raise Fail("spindown fit reads it wrong: " + "; ".join(wrong))
    elif abs((row.get("t_cut_s") or -1e9) - t["cut_device_s"]) > 0.25:
        raise Fail("spindown fit puts the cut at %s s (truth %.3f s)" % (fmt(row.get("t_cut_s")), t["cut_device_s"]))
    off, e = export_samples(sp, t["file"], d)
    if off is None:
        raise Fail("spindown export of the capture failed: " + e)
    # live: the same bytes through spindown-bridge
    live = os.path.join(d, "live")
    shutil.rmtree(live, ignore_errors=True)
    tmo = min(40.0, left())
    try:
        p = subprocess.run(["unshare", "-n", sys.executable, os.path.abspath(__file__), "--feed", B["dir"],
                            os.path.join(d, t["file"]), live], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           timeout=tmo)
    except subprocess.TimeoutExpired:
        raise Fail("the bridge capture timed out after %.0f s" % tmo)
    logs = sorted(glob.glob(os.path.join(live, "*.lcm")))
    if p.returncode != 0 or not logs:
        raise Fail("the bridge capture did not run: %s" % first_lines(p.stderr.decode(errors="replace")))
    brerr = open(os.path.join(live, "bridge.err"), errors="replace").read()
    on, e = export_samples(sp, logs[-1], d)
    if on is None:
        raise Fail("spindown export of the bridge's log failed: " + e)
    if not on:
        raise Fail("the bridge published no sample of bytes spindown fit reads (%d samples): %s" % (
            len(off), first_lines(brerr, 3)))
    return compare_samples(off, on, brerr)


def compare_samples(off, on, brerr):
    """Every sample fit takes is one the bridge published (the same value at the same device time,
    allowing one constant clock offset), and the bridge publishes nothing fit does not take;
    up to 2 samples at the start may differ (a first line the bridge joined part-way)."""
    best = None
    for j in range(min(3, len(off))):
        for k in range(min(3, len(on))):
            shift = on[k][0] - off[j][0]
            onset = {(round(tt - shift, 4), round(v, 6)) for tt, v in on}
            matched = sum(1 for tt, v in off if (round(tt, 4), round(v, 6)) in onset)
            if best is None or matched > best[0]:
                best = (matched, shift)
    matched, shift = best
    missing = len(off) - matched
    extra = len(on) - matched
    if missing > 2 or extra > 2:
        bad = re.search(r"(\d+) good / (\d+) bad lines", brerr)
        raise Fail("live and offline differ: fit takes %d samples, the bridge published %d, %d in common%s; "
                   "bridge: %s" % (len(off), len(on), matched,
                                   (" (bridge %s good / %s bad lines)" % bad.groups()) if bad else "",
                                   first_lines(brerr, 3, 400)))
    return "the bridge published the %d samples fit takes (%d of %d in common, clock offset %.3f s)" % (
        len(on), matched, len(off), shift)


# ================================================================ a class through an LMS

def j_class_finder_nfd_roster(B, d):
    t = load_truth(d)
    sp = B["spindown"]
    os.makedirs(os.path.join(d, "benches"), exist_ok=True)
    for b in sorted(t["references"]):
        make_baseline(sp, d, b, "ref/%s.log" % b, "benches/%s.toml" % b)
    files = sorted(os.path.join("class", f["file"]) for f in t["files"])
    rc, out, err = run([sp, "fit", "--roster", "class/roster.csv", "--bench-config", "benches",
                        "--table", "json"] + files, cwd=d)
    if rc != 0:
        raise Fail("exit %d: %s" % (rc, first_lines(err)))
    rows = table_rows(out)
    probs = []
    for f in t["files"]:
        mine = [r for r in rows if nfc(r.get("file")).endswith(nfc(f["file"]))]
        if not mine:
            probs.append("%s: no row" % f["file"])
            continue
        r = mine[0]
        if r.get("bench") != f["bench"] or nfc(r.get("student")) != f["student"]:
            probs.append("%s: bench %r student %r (roster: %s, %s)" % (f["student"], r.get("bench"), r.get("student"),
                                                                       f["bench"], f["student"]))
            continue
        h = (r.get("health") or "").lower()
        if f["health"] == "ok" and h != "ok":
            probs.append("%s (%s): health %r, a healthy motor" % (f["student"], f["bench"], h))
        if f["health"] == "not ok" and h not in ("check", "service"):
            probs.append("%s (%s): health %r on the worn bench" % (f["student"], f["bench"], h))
    if re.search(r"not in the roster|give its folder|folder too", err):
        probs.append("stderr: " + first_lines("\n".join(l for l in err.splitlines()
                                                        if re.search(r"roster|folder", l)), 1, 200))
    if any((r.get("bench") or "").startswith("putty") for r in rows):
        probs.append("a bench named after the shared file name 'putty.log'")
    if probs:
        raise Fail("; ".join(probs[:4]) + (" …" if len(probs) > 4 else ""))
    return "%d files matched to their NFD roster rows; the worn bench's 2 students CHECK/SERVICE, the rest OK" % len(rows)


def j_class_excel_mac_roster(B, d):
    t = load_truth(d)
    sp = B["spindown"]
    files = [f["file"] for f in t["files"]]

    def check(rows):
        probs = []
        for f in t["files"]:
            r = [x for x in rows if os.path.basename(x.get("file", "")) == f["file"]]
            if not r:
                probs.append("%s: no row" % f["file"])
            elif r[0].get("bench") != f["bench"] or nfc(r[0].get("student")) != f["student"]:
                probs.append("%s: bench %r student %r (truth %s, %s)" % (f["file"], r[0].get("bench"),
                                                                          r[0].get("student"), f["bench"], f["student"]))
        return probs
    rc, out, err = run([sp, "fit", "--roster", "roster.csv", "--table", "json"] + files, cwd=d)
    if rc == 0:
        probs = check(table_rows(out))
        if probs:
            raise Fail("names read wrong from the Mac OS Roman roster: " + "; ".join(probs))
        return "Mac OS Roman roster read: Zoë Brontë, François Mäder, Jürgen Groß"
    if rc == 2 and re.search(r"UTF-8", err):
        # follow the advice: save it again from Excel for Mac as "CSV UTF-8" (BOM, CR LF)
        with open(os.path.join(d, "roster.csv"), "rb") as f:
            text = f.read().decode("mac_roman")
        lines = [l for l in re.split(r"\r\n|\r|\n", text) if l]
        with open(os.path.join(d, "roster.csv"), "wb") as f:
            f.write(("\ufeff" + "\r\n".join(lines) + "\r\n").encode("utf-8"))
        rc2, out2, err2 = run([sp, "fit", "--roster", "roster.csv", "--table", "json"] + files, cwd=d)
        if rc2 != 0:
            raise Fail("refused (%s); saved as CSV UTF-8 as advised, still exit %d: %s" % (
                first_lines(err, 1, 150), rc2, first_lines(err2)))
        probs = check(table_rows(out2))
        if probs:
            raise Fail("after saving as CSV UTF-8 as advised: " + "; ".join(probs))
        return "refused naming the encoding (%s); as CSV UTF-8 the names are right" % first_lines(err, 1, 150)
    raise Fail("exit %d without the way to fix it: %s" % (rc, first_lines(err)))


# ================================================================ verdicts that name the cause

def verdict_text(row):
    return ((row.get("health_reason") or "") + " ; " + (row.get("doubts") or "")).strip(" ;")


def j_verdict_cause(B, d):
    t = load_truth(d)
    sp = B["spindown"]
    bench = t["bench"]
    make_baseline(sp, d, bench, "ref/%s_good.log" % bench, bench + ".toml")
    rc, out, err = run([sp, "fit", "--bench-config", bench + ".toml", "--table", "json", t["file"]], cwd=d)
    rows = table_rows(out) if rc != 2 else []
    if not rows:
        raise Fail("no run fitted (exit %d): %s" % (rc, first_lines(err)))
    row = best_row(rows, t)
    h = (row.get("health") or "").lower()
    text = verdict_text(row)
    ref = t["reference"]
    ratios = "c3 %.2f×, c4 %.2f× the reference motor (physics: %.2f×, %.2f×)" % (
        (row.get("c3") or 0) / ref["c_v"], (row.get("c4") or 0) / ref["c_c"],
        t["expected_ratios"]["c3"], t["expected_ratios"]["c4"])
    if h == "ok":
        raise Fail("judged OK (%s): %s" % (ratios, text[:200]))
    m = re.search(t["cause_re"], text)
    if not m:
        raise Fail("%s: %s names no %s: %s" % (ratios, h.upper() or "verdict", t["cause"], text[:300]))
    w = re.search(t["wrong_first_re"], text)
    if w and w.start() < m.start():
        raise Fail("%s: %s names %r before the cause (%s): %s" % (ratios, h.upper(), w.group(0), t["cause"], text[:300]))
    return "%s, %s: %s" % (h.upper() or "verdict", ratios, text[:200])


def html_text(path):
    with open(path, encoding="utf-8", errors="replace") as f:
        s = f.read()
    s = re.sub(r"(?is)<(script|style)\b.*?</\1>", " ", s)
    s = html.unescape(re.sub(r"<[^>]+>", " ", s))
    return re.sub(r"\s+", " ", s)


def j_verdict_step_up_semester(B, d):
    t = load_truth(d)
    sp = B["spindown"]
    make_baseline(sp, d, "bench-w", "ref/bench-w_good.log", "bench-w.toml")
    files = [w["file"] for w in t["weeks"]]
    rc, out, err = run([sp, "report", "--bench", "bench-w", "--bench-config", "bench-w.toml", "--no-explain",
                        "--no-progress", "-o", "semester.html"] + files, cwd=d, timeout=120)
    if rc not in (0, 1) or not os.path.exists(os.path.join(d, "semester.html")):
        raise Fail("report exit %d: %s" % (rc, first_lines(err)))
    text = html_text(os.path.join(d, "semester.html"))
    when = (r"2024-10-2[29]|2024\.10\.2[29]|2[29]\.10\.|(?:Oct\w*\.?) 2[29]|2[29] Oct|10/2[29]|"
            r"week ?[45]\b|week[45]\.log|session ?[45]\b")
    step = None
    for m in re.finditer(r"(?i)\bstep(?:s|ped)?\b", text):
        win = text[max(0, m.start() - 200):m.end() + 200]
        if re.search(when, win, re.I):
            step = win
            break
    bad = re.search(r"(?i)drifting|rising steadily|rose steadily|not steady", text)
    if step and not bad:
        return "names the step: …%s…" % step.strip()[:220]
    trend = re.search(r"(?i)dry friction (?:rose|fell|stepped)[^.]{0,260}", text)
    raise Fail("%s%s" % ("no step between week 4 (2024-10-22) and week 5 (2024-10-29) named" if not step else "names a step",
                         ("; says %r: %s" % (bad.group(0), trend.group(0) if trend else "")) if bad else ""))


def j_verdict_one_decimal_print(B, d):
    t = load_truth(d)
    sp = B["spindown"]
    rc, out, err = run([sp, "explain", "--json", t["file"]], cwd=d)
    if rc != 0:
        raise Fail("explain exit %d: %s" % (rc, first_lines(err)))
    try:
        runs = json.loads(out)["files"][0]["runs"]
    except (ValueError, KeyError, IndexError):
        raise Fail("explain --json gave no run")
    if not runs:
        raise Fail("explain found no run")
    r = runs[0]
    final = r.get("final") or []
    extra = [e for e in final if e not in t["allowed_effects"]]
    added = [s.get("added") for s in r.get("steps", []) if s.get("added")]
    probs = []
    if "coulomb" in extra:
        c4 = (r.get("final_params") or {}).get("c4") or {}
        v, e = c4.get("value"), c4.get("stderr") or 0.0
        if v is not None and v - 3 * e <= 0:
            extra.remove("coulomb")          # a dry friction consistent with none is no claim
    if extra:
        probs.append("explain ends at %s (added %s): the 0.1 V print's rounding near zero taken for %s" % (
            "+".join(final), ", ".join(added) or "-", ", ".join(extra)))
    # fit: viscous, or a combined model whose dry friction is consistent with none
    rc2, out2, err2 = run([sp, "fit", "--table", "json", t["file"]], cwd=d)
    rows = table_rows(out2) if rc2 != 2 else []
    if not rows:
        probs.append("fit: no run (exit %d): %s" % (rc2, first_lines(err2, 1)))
    else:
        row = rows[0]
        if row.get("best") not in ("viscous",):
            c4, e4 = row.get("c4"), row.get("c4_stderr") or 0.0
            if not (row.get("best") == "combined" and c4 is not None and c4 - 3 * e4 <= 0):
                probs.append("fit says %s (c4 %s ± %s) where the motor has no dry friction" % (
                    row.get("best"), fmt(c4), fmt(e4)))
        elif not close(row.get("c1"), row.get("c1_stderr"), t["c_v_total"], 0.05):
            probs.append("fit's c1 = %s (truth %.4g)" % (fmt(row.get("c1")), t["c_v_total"]))
    if probs:
        raise Fail("; ".join(probs))
    return "explain ends at %s; fit says %s" % ("+".join(final), rows[0].get("best"))


CASES = [
    ("fmt_tek_tbs_csv", j_fmt_tek_tbs_csv),
    ("fmt_raw_adc_counts", j_fmt_raw_adc_counts),
    ("fmt_micros_clock", j_fmt_micros_clock),
    ("fmt_pyserial_bytes_repr", j_fmt_pyserial_bytes_repr),
    ("live_pico_micropython_space", j_live),
    ("live_uno_header_three_columns", j_live),
    ("live_esp32_boot_rom", j_live),
    ("class_finder_nfd_roster", j_class_finder_nfd_roster),
    ("class_excel_mac_roster", j_class_excel_mac_roster),
    ("verdict_dmm_across_leads", j_verdict_cause),
    ("verdict_steel_flywheel", j_verdict_cause),
    ("verdict_3v3_board", j_verdict_cause),
    ("verdict_step_up_semester", j_verdict_step_up_semester),
    ("verdict_one_decimal_print", j_verdict_one_decimal_print),
]


def main():
    if len(sys.argv) == 5 and sys.argv[1] == "--feed":
        feed(sys.argv[2], sys.argv[3], sys.argv[4])
        return 0
    if len(sys.argv) != 3:
        sys.exit("usage: judge.py BIN_DIR SCRATCH_DIR")
    bindir, scratch = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    B = {"dir": bindir, "spindown": os.path.join(bindir, "spindown")}
    passed = 0
    for name, fn in CASES:
        d = os.path.join(scratch, name)
        try:
            if left() < 5:
                raise Fail("not run: the 5-minute budget is spent")
            if not os.path.exists(B["spindown"]):
                raise Fail("no spindown in %s" % bindir)
            msg = fn(B, d)
            print("PASS %s: %s" % (name, msg), flush=True)
            passed += 1
        except Fail as e:
            print("FAIL %s: %s" % (name, e), flush=True)
        except Exception as e:  # a judge error is a failure of the case, said
            print("FAIL %s: judge error %s: %s" % (name, type(e).__name__, e), flush=True)
    print("SUMMARY: %d/%d passed" % (passed, len(CASES)))
    return 0 if passed == len(CASES) else 1


if __name__ == "__main__":
    sys.exit(main())
