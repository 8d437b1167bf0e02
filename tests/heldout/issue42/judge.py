#!/usr/bin/env python3
"""Judges the issue-42 held-out cases against truth.

Truth sources: the virtual benches' truth files (--truth: cut device times, stops, friction) and
sent-line files (--sent), and what the network provably delivered (witness log vs lab log, by
sequence number). The program's outputs are read through the documented interfaces only:
`spindown refit [--live|--compare] --json`, and the STATUS heartbeats in the logs (decoded with the
documented Python reader in build/python, docs/using-the-data.md).

Usage: judge.py CASE   (environment: BIN, SCR). Prints problems, one a line; exit 0 when there is
none, 1 when the program failed a truth, 3 for a harness problem (line starting "HARNESS:").
"""
import glob, json, os, re, subprocess, sys

sys.dont_write_bytecode = True   # never write into the build tree (build/python)
BIN = os.environ["BIN"]
SCR = os.environ["SCR"]
PYDIR = os.path.normpath(os.path.join(BIN, "..", "python"))
sys.path.insert(0, PYDIR)

CUT_TOL = 0.1        # s: a true cut
INVENT_TOL = 0.5     # s: a claimed cut farther than this from every truth cut is invented
STOP_TOL = 1.0       # s
C4_REL = 0.03        # friction: max(6 stderr, 3 %)
EQ_CUT = 0.001       # s: equal runs
EQ_REL = 1e-6


class Harness(Exception):
    pass


problems = []
def bad(msg):
    problems.append(msg)


def spindown_log():
    try:
        import spindown_log as sl
    except ImportError as e:
        raise Harness("the documented Python log reader is not at %s (%s)" % (PYDIR, e))
    return sl


def logs(d):
    fs = sorted(glob.glob(os.path.join(SCR, d, "*.lcm")))
    if not fs:
        raise Harness("no log in %s" % d)
    return fs


# ---------------------------------------------------------------- truth
def truth(tag, motor=None):
    """Truth runs of virtual bench TAG: cut (device s), stop (device s), c3, c4."""
    p = os.path.join(SCR, tag + ".truth.json")
    try:
        with open(p) as f:
            t = json.load(f)
    except (OSError, ValueError) as e:
        raise Harness("truth file %s: %s" % (p, e))
    runs = []
    for r in t["runs"]:
        cut = r["cut_device_us"] / 1e6
        runs.append({"tag": tag, "motor": motor or tag, "run": r["run"], "cut": cut,
                     "stop": cut + r["t_stop_s"] if r.get("stopped") else None,
                     "c3": t["c_v"], "c4": t["c_c"]})
    return runs


# ---------------------------------------------------------------- spindown refit
def run_json(args, ok_codes=(0, 1)):
    cmd = [os.path.join(BIN, "spindown"), "refit", "--json", "--no-progress"] + args
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=60)
    if p.returncode not in ok_codes:
        raise Harness("%s: exit %d: %s" % (" ".join(cmd), p.returncode, p.stderr[-400:]))
    try:
        d = json.loads(p.stdout)
    except ValueError:
        raise Harness("%s: not JSON: %s" % (" ".join(cmd), p.stdout[:200]))
    return d, p.returncode


def flat_runs(d):
    out = []
    for f in d.get("files", []):
        for r in f.get("runs", []):
            r = dict(r)
            r["_file"] = f.get("file")
            r["_bench"] = (r.get("bench") or {}).get("id")
            out.append(r)
    return out


def live_fits(files, extra=()):
    d, _ = run_json(["--live"] + list(extra) + files)
    return flat_runs(d)


def refit(files, extra=()):
    d, rc = run_json(list(extra) + files)
    return flat_runs(d), d


def compare(files, extra=()):
    cmd = [os.path.join(BIN, "spindown"), "refit", "--compare", "--no-progress"] + list(extra) + files
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=60)
    return p.returncode, p.stdout + p.stderr


def param(run, model, name):
    for m in run.get("models", []):
        if m.get("name") == model:
            v = (m.get("params") or {}).get(name)
            if v and v.get("value") is not None:
                return v["value"], v.get("stderr") or 0.0
    return None, None


def claimed(run):
    return run.get("lead_in") not in (None, "none") and not run.get("partial")


