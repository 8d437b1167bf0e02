#!/usr/bin/python3
"""The live lab for issue 33, run INSIDE a private network namespace (run.sh calls it under
`unshare -n`): loopback up, a multicast route on lo, LCM with ttl=0; spindown-logger,
spindown-fitter (discrepancy workflow on, --explain-base viscous) and spindown-bridge reading a
real pseudo-terminal, on which this script prints the recording's serial lines with the
recording's own timing (millis), sped up SPEED times (deploy/run-lab feeds its virtual benches
5x faster than real time, so the programs allow it).

Usage: live.py BIN_DIR LINES_JSON OUT_DIR SPEED
Writes OUT_DIR/live.json: {"log": path, "events": {...}, "errors": [...]} and the programs'
stderr in OUT_DIR/*.err. Every wait is bounded; every process it starts is stopped by its pid.
"""
import json
import os
import signal
import struct
import subprocess
import sys
import time
import tty

BIN, LINES, OUT, SPEED = sys.argv[1], sys.argv[2], sys.argv[3], float(sys.argv[4])
URL = "udpm://239.255.76.67:7667?ttl=0"
BENCH = "bench33"
procs = []
errors = []


def sh(*cmd):
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=10)
    if r.returncode != 0:
        errors.append("%s: rc %d %s" % (" ".join(cmd), r.returncode, r.stderr.strip()))


def start(name, args):
    err = open(os.path.join(OUT, name + ".err"), "w")
    p = subprocess.Popen(args, stdout=err, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                         env=dict(os.environ, LCM_DEFAULT_URL=URL))
    procs.append((name, p))
    return p


def stop_all():
    for name, p in reversed(procs):
        if p.poll() is None:
            p.send_signal(signal.SIGTERM)
            try:
                p.wait(timeout=5)
            except subprocess.TimeoutExpired:
                errors.append("%s did not stop on SIGTERM within 5 s; killed" % name)
                p.kill()
                p.wait(timeout=5)


def log_channels(path):
    """Channels of the events in an LCM event log (format: docs/using-the-data.md)."""
    out = {}
    try:
        data = open(path, "rb").read()
    except OSError:
        return out
    i = 0
    n = len(data)
    while i + 28 <= n:
        sync, _num, _ts, clen, dlen = struct.unpack(">IqqII", data[i:i + 28])
        if sync != 0xEDA1DA01:
            i += 1
            continue
        if i + 28 + clen + dlen > n:
            break
        ch = data[i + 28:i + 28 + clen].decode("latin-1")
        out[ch] = out.get(ch, 0) + 1
        i += 28 + clen + dlen
    return out


def find_log(logdir):
    logs = sorted(f for f in os.listdir(logdir) if f.endswith(".lcm"))
    return os.path.join(logdir, logs[-1]) if logs else None


def main():
    logdir = os.path.join(OUT, "logs")
    os.makedirs(logdir, exist_ok=True)
    sh("ip", "link", "set", "lo", "up")
    sh("ip", "route", "add", "224.0.0.0/4", "dev", "lo")
    lines = json.load(open(LINES))
    master, slave = os.openpty()
    tty.setraw(slave)  # a serial port has no echo and no line editing
    dev = os.ttyname(slave)
    start("logger", [os.path.join(BIN, "spindown-logger"), "--lcm-url", URL, "--dir", logdir,
                     "--prefix", "issue33", "--flush-interval", "0.2"])
    start("fitter", [os.path.join(BIN, "spindown-fitter"), "--lcm-url", URL, "--instance",
                     "heldout33", "--explain-base", "viscous", "-v"])
    time.sleep(1.0)
    start("bridge", [os.path.join(BIN, "spindown-bridge"), "--device", dev, "--bench", BENCH,
                     "--baud", "9600", "--lcm-url", URL])
    # bounded wait for the bridge to be up (its CONFIG or STATUS in the log), at most 8 s
    t0 = time.monotonic()
    while time.monotonic() - t0 < 8.0:
        lg = find_log(logdir)
        if lg and any(c.startswith("SPINDOWN.%s." % BENCH) for c in log_channels(lg)):
            break
        time.sleep(0.2)
    time.sleep(0.5)
    # feed: each line at its millis, relative to the first timed line, SPEED x faster
    start_wall = time.monotonic()
    ms0 = None
    for ln in lines:
        b = ln.encode("latin-1")
        head = b.split(b"\t", 1)[0]
        if head.isdigit():
            ms = int(head)
            if ms0 is None:
                ms0 = ms
            due = start_wall + (ms - ms0) / 1000.0 / SPEED
            delay = due - time.monotonic()
            if delay > 0:
                time.sleep(min(delay, 1.0))
        os.write(master, b)
        # drain anything the bridge writes to the port (a real Arduino ignores it)
        try:
            os.set_blocking(master, False)
            while os.read(master, 4096):
                pass
        except (BlockingIOError, OSError):
            pass
    feed_s = time.monotonic() - start_wall
    # bounded wait for FIT and EXPLAIN of the bench in the log: at most 40 s
    t0 = time.monotonic()
    chans = {}
    lg = None
    while time.monotonic() - t0 < 40.0:
        lg = find_log(logdir)
        chans = log_channels(lg) if lg else {}
        if chans.get("SPINDOWN.%s.FIT" % BENCH) and chans.get("SPINDOWN.%s.EXPLAIN" % BENCH):
            break
        time.sleep(0.5)
    time.sleep(1.0)  # one more heartbeat / flush
    stop_all()
    os.close(master)
    os.close(slave)
    lg = find_log(logdir)
    chans = log_channels(lg) if lg else {}
    json.dump({"log": lg, "channels": chans, "errors": errors, "feed_s": feed_s,
               "wait_s": time.monotonic() - t0}, open(os.path.join(OUT, "live.json"), "w"),
              indent=1)


if __name__ == "__main__":
    try:
        main()
    finally:
        stop_all()
