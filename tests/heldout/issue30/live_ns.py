#!/usr/bin/python3
"""The live part of issue 30's cases, run INSIDE a private network namespace (live.py starts it
with `unshare -n`).  Three benches whose Arduinos are pseudo-terminals fed by this script with
recordings made by physics.py (device time from each line's millis, sent 10x faster than real
time), one spindown-bridge per bench, spindown-fitter with the bench files, spindown-logger,
and `spindown watch` under pseudo-terminals of 80x32 and 120x40.

Prints `PASS|FAIL <id>: <msg>` lines (collected by live.py).
usage: live_ns.py BIN SCRATCH DEADLINE_S
"""
import sys
sys.dont_write_bytecode = True
import fcntl
import json
import math
import os
import pty
import re
import select
import signal
import struct
import subprocess
import sys
import termios
import threading
import time
import tty

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import physics as ph  # noqa: E402
import vt  # noqa: E402

BIN = os.path.abspath(sys.argv[1])
SCR = os.path.abspath(sys.argv[2])
DEADLINE = time.monotonic() + float(sys.argv[3])
URL = "udpm://239.255.76.67:7667?ttl=0"
SPEED = 10.0
SPINDOWN = os.path.join(BIN, "spindown")
PROCS = []
WATCH_PIDS = []


def say(ok, cid, msg):
    print("%s %s: %s" % ("PASS" if ok else "FAIL", cid, msg), flush=True)


