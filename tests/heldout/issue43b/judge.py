#!/usr/bin/env python3
"""Judge for tests/heldout/issue43b: runs spindown as a user would, against gen.py's truth.

usage: python3 judge.py BIN_DIR SCRATCH_DIR [--no-live REASON]

Prints `PASS name` / `FAIL name: why` per case and `SUMMARY: N/M passed`; exit 1 if any failed.
Must run inside the private network namespace run.sh creates (the live cases use LCM).
"""
import csv
import glob
import io
import json
import os
import re
import signal
import subprocess
import sys
import threading
import time
import tty
import unicodedata

CMD_TIMEOUT = 60
LCM_URL = "udpm://239.255.76.67:7667?ttl=0"
VERBOSE = os.environ.get("ISSUE43B_VERBOSE", "") not in ("", "0")
LOGLINES = []


def log(msg):
    LOGLINES.append(msg)
    if VERBOSE:
        print("  . " + msg, file=sys.stderr)


def run(cmd, timeout=CMD_TIMEOUT):
    try:
        p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, timeout=timeout)
        return p.returncode, p.stdout.decode("utf-8", "replace"), p.stderr.decode("utf-8", "replace")
    except subprocess.TimeoutExpired:
        return -9, "", "timeout after %ds" % timeout


# ---------------------------------------------------------------------------- proposals

VALUE_OPTS = {"time-column", "value-column", "time-unit", "value-unit", "delimiter",
              "period-ms", "kb", "speed-constant", "inertia"}
NUMERIC_OPTS = {"period-ms", "kb", "speed-constant", "inertia"}
KNOWN_UNITS = {"v", "mv", "rpm", "rev/s", "rad/s", "deg/s", "counts", "count", "ms", "s", "us",
               "µs"}
OPT_RE = re.compile(r"--([a-z][a-z0-9-]*)(?:[ =]('[^'\n]*'|\"[^\"\n]*\"|`[^`\n]*`|(?!--)[^\s,;)]+))?")


def _clean_val(v):
    if v is None:
        return None
    if len(v) >= 2 and v[0] in "'\"`" and v[-1] == v[0]:
        return v[1:-1]
    return v.rstrip(".:'`\"")


def extract_proposals(text):
    """[{opts: [(name, value)], cond: str|None, line: str, idx: int}] per group of options."""
    props = []
    for li, line in enumerate(text.splitlines()):
        ms = list(OPT_RE.finditer(line))
        groups = []
        for m in ms:
            between = line[groups[-1][-1].end():m.start()] if groups else None
            # "--period-ms 20 for the lab sketch's delay(20) …, with --value-column 2" is one
            # command: options joined by "with" (no ';' between) belong to the same proposal
            if groups and (between.strip() == "" or
                           (re.search(r"\bwith\s*$", between) and ";" not in between)):
                groups[-1].append(m)
            else:
                groups.append([m])
        for g in groups:
            opts = []
            for m in g:
                name, val = m.group(1), _clean_val(m.group(2))
                if name in VALUE_OPTS:
                    opts.append((name, val))
            if not opts:
                continue
            start = g[0].start()
            # the clause before: back to the last ( ) ; or sentence end
            before = line[:start]
            cut = max(before.rfind("("), before.rfind(")"), before.rfind(";"), before.rfind(". "))
            clause_before = before[cut + 1:]
            cond = None
            for k, m in enumerate(g):
                after = line[m.end():(g[k + 1].start() if k + 1 < len(g) else len(line))]
                ma = re.match(r"\s*[(,]?\s*((?:if|when|in case|for)\b[^;)]*)", after)
                if ma:
                    cond = ma.group(1).strip()
                    break
            if cond is None and re.search(r"\bif\b", clause_before):
                cond = clause_before.strip()
            props.append(dict(opts=opts, cond=cond, line=line.strip(), idx=li))
    return props


def _word_in(word, text):
    return re.search(r"(?<![\w/])" + re.escape(word.lower()) + r"(?![\w/])", text.lower()) is not None