def desc(r):
    c4, _ = param(r, "combined", "c4")
    return "%s run %s (cut %.3f s, stop %s, end %s, lead-in %s, %s samples, c4 %s)" % (
        r["_bench"], r.get("run"), r.get("t_cut_s") or float("nan"), r.get("t_stop_s"), r.get("end"),
        r.get("lead_in"), r.get("samples"), "%.4g" % c4 if c4 else None)


def friction_ok(r, tr):
    c4, se = param(r, "combined", "c4")
    if c4 is None:
        return False, "no combined c4"
    tol = max(6 * se, C4_REL * tr["c4"])
    if abs(c4 - tr["c4"]) > tol:
        return False, "c4 %.4g vs truth %.4g (tolerance %.2g)" % (c4, tr["c4"], tol)
    return True, ""


def whole_problem(r, tr, cut_tol=CUT_TOL):
    """None when r is a whole run of truth run tr, else why not."""
    if r.get("t_cut_s") is None or abs(r["t_cut_s"] - tr["cut"]) > cut_tol:
        return "cut %s vs truth %.3f" % (r.get("t_cut_s"), tr["cut"])
    if not claimed(r):
        return "published partial (lead-in %s) though its cut was seen" % r.get("lead_in")
    if r.get("end") != "stopped":
        return "ended '%s', not stopped" % r.get("end")
    if tr["stop"] is not None and (r.get("t_stop_s") is None or abs(r["t_stop_s"] - tr["stop"]) > STOP_TOL):
        return "stop %s vs truth %.3f" % (r.get("t_stop_s"), tr["stop"])
    ok, why = friction_ok(r, tr)
    if not ok:
        return why
    return None


def check_whole(label, runs, bench, truths, cut_tols=None, only=None):
    """Every truth run (of `only`, default all) has exactly one run of `bench` in `runs` with its
    true cut, and that run is whole."""
    mine = [r for r in runs if r["_bench"] == bench]
    for tr in truths:
        if only is not None and not only(tr):
            continue
        tol = (cut_tols or {}).get(tr["run"], CUT_TOL)
        near = [r for r in mine if r.get("t_cut_s") is not None and abs(r["t_cut_s"] - tr["cut"]) <= max(tol, INVENT_TOL)
                and claimed(r)]
        if not near:
            inside = [desc(r) for r in mine if r.get("t_cut_s") is not None and tr["stop"] is not None
                      and tr["cut"] - 1 <= r["t_cut_s"] <= tr["stop"] + 1]
            bad("%s: %s truth run %d (cut %.3f s) not fitted%s" % (label, bench, tr["run"], tr["cut"],
                (": what covers it: " + "; ".join(inside)) if inside else ""))
            continue
        if len(near) > 1:
            bad("%s: %s truth run %d fitted %d times: %s" % (label, bench, tr["run"], len(near),
                "; ".join(desc(r) for r in near)))
        w = whole_problem(near[0], tr, tol)
        if w:
            bad("%s: %s truth run %d not whole: %s [%s]" % (label, bench, tr["run"], w, desc(near[0])))


def check_no_invented(label, runs, bench, truths):
    for r in runs:
        if r["_bench"] != bench or not claimed(r) or r.get("t_cut_s") is None:
            continue
        if all(abs(r["t_cut_s"] - tr["cut"]) > INVENT_TOL for tr in truths):
            bad("%s: invented cut: %s" % (label, desc(r)))


def check_no_end(label, runs, ends=("silent",)):
    for r in runs:
        if r.get("end") in ends:
            bad("%s: run closed '%s': %s" % (label, r.get("end"), desc(r)))