def sh(*a):
    subprocess.run(list(a), check=False, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def start(args, log):
    f = open(log, "wb")
    p = subprocess.Popen(args, stdout=f, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                         start_new_session=True)
    PROCS.append(p)
    return p


def stop_all():
    for pid in WATCH_PIDS:
        try:
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
        except (ProcessLookupError, ChildProcessError):
            pass
    for p in reversed(PROCS):
        if p.poll() is None:
            try:
                os.killpg(p.pid, signal.SIGTERM)
            except ProcessLookupError:
                pass
    t_end = time.monotonic() + 5
    for p in reversed(PROCS):
        try:
            p.wait(timeout=max(0.1, t_end - time.monotonic()))
        except subprocess.TimeoutExpired:
            try:
                os.killpg(p.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            p.wait()


class Bench:
    """A pseudo-terminal standing in for an Arduino: the bridge opens the slave side."""

    def __init__(self, bench_id, data):
        self.id = bench_id
        self.master, self.slave = os.openpty()
        tty.setraw(self.slave)
        self.path = os.ttyname(self.slave)
        text = data.decode("ascii")
        # the PuTTY header is PuTTY's, not the Arduino's: the port carries the sketch's lines only
        self.lines = [l + "\r\n" for l in text.split("\r\n") if l and not l.startswith("=~=")]
        self.done = threading.Event()
        self.thread = threading.Thread(target=self.feed, daemon=True)

    def feed(self):
        t0 = time.monotonic()
        ms0 = None
        try:
            for l in self.lines:
                try:
                    ms = int(l.split("\t")[0])
                except ValueError:
                    continue
                if ms0 is None:
                    ms0 = ms
                due = t0 + (ms - ms0) / 1000.0 / SPEED
                dt = due - time.monotonic()
                if dt > 0:
                    time.sleep(dt)
                if time.monotonic() > DEADLINE:
                    break
                os.write(self.master, l.encode("ascii"))
                # drain what the bridge may send (nothing expected)
                r, _, _ = select.select([self.master], [], [], 0)
                if r:
                    try:
                        os.read(self.master, 4096)
                    except OSError:
                        pass
        finally:
            self.done.set()


def start_watch(cols, rows, seconds, log):
    """spindown watch on a terminal of cols x rows; returns (pid, fd)."""
    pid, fd = pty.fork()
    if pid == 0:
        os.environ["TERM"] = "xterm"
        os.environ["COLUMNS"] = str(cols)
        os.environ["LINES"] = str(rows)
        os.environ["LC_ALL"] = "C.UTF-8"
        os.execv(SPINDOWN, [SPINDOWN, "watch", "--lcm-url", URL, "--duration", str(seconds)])
    WATCH_PIDS.append(pid)
    fcntl.ioctl(fd, termios.TIOCSWINSZ, struct.pack("HHHH", rows, cols, 0, 0))
    os.kill(pid, signal.SIGWINCH)
    return pid, fd


def collect_watch(pid, fd, until, outpath):
    wpid = pid
    buf = bytearray()
    while time.monotonic() < until:
        r, _, _ = select.select([fd], [], [], 0.2)
        if r:
            try:
                b = os.read(fd, 65536)
            except OSError:
                break
            if not b:
                break
            buf += b
        try:
            wp, _ = os.waitpid(pid, os.WNOHANG)
            if wp == pid:
                pid = None
                # read what is left
                while True:
                    r, _, _ = select.select([fd], [], [], 0.1)
                    if not r:
                        break
                    try:
                        b = os.read(fd, 65536)
                    except OSError:
                        break
                    if not b:
                        break
                    buf += b
                break
        except ChildProcessError:
            break
    if pid:
        try:
            os.kill(pid, signal.SIGTERM)
            time.sleep(0.3)
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        try:
            os.waitpid(pid, 0)
        except ChildProcessError:
            pass
    if wpid in WATCH_PIDS:
        WATCH_PIDS.remove(wpid)
    os.close(fd)
    with open(outpath, "wb") as f:
        f.write(bytes(buf))
    return bytes(buf)


BENCHQ = """bench_id = "benchq"
[bench]
inertia_kg_m2 = 1.12687602e-5
speed_constant_rpm_per_v = 1180
quantity = "V"
[adc]
bits = 10
ref_v = 5.0
[lab]
period_s = 0.020
"""

BENCHM = """bench_id = "benchm"
[bench]
inertia_kg_m2 = 1.12687602e-5
speed_constant_rpm_per_v = 1180
quantity = "V"
[adc]
bits = 10
ref_v = 5.0
[lab]
period_s = 0.020
[baseline]
c_viscous_n_m_s = 1.8e-07
c_viscous_stderr = 2.0e-09
c_viscous_spread = 4.0e-09
c_coulomb_n_m = 1.14e-04
c_coulomb_stderr = 4.0e-07
c_coulomb_spread = 2.0e-06
runs = 3
date = "2024-09-07"
inertia_kg_m2 = 1.12687602e-5
"""

FLY_J = 2700.0 * math.pi * 0.03 ** 2 * 0.01 * 0.03 ** 2 / 2 + 1.09e-6
BENCHF = """bench_id = "benchf"
[bench]
flywheel_radius_m = 0.03
flywheel_height_m = 0.01
flywheel_density_kg_m3 = 2700
rotor_inertia_kg_m2 = 1.09e-6
speed_constant_rpm_per_v = 1180
quantity = "V"
[adc]
bits = 10
ref_v = 5.0
[lab]
period_s = 0.020
[baseline]
c_viscous_n_m_s = 2.6e-07
c_viscous_stderr = 3.0e-09
c_viscous_spread = 5.0e-09
c_coulomb_n_m = 1.25e-04
c_coulomb_stderr = 5.0e-07
c_coulomb_spread = 2.0e-06
runs = 3
date = "2024-09-07"
inertia_kg_m2 = %.9g
[health]
# this flywheel is three times the handout's: its healthy coast takes 80 s
max_slowdown_s = 90.0
max_stop_s = 150.0
""" % FLY_J


def main():
    os.makedirs(SCR, exist_ok=True)
    sh("ip", "link", "set", "lo", "up")
    sh("ip", "route", "add", "224.0.0.0/4", "dev", "lo")
    benches = os.path.join(SCR, "benches")
    logs = os.path.join(SCR, "logs")
    os.makedirs(benches, exist_ok=True)
    os.makedirs(logs, exist_ok=True)
    for name, text in (("benchq", BENCHQ), ("benchm", BENCHM), ("benchf", BENCHF)):
        with open(os.path.join(benches, name + ".toml"), "w") as f:
            f.write(text)
    # the recordings: a quiet pure-viscous motor (c4 = 0), a millivolt sketch on a healthy bench,
    # the flywheel bench's healthy run
    qdata, qtruth = ph.viscous_recording(101, "ard10-round")
    mdata, mtruth = ph.sketch_recording(102, scale=1000.0)
    fdata, ftruth = ph.sketch_recording(103, J=FLY_J, c3=2.6e-7, c4=1.25e-4)
    for n, d in (("q", qdata), ("m", mdata), ("f", fdata)):
        with open(os.path.join(SCR, "bench%s-sent.txt" % n), "wb") as f:
            f.write(d)
    env_url = ["--lcm-url", URL]
    start([os.path.join(BIN, "spindown-logger"), "--dir", logs, "--prefix", "lab"] + env_url, os.path.join(SCR, "logger.log"))
    start([os.path.join(BIN, "spindown-fitter"), "--bench-config", benches, "-v"] + env_url, os.path.join(SCR, "fitter.log"))
    bs = [Bench("benchq", qdata), Bench("benchm", mdata), Bench("benchf", fdata)]
    for b in bs:
        start([os.path.join(BIN, "spindown-bridge"), "--device", b.path, "--bench", b.id, "--config",
               os.path.join(benches, b.id + ".toml")] + env_url, os.path.join(SCR, "bridge-%s.log" % b.id))
    time.sleep(1.5)
    def span(b):
        ms = [int(l.split("\t")[0]) for l in b.lines if re.match(r"\d+\t", l)]
        return (ms[-1] - ms[0]) / 1000.0 / SPEED
    longest = max(span(b) for b in bs)
    w80 = start_watch(80, 32, longest + 6, None)
    w120 = start_watch(120, 40, longest + 6, None)
    for b in bs:
        b.thread.start()
    res = {}

    def col(name, w, cols):
        res[name] = collect_watch(w[0], w[1], min(DEADLINE, time.monotonic() + longest + 12),
                                  os.path.join(SCR, "watch-%s.raw" % name))
    th = [threading.Thread(target=col, args=("80x32", w80, 80)), threading.Thread(target=col, args=("120x40", w120, 120))]
    for t in th:
        t.start()
    for b in bs:
        b.done.wait(max(0.1, DEADLINE - time.monotonic()))
    time.sleep(4.0)           # the last FITs, the logger's flush
    for t in th:
        t.join(max(0.1, DEADLINE - time.monotonic()))
    stop_all()
    logfiles = sorted(os.path.join(logs, f) for f in os.listdir(logs) if f.endswith(".lcm"))
    judge(logfiles, benches, res, qtruth, mtruth, ftruth)


def recorded_fits(logfiles):
    """The FIT messages as the live fitter published them: `spindown refit --live --json`."""
    p = subprocess.run([SPINDOWN, "refit", "--live", "--json"] + logfiles, stdout=subprocess.PIPE,
                       stderr=subprocess.PIPE, timeout=60)
    try:
        js = json.loads(p.stdout.decode("utf-8", "replace"))
    except Exception:
        return None, p
    runs = []
    for f in js.get("files", []):
        for r in f.get("runs", []):
            runs.append(r)
    return runs, p


def bench_of(r):
    b = r.get("bench")
    if isinstance(b, dict):
        return b.get("id")
    return b


def health_of(r):
    h = r.get("health")
    if isinstance(h, dict):
        h = h.get("level") or h.get("verdict") or h.get("status") or h.get("state")
    return "" if h is None else str(h)


def judge(logfiles, benches, res, qtruth, mtruth, ftruth):
    if not logfiles:
        for cid in ("P2-live-quiet-viscous", "P3-live-not-judged", "P6-refit-compare-health", "P7-watch-80x32", "P7-watch-120x40"):
            say(False, cid, "the live lab recorded no log (see %s)" % SCR)
        return
    runs, p = recorded_fits(logfiles)
    if runs is None:
        runs = []
        err = p.stderr.decode("utf-8", "replace")[-200:]
    else:
        err = ""
    # --- point 2 live: the quiet viscous bench
    q = [r for r in runs if bench_of(r) == "benchq"]
    if q:
        r = max(q, key=lambda x: x.get("samples") or 0)
        best, reason = r.get("best"), str(r.get("best_reason", ""))
        ok = best == "viscous" or (re.search(r"cannot tell|undecided|indistinguishable", reason, re.I) and "very strong" not in reason.lower())
        say(ok, "P2-live-quiet-viscous", "pure viscous (c1 %.3g, c4 0) on a quiet 10-bit Arduino through bridge+fitter; truth: viscous or cannot-tell without 'very strong'; live FIT: %s (%s)" % (
            qtruth["c1"], best, reason[:100]))
    else:
        say(False, "P2-live-quiet-viscous", "no live FIT for benchq (%d FITs in the log) %s" % (len(runs), err))
    # --- point 3 live: the millivolt sketch on a bench with a baseline
    m = [r for r in runs if bench_of(r) == "benchm"]
    if m:
        hs = [(health_of(r), bool(r.get("doubts"))) for r in m]
        ok = all(re.sub(r"[\s_\-]+", " ", h.lower()).strip() == "not judged" for h, _ in hs) and all(d for _, d in hs)
        # what the class sees in spindown watch's event lines for that fit
        ev = []
        for raw in res.values():
            plain = re.sub(r"\x1b\[[0-9;?]*[A-Za-z]", "", raw.decode("utf-8", "replace"))
            ev += re.findall(r"benchm: run \d+ fit:.{0,400}?health\s+(\w+)", plain, re.S)
        judged = sorted(set(v.lower() for v in ev if v.lower() in ("ok", "check", "service")))
        ok = ok and not judged
        say(ok, "P3-live-not-judged", "millivolts printed as volts on a bench with a baseline, live; truth: doubted and health 'not judged' in the FIT and in watch; live FIT (health, doubted): %s; watch shows health %s" % (
            hs, judged or "no verdict"))
    else:
        say(False, "P3-live-not-judged", "no live FIT for benchm (%d FITs in the log) %s" % (len(runs), err))
    # --- point 6: refit --compare of a log whose fitter gave health verdicts
    pc = subprocess.run([SPINDOWN, "refit", "--compare"] + logfiles, stdout=subprocess.PIPE, stderr=subprocess.PIPE, timeout=60)
    txt = (pc.stdout + pc.stderr).decode("utf-8", "replace")
    diff = re.search(r"(\d+)\s+different", txt)
    ndiff = int(diff.group(1)) if diff else None
    f = [r for r in runs if bench_of(r) == "benchf"]
    fh = [health_of(r) for r in f]
    ok = pc.returncode == 0 and (ndiff in (None, 0)) and bool(f)
    line = [l for l in txt.splitlines() if re.search(r"identical|different", l)]
    say(ok, "P6-refit-compare-health", "a log whose fitter had --bench-config (flywheel bench, baseline: health %s); truth: refit --compare finds no difference; measured exit %d, %s" % (
        fh or "no FIT", pc.returncode, (line[-1].strip()[:160] if line else txt.strip()[-160:])))
    # --- point 7: watch at small terminals
    for name, cols, rows in (("80x32", 80, 32), ("120x40", 120, 40)):
        raw = res.get(name, b"")
        scr = vt.Screen(cols, rows)
        scr.feed(raw.decode("utf-8", "replace"))
        lines = scr.lines()
        visible = "\n".join(lines)
        probs = []
        if not raw:
            probs.append("no output")
        if scr.wraps:
            probs.append("%d lines wrapped past %d columns (e.g. %r)" % (len(scr.wraps), cols, scr.wraps[0][:90]))
        hdr = [l for l in lines if re.search(r"\bbench\b", l, re.I) and re.search(r"c3|state|run", l, re.I)]
        if not hdr:
            probs.append("no header row visible")
        for b in ("benchq", "benchm", "benchf"):
            if not any(re.search(r"^\s*\S*\s*%s\b" % b, l) for l in lines):
                probs.append("row of %s not visible" % b)
        if not lines or not re.search(r"spindown|watch", lines[0], re.I):
            probs.append("no title on the first line (it reads %r)" % (lines[0][:60] if lines else ""))
        if cols >= 120 and hdr and not re.search(r"health", hdr[0], re.I):
            probs.append("no health column at %d columns" % cols)
        say(not probs, "P7-watch-" + name, "spindown watch on a %dx%d terminal, 3 live benches; truth: no line wider than %d, title, header and 3 bench rows on screen; %s" % (
            cols, rows, cols, "; ".join(probs) if probs else "measured: as truth"))


def on_term(signum, frame):
    raise SystemExit(1)


if __name__ == "__main__":
    signal.signal(signal.SIGTERM, on_term)
    try:
        main()
    finally:
        stop_all()