def applicable(props, truth):
    """Resolve conditionals and placeholders. Returns (list of option lists to follow, notes)."""
    notes = []
    aliases = truth.get("unit_aliases", [])
    knows = truth.get("user_knows", {})
    uncond = [p for p in props if p["cond"] is None]
    cond_ok = []
    for p in props:
        if p["cond"] is None:
            continue
        knows_all = all(n in knows and v is not None and same_val(knows[n], v) for n, v in p["opts"])
        if any(_word_in(a, p["cond"]) for a in aliases) or knows_all:
            cond_ok.append(p)
        else:
            notes.append("skipped conditional %s (%s)" % (fmt_opts(p["opts"]), p["cond"]))
    follow = []
    used_cond = set()
    for p in uncond:
        opts = list(p["opts"])
        for c in cond_ok:
            if c["idx"] == p["idx"] and all(n in dict(opts) for n, _ in c["opts"]):
                d = dict(opts)
                d.update(dict(c["opts"]))
                opts = [(n, d[n]) for n, _ in opts]
                used_cond.add(id(c))
                notes.append("conditional %s applies (%s): used in %s" %
                             (fmt_opts(c["opts"]), c["cond"], fmt_opts(opts)))
        follow.append(opts)
    for c in cond_ok:
        if id(c) not in used_cond:
            follow.append(list(c["opts"]))
    out = []
    for opts in follow:
        fixed = []
        literal = True
        for n, v in opts:
            ph = (v is None or v == "" or (n in NUMERIC_OPTS and not re.match(r"^[0-9.eE+-]+$", v))
                  or (n in ("time-unit", "value-unit") and v.lower() not in KNOWN_UNITS
                      and re.match(r"^[A-Z_<\[]", v or "")))
            if ph:
                if n in knows:
                    notes.append("placeholder --%s %s filled with %s (what the user knows)" % (n, v, knows[n]))
                    v = knows[n]
                else:
                    literal = False
            fixed.append((n, v))
        if not literal:
            notes.append("not literal, nothing the user knows fills it: %s" % fmt_opts(opts))
            continue
        if fixed not in out:
            out.append(fixed)
    return out, notes


def fmt_opts(opts):
    return " ".join("--%s %s" % (n, v) if v is not None else "--%s" % n for n, v in opts)


def opts_argv(opts):
    a = []
    for n, v in opts:
        a.append("--" + n)
        if v is not None:
            a.append(v)
    return a


def merge(base, new):
    d = dict(base)
    order = [n for n, _ in base]
    for n, v in new:
        if n not in d:
            order.append(n)
        d[n] = v
    # --period-ms excludes --time-column/--time-unit
    if "period-ms" in dict(new):
        for n in ("time-column", "time-unit"):
            if n in d and n not in dict(new):
                del d[n]
                order.remove(n)
    return [(n, d[n]) for n in order]


def same_val(a, b):
    norm = lambda x: (x or "").strip().lower().replace("µ", "u")
    try:
        return abs(float(a) - float(b)) < 1e-9
    except (TypeError, ValueError):
        return norm(a) == norm(b)


# ---------------------------------------------------------------------------- matching

def nfc(s):
    return unicodedata.normalize("NFC", s or "").casefold()


def table_rows(binp, path, opts):
    rc, out, err = run([binp, "fit", path, "--table", "json"] + opts_argv(opts))
    rows = []
    try:
        j = json.loads(out) if out.strip() else []
        rows = j if isinstance(j, list) else j.get("rows", [])
    except ValueError:
        pass
    return rc, rows, err


def num(x):
    try:
        if x is None or x == "":
            return None
        return float(x)
    except (TypeError, ValueError):
        return None