def equal_runs(label, a, b, bench=None, a_name="a", b_name="b", only_cuts=None):
    """Runs of a and b (one bench or all) pair one to one and are equal."""
    def key(rs):
        return sorted([r for r in rs if bench is None or r["_bench"] == bench
                       if only_cuts is None or only_cuts(r)], key=lambda r: (r["_bench"], r.get("t_cut_s") or -1))
    ra, rb = key(a), key(b)
    used = set()
    for x in ra:
        best = None
        for j, y in enumerate(rb):
            if j in used or y["_bench"] != x["_bench"]:
                continue
            if x.get("t_cut_s") is not None and y.get("t_cut_s") is not None and abs(x["t_cut_s"] - y["t_cut_s"]) <= 0.5:
                best = j
                break
        if best is None:
            bad("%s: %s has %s, %s has no run there" % (label, a_name, desc(x), b_name))
            continue
        used.add(best)
        y = rb[best]
        diffs = []
        if abs(x["t_cut_s"] - y["t_cut_s"]) > EQ_CUT:
            diffs.append("cut %.4f vs %.4f" % (x["t_cut_s"], y["t_cut_s"]))
        if x.get("samples") != y.get("samples"):
            diffs.append("samples %s vs %s" % (x.get("samples"), y.get("samples")))
        for p in ("c3", "c4"):
            u, _ = param(x, "combined", p)
            v, _ = param(y, "combined", p)
            if u is None or v is None or abs(u - v) > EQ_REL * max(abs(u), abs(v)):
                diffs.append("%s %s vs %s" % (p, u, v))
        if x.get("end") != y.get("end"):
            diffs.append("end %s vs %s" % (x.get("end"), y.get("end")))
        if diffs:
            bad("%s: %s run at cut %.3f differs (%s vs %s): %s" % (label, x["_bench"], x["t_cut_s"], a_name, b_name,
                                                                 ", ".join(diffs)))
    for j, y in enumerate(rb):
        if j not in used:
            bad("%s: %s has %s, %s has no run there" % (label, b_name, desc(y), a_name))


# ---------------------------------------------------------------- logs: samples and heartbeats
def samples(files):
    """{bench: [(seq, device_s, host_us, log_us, source_session)]} for every sample recorded, log order."""
    sl = spindown_log()
    out = {}
    for f in files:
        for m in sl.SpindownLog(f).messages(kinds={"SAMPLE"}):
            s = m.message
            for i in range(s.n):
                out.setdefault(m.bench, []).append((s.seq + i, s.device_time_us[i] / 1e6, s.host_time_us[i],
                                                    m.timestamp, s.source_session))
    return out


def statuses(files):
    """[(log_us, service, instance, state, counters, utime, start_utime)] of every STATUS, log order."""
    sl = spindown_log()
    out = []
    for f in files:
        for m in sl.SpindownLog(f).messages(kinds={"STATUS"}):
            s = m.message
            out.append((m.timestamp, s.service, s.instance, s.state,
                        dict(zip(s.counter_name, s.counter_value)), s.utime, getattr(s, "start_utime", 0)))
    return out


def last_counters(files, service, instance=None):
    """Each counter's latest value over the service's STATUS messages in the log. The logger writes
    two kinds into its own file: its heartbeats (all counters) and status events at open and stop
    (a subset, without the signature counters): so a counter is taken from the latest STATUS that
    carries it, not only from the very last STATUS."""
    c = None
    for st in statuses(files):
        if st[1] == service and (instance is None or st[2] == instance):
            c = dict(c or {})
            c.update(st[4])
    if c is None:
        raise Harness("no %s STATUS in %s" % (service, files))
    return c


def counter_zero(label, counters, names):
    for n in names:
        if n not in counters:
            raise Harness("%s: no counter %s (have %s)" % (label, n, sorted(counters)))
        if counters[n] != 0:
            bad("%s: %s = %d, truth 0" % (label, n, counters[n]))


def sent_lines(tag):
    with open(os.path.join(SCR, tag + ".sent.tsv")) as f:
        return max(0, sum(1 for _ in f) - 1)


def fit_messages(files):
    """FIT messages as decoded (for bridge_session, which refit --live does not print)."""
    sl = spindown_log()
    out = []
    for f in files:
        for m in sl.SpindownLog(f).messages(kinds={"FIT"}):
            out.append(m.message)
    return out


def bridge_session(tag):
    """The bridge's session id, from its stderr ('session 02f3bdfb1411353c'), as the signed int64 of the messages."""
    with open(os.path.join(SCR, tag + ".err")) as f:
        m = re.search(r"session ([0-9a-f]{16})", f.read())
    if not m:
        raise Harness("bridge %s named no session on stderr" % tag)
    v = int(m.group(1), 16)
    return v - (1 << 64) if v >= (1 << 63) else v


def relay_stats():
    with open(os.path.join(SCR, "relay.stats.json")) as f:
        return json.load(f)


