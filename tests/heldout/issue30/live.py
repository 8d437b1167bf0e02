"""Starts live_ns.py inside a private network namespace and hands its verdicts to the runner."""
import os
import re
import subprocess
import time

HERE = os.path.dirname(os.path.abspath(__file__))
LIVE_IDS = ("P2-live-quiet-viscous", "P3-live-not-judged", "P6-refit-compare-health", "P7-watch-80x32", "P7-watch-120x40")


def run_all(bin_dir, scratch, report, wanted, t_start, budget):
    ids = [i for i in LIVE_IDS if wanted(i)]
    if not ids:
        return
    left = budget - (time.monotonic() - t_start)
    if left < 60:
        for i in ids:
            report(i, False, "not run: the runner's time budget was used up")
        return
    d = os.path.join(scratch, "live")
    os.makedirs(d, exist_ok=True)
    deadline = min(90.0, left - 20)
    p = subprocess.Popen(["unshare", "-n", "/usr/bin/python3", os.path.join(HERE, "live_ns.py"), bin_dir, d, str(deadline)],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        o, e = p.communicate(timeout=deadline + 30)
        rc = p.returncode
    except subprocess.TimeoutExpired:
        p.terminate()              # live_ns.py ends the services it started on SIGTERM
        try:
            o, e = p.communicate(timeout=10)
        except subprocess.TimeoutExpired:
            p.kill()
            o, e = p.communicate()
        rc = "timeout"
    out, err = o.decode("utf-8", "replace"), e.decode("utf-8", "replace")
    seen = set()
    for line in out.splitlines():
        m = re.match(r"(PASS|FAIL) (\S+): (.*)", line)
        if m and m.group(2) in ids:
            seen.add(m.group(2))
            report(m.group(2), m.group(1) == "PASS", m.group(3))
    for i in ids:
        if i not in seen:
            report(i, False, "the live lab gave no verdict (exit %s): %s" % (rc, err.strip()[-300:]))