def match_runs(found, truth, label, check_names=False):
    """found: [{t_cut, t_stop, c3, c4, student?}]. Returns (ok, why)."""
    truns = truth["runs"]
    problems = []
    used = set()
    for i, tr in enumerate(truns):
        best = None
        for j, f in enumerate(found):
            if j in used or f["t_cut"] is None:
                continue
            d = abs(f["t_cut"] - tr["t_cut"])
            if best is None or d < best[0]:
                best = (d, j)
        if best is None or best[0] > tr["tol_cut"]:
            near = ("nearest cut at %.3f s" % found[best[1]]["t_cut"]) if best else "no run"
            problems.append("run %d (cut %.3f s ± %.3f) not found (%s)" % (i + 1, tr["t_cut"], tr["tol_cut"], near))
            continue
        f = found[best[1]]
        used.add(best[1])
        if f["t_stop"] is None or abs(f["t_stop"] - tr["t_stop"]) > tr["tol_stop"]:
            problems.append("run %d stop %s s, truth %.3f ± %.3f" % (
                i + 1, "none" if f["t_stop"] is None else "%.3f" % f["t_stop"], tr["t_stop"], tr["tol_stop"]))
        for k, rt in (("c3", truth["c3_rtol"]), ("c4", truth["c4_rtol"])):
            v = f.get(k)
            if v is None or abs(v / tr[k] - 1.0) > rt:
                problems.append("run %d %s %s, truth %.4g (±%d %%)" % (
                    i + 1, k, "none" if v is None else "%.4g (x%.3g)" % (v, v / tr[k]), tr[k], round(rt * 100)))
        if check_names:
            who = f.get("student") or ""
            name = tr["student"]
            if not re.search(r"(?<!\w)" + re.escape(nfc(name)) + r"(?!\w)", nfc(who)):
                problems.append("run %d (cut %.3f s) student %r, truth %r" % (i + 1, tr["t_cut"], who, name))
            else:
                others = [o for o in truth["students"] if nfc(o) != nfc(name)
                          and re.search(r"(?<!\w)" + re.escape(nfc(o)) + r"(?!\w)", nfc(who))]
                if others:
                    problems.append("run %d student %r also names %s" % (i + 1, who, others))
    extra = [f for j, f in enumerate(found) if j not in used]
    if extra:
        problems.append("%d run(s) not in the truth (cuts at %s s)" % (
            len(extra), ", ".join("%.3f" % e["t_cut"] if e["t_cut"] is not None else "?" for e in extra)))
    if problems:
        return False, "%s: %s" % (label, "; ".join(problems))
    return True, ""


def rows_to_found(rows):
    out = []
    for r in rows:
        out.append(dict(t_cut=num(r.get("t_cut_s")), t_stop=num(r.get("t_stop_s")),
                        c3=num(r.get("c3")), c4=num(r.get("c4")), student=r.get("student"),
                        trust=r.get("trust"), doubts=r.get("doubts")))
    return out


def first_error(err, out=""):
    for line in (err + "\n" + out).splitlines():
        if "error" in line or "not used" in line:
            return line.strip()[:300]
    lines = [l for l in err.splitlines() if l.strip()]
    return (lines[0].strip()[:300]) if lines else "(nothing on stderr)"


# ---------------------------------------------------------------------------- offline cases

def attempt(binp, path, truth, opts, check_names, depth, trail):
    """Run fit with opts; judge it and every further consistent proposal. (ok, why)"""
    rc, rows, err = table_rows(binp, path, opts)
    trc, tout, terr = run([binp, "fit", path] + opts_argv(opts))
    label = "`spindown fit %s %s`" % (os.path.basename(path), fmt_opts(opts))
    log("%s -> exit %d, %d rows" % (label, rc, len(rows)))
    if not rows:
        return False, "%s refused (exit %d: %s)" % (label, rc, first_error(terr, tout))
    ok, why = match_runs(rows_to_found(rows), truth, label, check_names)
    if not ok:
        return False, why
    props = extract_proposals(terr + "\n" + tout)
    follow, notes = applicable(props, truth)
    for n in notes:
        log(n)
    given = dict(opts)
    for p in follow:
        for n, v in p:
            if n in given and not same_val(given[n], v):
                return False, "%s then proposes %s, contradicting --%s %s" % (label, fmt_opts(p), n, given[n])
        merged = merge(opts, p)
        if merged == opts or fmt_opts(merged) in trail:
            continue
        if depth >= 3:
            continue
        ok, why = attempt(binp, path, truth, merged, check_names, depth + 1, trail | {fmt_opts(merged)})
        if not ok:
            return False, "following its further proposal: " + why
    return True, ""