# ---------------------------------------------------------------- the cases
def seqset(smp, bench):
    return [x[0] for x in smp.get(bench, [])]


def repeat_count(smp, bench):
    seen, extra = set(), 0
    for x in smp.get(bench, []):
        if (x[0], x[4]) in seen:
            extra += 1
        seen.add((x[0], x[4]))
    return extra


def case_dup_reorder():
    benches = {"bench-1": truth("vb1"), "bench-2": truth("vb2")}
    lab, wit = logs("lablogs"), logs("witlogs")
    live = live_fits(lab)
    wref, _ = refit(wit)
    lref, _ = refit(lab)
    smp = samples(lab)
    for b, tr in benches.items():
        check_whole("live", live, b, tr)
        check_no_invented("live", live, b, tr)
        check_whole("refit of the lab log", lref, b, tr)
    equal_runs("live vs witness refit (every sample used once)", live, wref, a_name="live FIT", b_name="witness refit")
    equal_runs("lab-log refit vs witness refit", lref, wref, a_name="lab refit", b_name="witness refit")
    lg = last_counters(lab, "logger")
    ft = last_counters(lab, "fitter")
    counter_zero("logger", lg, ["samples_missing", "seq_gaps"])
    counter_zero("fitter", ft, ["samples_lost", "seq_gaps"])
    extra = sum(repeat_count(smp, b) for b in benches)
    if extra == 0:
        raise Harness("the link duplicated nothing (relay: %s)" % relay_stats())
    for who, c, name in (("logger", lg, "seq_repeats"), ("fitter", ft, "duplicates")):
        if name in c and c[name] != extra:
            bad("%s: %s = %d, truth %d (extra copies in the lab log by sequence number)" % (who, name, c[name], extra))
    # the reordering really happened
    late = 0
    for b in benches:
        s = seqset(smp, b)
        late += sum(1 for i in range(1, len(s)) if s[i] < s[i - 1])
    if late < 20:
        raise Harness("only %d out-of-order arrivals: the link did not reorder" % late)


def block_late(smp, bench, tr):
    """How many samples of run 1's coast arrived after a newer one (the late block)."""
    s = smp.get(bench, [])
    hi, late, where = -1, 0, []
    for x in s:
        if x[0] < hi:
            late += 1
            where.append(x[1])
        hi = max(hi, x[0])
    return late, where


def case_late_block():
    tr = truth("vb1")
    lab, wit = logs("lablogs"), logs("witlogs")
    smp = samples(lab)
    late, where = block_late(smp, "bench-1", tr)
    r1 = tr[0]
    if late < 40 or not where or not (r1["cut"] + 0.5 <= min(where) and max(where) <= r1["stop"] - 2):
        raise Harness("the late block did not fall inside run 1's coast as planned (%d late samples, device %s..%s, "
                      "coast %.2f..%.2f)" % (late, min(where) if where else None, max(where) if where else None,
                                             r1["cut"], r1["stop"] or -1))
    live = live_fits(lab)
    wref, _ = refit(wit)
    lref, _ = refit(lab)
    check_whole("live", live, "bench-1", tr)
    check_no_invented("live", live, "bench-1", tr)
    check_no_end("live", live)
    check_whole("refit of the lab log", lref, "bench-1", tr)
    check_no_end("refit of the lab log", lref)
    equal_runs("live vs witness refit (every sample used once)", live, wref, a_name="live FIT", b_name="witness refit")
    equal_runs("lab-log refit vs witness refit", lref, wref, a_name="lab refit", b_name="witness refit")
    lg = last_counters(lab, "logger")
    ft = last_counters(lab, "fitter")
    counter_zero("logger", lg, ["samples_missing", "seq_gaps", "seq_repeats"])
    counter_zero("fitter", ft, ["samples_lost", "seq_gaps", "duplicates", "silent_benches"])


def case_burst_loss():
    tr = truth("vb1")
    lab, wit = logs("lablogs"), logs("witlogs")
    ls, ws = samples(lab), samples(wit)
    got = {x[0] for x in ls.get("bench-1", [])}
    wdev = {x[0]: x[1] for x in ws.get("bench-1", [])}
    top = max(got) if got else -1
    lost = sorted(q for q in wdev if q not in got and q < top)
    if len(lost) < 10:
        raise Harness("the link lost only %d samples (relay: %s)" % (len(lost), relay_stats()))
    rep = repeat_count(ls, "bench-1")
    if rep:
        raise Harness("the lab log holds %d repeated samples, but this link never duplicates" % rep)
    live = live_fits(lab)
    wref, _ = refit(wit)
    # cut tolerance: the lost stretch at the cut
    tols = {}
    lostset = set(lost)
    for r in tr:
        seqs = sorted(q for q, d in wdev.items() if abs(d - r["cut"]) <= 0.5)
        run_len, best = 0, 0
        for q in seqs:
            run_len = run_len + 1 if q in lostset else 0
            best = max(best, run_len)
        tols[r["run"]] = CUT_TOL + 0.02 * best
    check_whole("live", live, "bench-1", tr, cut_tols=tols)
    check_no_invented("live", live, "bench-1", tr)
    check_no_end("live", live, ("silent", "gap"))
    # samples used: the witness's run less what never arrived in its window
    for r in live:
        if r["_bench"] != "bench-1" or r.get("first_seq") is None:
            continue
        w = [x for x in wref if x["_bench"] == "bench-1" and x.get("t_cut_s") is not None
             and abs(x["t_cut_s"] - r["t_cut_s"]) <= 0.5]
        if not w:
            continue
        w = w[0]
        missing_in = sum(1 for q in lost if w["first_seq"] <= q <= w["last_seq"])
        expect = w["samples"] - missing_in
        if abs(r["samples"] - expect) > 2:
            bad("live FIT of run at cut %.3f used %s samples; the witness's run has %d of which %d never arrived: "
                "expected %d +- 2" % (r["t_cut_s"], r["samples"], w["samples"], missing_in, expect))
    lg = last_counters(lab, "logger")
    ft = last_counters(lab, "fitter")
    if lg.get("samples_missing") != len(lost):
        bad("logger: samples_missing = %s, truth %d (in the witness log, absent from the lab log)" % (
            lg.get("samples_missing"), len(lost)))
    if ft.get("samples_lost") != len(lost):
        bad("fitter: samples_lost = %s, truth %d" % (ft.get("samples_lost"), len(lost)))
    counter_zero("logger", lg, ["seq_repeats"])
    counter_zero("fitter", ft, ["duplicates"])


def step_check(files, bench, r1, min_jump):
    """The log shows the wall-clock step inside run 1's coast: returns the device time of the step."""
    smp = samples(files)[bench]
    for i in range(1, len(smp)):
        jl = (smp[i][3] - smp[i - 1][3]) / 1e6     # log time
        jh = (smp[i][2] - smp[i - 1][2]) / 1e6     # bridge host time
        if abs(jl) >= min_jump or abs(jh) >= min_jump:
            d = smp[i][1]
            if not (r1["cut"] + 0.5 <= d <= r1["stop"] - 2):
                raise Harness("the clock step fell at device %.2f s, outside run 1's coast %.2f..%.2f" % (
                    d, r1["cut"], r1["stop"]))
            return d
    raise Harness("no clock step of %g s seen in the log" % min_jump)


def case_lab_clock_forward():
    tr = truth("vb1")
    lab = logs("lablogs")
    step_check(lab, "bench-1", tr[0], 3000)
    live = live_fits(lab)
    check_whole("live", live, "bench-1", tr)
    check_no_invented("live", live, "bench-1", tr)
    check_no_end("live", live)
    ref, _ = refit(lab)
    check_whole("refit of the logger's files", ref, "bench-1", tr)
    check_no_invented("refit", ref, "bench-1", tr)
    check_no_end("refit of the logger's files", ref)
    rc, out = compare(lab)
    if rc != 0:
        bad("refit --compare exit %d: %s" % (rc, " | ".join(l for l in out.splitlines() if l.strip())[-600:]))
    counter_zero("logger", last_counters(lab, "logger"), ["samples_missing"])
    counter_zero("fitter", last_counters(lab, "fitter"), ["samples_lost", "silent_benches"])