def judge_offline(binp, d, truth):
    path = os.path.join(d, truth["input"])
    names = truth["kind"] == "names"
    base = [tuple(x) for x in truth.get("base_opts", [])]
    rc, rows, err = table_rows(binp, path, base)
    trc, tout, terr = run([binp, "fit", path] + opts_argv(base))
    props = extract_proposals(terr + "\n" + tout)
    follow, notes = applicable(props, truth)
    for n in notes:
        log("%s: %s" % (truth["name"], n))
    log("%s: plain fit exit %d, %d rows, proposals %s" % (
        truth["name"], rc, len(rows), [fmt_opts(p) for p in follow]))
    label = "`spindown fit %s`" % os.path.basename(path)
    plain_ok, plain_why = (False, "%s refused (exit %d: %s)" % (label, rc, first_error(terr, tout)))
    if rows:
        plain_ok, plain_why = match_runs(rows_to_found(rows), truth, label, names)
    if not follow:
        if plain_ok:
            return True, "read without a proposal"
        if rows:
            return False, plain_why + " (no proposal)"
        return False, plain_why + "; it proposes nothing that applies" + (
            " (%s)" % "; ".join(notes) if notes else "")
    if rows and not plain_ok:
        doubted = all((r.get("trust") or "") == "doubtful" for r in rows)
        if not doubted:
            return False, plain_why + " (not doubted)"
    for p in follow:
        opts = merge(base, p)
        ok, why = attempt(binp, path, truth, opts, names, 1, {fmt_opts(opts)})
        if not ok:
            return False, "following its proposal `%s`: %s" % (fmt_opts(p), why)
    return True, "%d proposal(s) followed: %s" % (len(follow), " | ".join(fmt_opts(p) for p in follow))


# ---------------------------------------------------------------------------- live cases

class Live:
    def __init__(self, binp, root, cases):
        self.binp = binp
        self.root = root
        self.cases = cases
        self.logdir = os.path.join(root, "live-logs")
        os.makedirs(self.logdir, exist_ok=True)
        for f in glob.glob(os.path.join(self.logdir, "*.lcm")):
            os.unlink(f)
        self.errors = {}
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.procs = []
        self.speed = float(os.environ.get("ISSUE43B_SPEED", "1") or 1)

    def start(self):
        self.thread.start()

    def join(self, timeout):
        self.thread.join(timeout)
        if self.thread.is_alive():
            for p in self.procs:
                if p.poll() is None:
                    p.kill()
            return False
        return True

    def _spawn(self, args, name):
        f = open(os.path.join(self.logdir, name + ".stderr"), "wb")
        env = dict(os.environ, LCM_DEFAULT_URL=LCM_URL)
        p = subprocess.Popen(args, stdout=f, stderr=subprocess.STDOUT, env=env)
        self.procs.append(p)
        return p

    def _run(self):
        try:
            self._run2()
        except Exception as e:   # report, never hang
            for c in self.cases:
                self.errors.setdefault(c[1]["name"], "live harness: %r" % e)

    def _run2(self):
        b = self.binp
        logger = self._spawn([b + "/spindown-logger", "--lcm-url", LCM_URL, "--dir", self.logdir,
                              "--prefix", "issue43b", "--flush-interval", "0.2"], "logger")
        fitter = self._spawn([b + "/spindown-fitter", "--lcm-url", LCM_URL, "-v"], "fitter")
        time.sleep(1.0)
        writers = []
        bridges = []
        for d, truth in self.cases:
            master, slave = os.openpty()
            tty.setraw(slave)
            path = os.ttyname(slave)
            br = self._spawn([b + "/spindown-bridge", "--device", path, "--bench", truth["bench"],
                              "--baud", "9600", "--lcm-url", LCM_URL], "bridge-" + truth["bench"])
            bridges.append((br, master, slave))
            # wait until the bridge has the device open
            t_end = time.time() + 10
            opened = False
            while time.time() < t_end and not opened:
                try:
                    for fd in os.listdir("/proc/%d/fd" % br.pid):
                        try:
                            if os.readlink("/proc/%d/fd/%s" % (br.pid, fd)) == path:
                                opened = True
                        except OSError:
                            pass
                except OSError:
                    break
                time.sleep(0.05)
            if not opened:
                self.errors[truth["name"]] = "spindown-bridge did not open %s within 10 s" % path
            time.sleep(0.5)
            data = open(os.path.join(d, truth["input"]), "rb").read()
            times = json.load(open(os.path.join(d, "serial_times.json")))
            w = threading.Thread(target=self._write, args=(master, data, times), daemon=True)
            r = threading.Thread(target=self._drain, args=(master,), daemon=True)
            writers.append(w)
            r.start()
        for w in writers:
            w.start()
        for w in writers:
            w.join()
        time.sleep(4.0)
        for br, master, slave in bridges:
            br.send_signal(signal.SIGTERM)
        for br, master, slave in bridges:
            try:
                br.wait(10)
            except subprocess.TimeoutExpired:
                br.kill()
        time.sleep(2.0)
        fitter.send_signal(signal.SIGTERM)
        try:
            fitter.wait(10)
        except subprocess.TimeoutExpired:
            fitter.kill()
        time.sleep(0.5)
        logger.send_signal(signal.SIGTERM)
        try:
            logger.wait(15)
        except subprocess.TimeoutExpired:
            logger.kill()
        for br, master, slave in bridges:
            for fd in (master, slave):
                try:
                    os.close(fd)
                except OSError:
                    pass

    def _write(self, master, data, times):
        t0 = time.monotonic()
        pos = 0
        for rel, n in times:
            target = t0 + rel / self.speed
            now = time.monotonic()
            if target > now:
                time.sleep(target - now)
            chunk = data[pos:pos + n]
            pos += n
            while chunk:
                k = os.write(master, chunk)
                chunk = chunk[k:]

    def _drain(self, master):
        while True:
            try:
                if not os.read(master, 4096):
                    return
            except OSError:
                return