def case_bench_clock_forward_signed():
    tr = truth("vb1")
    lab = logs("lablogs")
    key = ["--key", os.path.join(SCR, "lab.key")]
    step_check(lab, "bench-1", tr[0], 30)
    ft = last_counters(lab, "fitter")
    lg = last_counters(lab, "logger")
    counter_zero("fitter", ft, ["unsigned_messages", "bad_signatures", "replays", "samples_lost"])
    counter_zero("logger", lg, ["unsigned_messages", "bad_signatures", "replays", "samples_missing"])
    live = live_fits(lab, key)
    check_whole("live (signed FITs)", live, "bench-1", tr)
    check_no_invented("live", live, "bench-1", tr)
    ref, _ = refit(lab, key)
    check_whole("refit --key", ref, "bench-1", tr)


def dev_at(smp, host_us):
    """Device time of the sample the bridge read nearest to host time host_us."""
    best = min(smp, key=lambda x: abs(x[2] - host_us))
    return best[1] + (host_us - best[2]) / 1e6


def case_fitter_joins_late():
    t1, t2 = truth("vb1"), truth("vb2")
    lab = logs("lablogs")
    smp = samples(lab)
    st = [s for s in statuses(lab) if s[1] == "fitter"]
    if not st:
        raise Harness("no fitter STATUS in the log")
    start = st[0][6] or st[0][5]
    d1, d2 = dev_at(smp["bench-1"], start), dev_at(smp["bench-2"], start)
    if not (d1 <= t1[0]["cut"] - 1.5 and d1 >= 0.5):
        raise Harness("the fitter started at bench-1 device %.2f s, not >= 1.5 s before its cut %.2f" % (d1, t1[0]["cut"]))
    if not (t2[0]["cut"] + 1.5 <= d2 <= t2[0]["stop"] - 1.5):
        raise Harness("the fitter started at bench-2 device %.2f s, not inside its coast %.2f..%.2f" % (
            d2, t2[0]["cut"], t2[0]["stop"]))
    live = live_fits(lab)
    check_whole("live", live, "bench-1", t1)                 # both runs: the first's cut was seen
    check_whole("live", live, "bench-2", t2, only=lambda r: r["run"] >= 2)
    check_no_invented("live", live, "bench-1", t1)
    for r in live:
        if r["_bench"] == "bench-2" and claimed(r) and r.get("t_cut_s") is not None and r["t_cut_s"] < d2 + 0.5:
            bad("live: bench-2's run in progress when the fitter started was given a cut: %s" % desc(r))
    check_no_invented("live", live, "bench-2", t2)
    ref, _ = refit(lab)
    whole_cuts = [t1[0]["cut"], t1[1]["cut"], t2[1]["cut"]]
    sel = lambda r: r.get("t_cut_s") is not None and any(abs(r["t_cut_s"] - c) <= INVENT_TOL for c in whole_cuts) and claimed(r)
    equal_runs("whole runs: live vs refit", live, ref, a_name="live FIT", b_name="refit", only_cuts=sel)
    rc, out = compare(lab)
    for w in ("invented cut", "split"):
        if w in out:
            bad("refit --compare says '%s': %s" % (w, " | ".join(l for l in out.splitlines() if w in l)[:500]))


def case_logger_restart():
    tr = truth("vb1")
    a, b = logs("logsA"), logs("logsB")
    ca = last_counters(a, "logger")
    cb = last_counters(b, "logger")
    counter_zero("logger 1 (its last STATUS)", ca, ["samples_missing"])
    counter_zero("logger 2, started mid-stream", cb, ["samples_missing"])
    ref, d = refit(list(reversed(b + a)))
    sess = d.get("files", [])
    if len(sess) != 1 or len(sess[0].get("session_files", [])) != len(a + b):
        bad("refit of the two loggers' files: %d sessions (%s), truth one session of %d files" % (
            len(sess), [s.get("session_files", [s.get("file")]) for s in sess], len(a + b)))
    check_whole("refit of both files", ref, "bench-1", tr)
    check_no_invented("refit of both files", ref, "bench-1", tr)
    check_no_end("refit of both files", ref, ("silent", "gap"))
    live = live_fits(a + b)
    check_whole("live", live, "bench-1", tr)
    # runs wholly in one file (all but the one across the restart) equal their live FIT
    gap_cut = tr[0]["cut"]
    sel = lambda r: r.get("t_cut_s") is not None and abs(r["t_cut_s"] - gap_cut) > INVENT_TOL
    equal_runs("runs wholly in one file: live vs refit", live, ref, a_name="live FIT", b_name="refit", only_cuts=sel)
    rc, out = compare(list(reversed(b + a)))
    for w in ("invented cut", "split"):
        if w in out:
            bad("refit --compare says '%s': %s" % (w, " | ".join(l for l in out.splitlines() if w in l)[:500]))


def case_replay_fast():
    tr = {"bench-1": truth("vb1"), "bench-2": truth("vb2")}
    rec, play = logs("reclogs"), logs("playlogs")
    live = live_fits(rec)
    rep = live_fits(play)
    for b, t in tr.items():
        check_whole("live", live, b, t)
        check_whole("replay fitter", rep, b, t)
        check_no_invented("replay fitter", rep, b, t)
    equal_runs("replay fitter vs live fitter", rep, live, a_name="replay FIT", b_name="live FIT")
    counter_zero("replay fitter", last_counters(play, "fitter"), ["samples_lost", "duplicates", "flood_drops",
                                                                   "queue_drops", "other_lab"])


def case_concat_days():
    mon, tue = truth("mon", "X"), truth("tue", "Y")
    M, T = logs("monlogs"), logs("tuelogs")
    week = os.path.join(SCR, "week.lcm")
    with open(week, "wb") as w:
        for f in M + T:
            with open(f, "rb") as r:
                w.write(r.read())
    rw, _ = refit([week])
    rm, _ = refit(M)
    rt, _ = refit(T)
    check_whole("refit week.lcm (Monday)", rw, "bench-1", mon)
    check_whole("refit week.lcm (Tuesday)", rw, "bench-1", tue)
    check_no_invented("refit week.lcm", rw, "bench-1", mon + tue)
    equal_runs("week.lcm vs each day alone", rw, rm + rt, a_name="week.lcm", b_name="the day's log")
    rc, out = compare([week])
    if rc != 0:
        bad("refit week.lcm --compare exit %d: %s" % (rc, " | ".join(l for l in out.splitlines() if l.strip())[-600:]))


def case_cable_swap():
    X, Y = truth("vbx", "X"), truth("vby", "Y")
    lab = logs("lablogs")
    with open(os.path.join(SCR, "swap.json")) as f:
        sw = json.load(f)          # wall (host) times of the swap: cables out, cables in
    smp = samples(lab)
    sess = {bridge_session("bra1"): ("bench-a", "X"), bridge_session("brb1"): ("bench-b", "Y"),
            bridge_session("bra2"): ("bench-a", "Y"), bridge_session("brb2"): ("bench-b", "X")}
    # device time of the swap on each motor's clock
    allx = [x for b in smp for x in smp[b] if sess.get(x[4], (None, None))[1] == "X"]
    ally = [x for b in smp for x in smp[b] if sess.get(x[4], (None, None))[1] == "Y"]
    if not allx or not ally:
        raise Harness("no samples of both motors in the log")
    out_x, in_x = dev_at(allx, sw["out_us"]), dev_at(allx, sw["in_us"])
    out_y, in_y = dev_at(ally, sw["out_us"]), dev_at(ally, sw["in_us"])
    truths = {"X": X, "Y": Y}
    xr = [r for r in X if r["cut"] < out_x < (r["stop"] or 0)]
    if not xr:
        raise Harness("the swap (X device %.2f s) did not fall in a coast of motor X" % out_x)
    fits = fit_messages(lab)
    live = live_fits(lab)
    for m in fits:
        if m.bridge_session not in sess:
            bad("FIT %s run %d names bridge session %d, none of the four bridges" % (m.bench, m.run, m.bridge_session))
            continue
        bench, motor = sess[m.bridge_session]
        if m.bench != bench:
            bad("FIT on %s names the bridge of %s" % (m.bench, bench))
        # its run as refit --live prints it
        r = [x for x in live if x["_bench"] == m.bench and x.get("run") == m.run
             and x.get("t_cut_s") is not None and abs(x["t_cut_s"] - m.t_cut_s) < 1e-6]
        if not r:
            continue
        r = r[0]
        c4, se = param(r, "combined", "c4")
        other = "Y" if motor == "X" else "X"
        tm, to = truths[motor][0]["c4"], truths[other][0]["c4"]
        if c4 is not None and abs(c4 - tm) > max(6 * se, 0.15 * tm):
            bad("FIT %s run %d of motor %s's samples has c4 %.4g: motor %s's is %.4g, %s's %.4g (mixed?) [%s]" % (
                m.bench, m.run, motor, c4, motor, tm, other, to, desc(r)))
        if claimed(r):
            if all(abs(r["t_cut_s"] - t["cut"]) > INVENT_TOL for t in truths[motor]):
                bad("invented cut: %s (motor %s's cuts: %s)" % (desc(r), motor,
                    ", ".join("%.2f" % t["cut"] for t in truths[motor])))
    # runs wholly after the swap, >= 2 s margin: whole under the id they were connected to
    runs_after = [r for r in live]
    check_whole("after the swap, bench-a = motor Y", [r for r in runs_after if r["_bench"] == "bench-a"], "bench-a", Y,
                only=lambda t: t["cut"] >= in_y + 2)
    check_whole("after the swap, bench-b = motor X", [r for r in runs_after if r["_bench"] == "bench-b"], "bench-b", X,
                only=lambda t: t["cut"] >= in_x + 2)
    check_whole("before the swap, bench-a = motor X", live, "bench-a", X,
                only=lambda t: t["stop"] is not None and t["stop"] + 2.5 <= out_x)
    check_whole("before the swap, bench-b = motor Y", live, "bench-b", Y,
                only=lambda t: t["stop"] is not None and t["stop"] + 2.5 <= out_y)
    rc, out = compare(lab)
    if "invented cut" in out:
        bad("refit --compare says 'invented cut': %s" % " | ".join(l for l in out.splitlines() if "invented" in l)[:500])