def walk_runs(obj, bench=None):
    """Every dict with t_cut_s in a refit/fit JSON, with its bench id where said."""
    out = []
    if isinstance(obj, dict):
        b = obj.get("bench")
        bid = None
        if isinstance(b, dict):
            bid = b.get("id")
        elif isinstance(b, str):
            bid = b
        bid = bid or obj.get("bench_id") or bench
        if "t_cut_s" in obj:
            c3 = c4 = None
            for m in obj.get("models", []) or []:
                if isinstance(m, dict) and m.get("name") == "combined":
                    p = m.get("params", {})
                    c3 = num((p.get("c3") or {}).get("value"))
                    c4 = num((p.get("c4") or {}).get("value"))
            if c3 is None and "c3" in obj:
                c3 = num(obj["c3"]["value"] if isinstance(obj["c3"], dict) else obj["c3"])
                c4 = num(obj["c4"]["value"] if isinstance(obj.get("c4"), dict) else obj.get("c4"))
            out.append(dict(t_cut=num(obj.get("t_cut_s")), t_stop=num(obj.get("t_stop_s")),
                            c3=c3, c4=c4, bench=bid))
        for k, v in obj.items():
            if k != "models":
                out.extend(walk_runs(v, bid))
    elif isinstance(obj, list):
        for v in obj:
            out.extend(walk_runs(v, bench))
    return out


def export_samples(binp, args):
    rc, out, err = run([binp, "export"] + args + ["--no-fits"])
    if rc != 0:
        return None, "export %s: exit %d: %s" % (" ".join(args), rc, first_error(err, out))
    rows = list(csv.DictReader(io.StringIO(out)))
    s = []
    for r in rows:
        t, v = num(r.get("device_time_s")), num(r.get("value"))
        if t is not None and v is not None:
            s.append((t, v))
    return s, ""