def case_bridge_stall():
    tr = truth("vb1")
    lab = logs("lablogs")
    smp = samples(lab)["bench-1"]
    # the stall: a gap in the bridge's host times inside run 1's coast
    gaps = [(smp[i][2] - smp[i - 1][2]) / 1e6 for i in range(1, len(smp))]
    i = max(range(len(gaps)), key=lambda k: gaps[k])
    if gaps[i] < 3.0 or not (tr[0]["cut"] + 0.5 <= smp[i + 1][1] <= tr[0]["stop"] - 1):
        raise Harness("no 3-s stall inside run 1's coast (largest gap %.2f s at device %.2f)" % (gaps[i], smp[i + 1][1]))
    seqs = [x[0] for x in smp]
    sent = sent_lines("vb1")
    if sorted(set(seqs)) != list(range(len(set(seqs)))) or len(set(seqs)) != sent:
        bad("samples lost: the Arduino printed %d lines, the log holds %d distinct sequence numbers (0..%d)" % (
            sent, len(set(seqs)), max(seqs)))
    if len(seqs) != len(set(seqs)):
        bad("the log holds %d repeated samples" % (len(seqs) - len(set(seqs))))
    live = live_fits(lab)
    check_whole("live", live, "bench-1", tr)
    check_no_invented("live", live, "bench-1", tr)
    check_no_end("live", live)
    for r in live:
        if r.get("first_seq") is None:
            continue
        n = sum(1 for q in set(seqs) if r["first_seq"] <= q <= r["last_seq"])
        if abs(r["samples"] - n) > 2:
            bad("live FIT at cut %.3f used %s samples; the log holds %d between its first and last sequence" % (
                r["t_cut_s"], r["samples"], n))
    counter_zero("logger", last_counters(lab, "logger"), ["samples_missing"])
    counter_zero("fitter", last_counters(lab, "fitter"), ["samples_lost", "silent_benches", "flood_drops",
                                                           "queue_drops"])


CASES = {n[5:].replace("_", "-"): f for n, f in globals().items() if n.startswith("case_")}

if __name__ == "__main__":
    name = sys.argv[1]
    try:
        CASES[name]()
    except Harness as e:
        print("HARNESS: %s" % e)
        sys.exit(3)
    except Exception as e:  # a bug of this judge is a harness failure, never a pass
        import traceback
        traceback.print_exc()
        print("HARNESS: judge error: %r" % e)
        sys.exit(3)
    for p in problems:
        print(p)
    sys.exit(1 if problems else 0)