def judge_live(binp, d, truth, logs, harness_error):
    if harness_error:
        return False, harness_error
    if not logs:
        return False, "no LCM log was written by spindown-logger"
    bench = truth["bench"]
    path = os.path.join(d, truth["input"])
    problems = []
    # 1. live FITs
    rc, out, err = run([binp + "/spindown", "refit", "--live", "--json", "--bench", "^%s$" % bench] + logs)
    try:
        live = [r for r in walk_runs(json.loads(out)) if r["bench"] in (None, bench)]
    except ValueError:
        live = []
    ok, why = match_runs(live, truth, "live FITs (refit --live)")
    if not ok:
        problems.append(why)
    # 2. refit of the log
    rc, out, err = run([binp + "/spindown", "refit", "--json", "--bench", "^%s$" % bench] + logs)
    try:
        ref = [r for r in walk_runs(json.loads(out)) if r["bench"] in (None, bench)]
    except ValueError:
        ref = []
    ok, why = match_runs(ref, truth, "refit of the log")
    if not ok:
        problems.append(why + ("" if ref else " (exit %d: %s)" % (rc, first_error(err, out))))
    # 3. fit of the same bytes
    rc, rows, err = table_rows(binp + "/spindown", path, [])
    ok, why = match_runs(rows_to_found(rows), truth, "`spindown fit` of the same bytes")
    if not ok:
        problems.append(why + ("" if rows else " (exit %d: %s)" % (rc, first_error(err))))
    # 4. the samples, bridge vs fit
    sb, e1 = export_samples(binp + "/spindown", logs + ["--bench", "^%s$" % bench])
    sf, e2 = export_samples(binp + "/spindown", [path])
    if sb is None or sf is None:
        problems.append("samples: " + (e1 or e2))
    else:
        lines = open(path, "rb").read().count(b"\n")

        def drop_partial(smp):
            # the first line was joined mid-line ("96\t0.00"): a sample read from it lies far
            # (over 1 s) from the next one; leave it out on both sides
            if len(smp) > 1 and abs(smp[1][0] - smp[0][0]) > 1.0:
                return smp[1:]
            return smp
        sf2, sb2 = drop_partial(sf), drop_partial(sb)
        if abs(len(sf2) - (lines - 1)) > 1:
            problems.append("fit's export has %d samples (first line aside) of %d lines" % (len(sf2), lines - 1))
        if len(sf2) != len(sb2):
            problems.append("samples: the bridge published %d, fit reads %d (first line aside)" % (len(sb2), len(sf2)))
        bad = [(k, x, y) for k, (x, y) in enumerate(zip(sf2, sb2))
               if abs(x[0] - y[0]) > 1.5e-6 or abs(x[1] - y[1]) > 1e-6]
        if bad:
            k, x, y = bad[0]
            problems.append("samples: %d of %d differ, the first (sample %d): fit (%.6f s, %g) vs bridge (%.6f s, %g)" % (
                len(bad), min(len(sf2), len(sb2)), k + 1, x[0], x[1], y[0], y[1]))
        if sb and max(t for t, _ in sb) < truth["wrap_at_s"]:
            problems.append("bridge's device times never pass the wrap at %.3f s (max %.3f): not unwrapped" % (
                truth["wrap_at_s"], max(t for t, _ in sb)))
    if problems:
        return False, "; ".join(problems)
    return True, "live, refit, fit and samples agree with the truth"


# ---------------------------------------------------------------------------- main

def main():
    if len(sys.argv) < 3:
        sys.exit("usage: judge.py BIN_DIR SCRATCH_DIR [--no-live REASON]")
    binp = os.path.abspath(sys.argv[1])
    root = os.path.abspath(sys.argv[2])
    no_live = None
    if len(sys.argv) >= 5 and sys.argv[3] == "--no-live":
        no_live = sys.argv[4]
    cases = []
    for d in sorted(glob.glob(os.path.join(root, "*", "truth.json"))):
        truth = json.load(open(d, encoding="utf-8"))
        cases.append((os.path.dirname(d), truth))
    order = {"names": 0, "live": 1, "proposal": 2}
    cases.sort(key=lambda c: (order[c[1]["kind"]], c[1]["name"]))
    live_cases = [c for c in cases if c[1]["kind"] == "live"]
    live = None
    if live_cases and not no_live:
        live = Live(binp, root, live_cases)
        live.start()
    results = {}
    for d, truth in cases:
        if truth["kind"] == "live":
            continue
        try:
            ok, why = judge_offline(binp + "/spindown", d, truth)
        except Exception as e:
            ok, why = False, "judge error: %r" % e
        results[truth["name"]] = (ok, why)
    finished = True
    if live:
        finished = live.join(200)
    logs = sorted(glob.glob(os.path.join(root, "live-logs", "*.lcm")))
    for d, truth in live_cases:
        if no_live:
            results[truth["name"]] = (False, no_live)
            continue
        err = live.errors.get(truth["name"])
        if not finished:
            err = "the live capture did not finish in time"
        try:
            results[truth["name"]] = judge_live(binp, d, truth, logs, err)
        except Exception as e:
            results[truth["name"]] = (False, "judge error: %r" % e)
    npass = 0
    for d, truth in cases:
        ok, why = results[truth["name"]]
        if ok:
            npass += 1
            print("PASS %s" % truth["name"])
        else:
            print("FAIL %s: %s" % (truth["name"], why))
        sys.stdout.flush()
    print("SUMMARY: %d/%d passed" % (npass, len(cases)))
    with open(os.path.join(root, "judge.log"), "w", encoding="utf-8") as f:
        f.write("\n".join(LOGLINES) + "\n")
    sys.exit(0 if npass == len(cases) else 1)


if __name__ == "__main__":
    main()
