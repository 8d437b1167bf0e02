#!/usr/bin/python3
"""Judge the issue-31 cases against the virtual benches' truth.

Every sub-command prints ONE line `PASS <id>: …` or `FAIL <id>: …`.
Inputs are the virtual bench's --truth JSON and the fits as `spindown refit --live --json`
(the FIT messages the live fitter published, as recorded by spindown-logger) or
`spindown refit --json` (the log refitted), and the log's RUN messages as
`spindown export --mcap` words them.
"""
import json
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import h31lib  # noqa: E402

CUT_TOL_S = 0.10    # 5 sample periods: a cut found in the right place
STOP_TOL_S = 0.50   # a stop found in the right place (the stop is fitted, ~ms in practice)


# ------------------------------------------------------------------ inputs
def load_runs_json(path):
    """fits from `spindown refit [--live] --json`: [(bench, run_obj)]."""
    out = []
    if not path or not os.path.exists(path) or os.path.getsize(path) == 0:
        return out
    try:
        d = json.load(open(path))
    except Exception:
        return None
    for f in d.get("files") or []:
        for r in f.get("runs") or []:
            b = (r.get("bench") or {}).get("id") if isinstance(r.get("bench"), dict) else r.get("bench")
            out.append((b, r))
    return out


def truth_runs(truth):
    """[(run_no, cut_device_s, epoch, stop_device_s or None, cut_bench_s, stop_bench_s)]"""
    res = []
    for r in truth["runs"]:
        cut_dev = r["cut_device_us"] / 1e6
        stop_rel = r.get("t_stop_s")
        stop_dev = cut_dev + stop_rel if (r.get("stopped") and stop_rel is not None) else None
        stop_bench = r["cut_bench_s"] + stop_rel if stop_rel is not None else None
        res.append(dict(run=r["run"], cut=cut_dev, epoch=r.get("cut_epoch", 0), stop=stop_dev,
                        cut_bench=r["cut_bench_s"], stop_bench=stop_bench))
    return res


def match_truth(fit, truths):
    """The truth run whose cut (device time) is within CUT_TOL_S of the fit's cut."""
    t = fit.get("t_cut_s")
    if t is None:
        return None
    best = None
    for tr in truths:
        d = abs(t - tr["cut"])
        if d <= CUT_TOL_S and (best is None or d < abs(t - best["cut"])):
            best = tr
    return best


def short(fit):
    c4, _ = h31lib.model_param(fit, "combined", "c4")
    return "run %s cut %s stop %s end %s lead_in %s c4 %s" % (
        fit.get("run"), _f(fit.get("t_cut_s")), _f(fit.get("t_stop_s")), fit.get("end"),
        fit.get("lead_in"), _f(c4, "%.4g"))


def _f(x, fmt="%.3f"):
    return "null" if x is None else fmt % x


def physics_stop(truth, e0):
    """t_stop after the cut of J·dω/dt = −(c_v·ω + c_c) from ω0 = e0/K_b (no Stribeck/windage)."""
    import math
    J, kb, cv, cc = truth["inertia_kg_m2"], truth["kb_v_s_per_rad"], truth["c_v"], truth["c_c"]
    w0 = e0 / kb
    if cv <= 0:
        return J * w0 / cc
    return (J / cv) * math.log(1.0 + cv * w0 / cc)


def truth_sane(truth):
    """The bench's printed stop times agree with the physics of its printed parameters."""
    probs = []
    for r in truth["runs"]:
        if truth.get("c_s", 0) or truth.get("c_w", 0):
            continue
        ts = physics_stop(truth, r["e0"])
        if r.get("t_stop_s") is not None and abs(ts - r["t_stop_s"]) > 0.05:
            probs.append("virtual bench truth: run %d stop %.3f s after the cut, physics says %.3f s" % (
                r["run"], r["t_stop_s"], ts))
    return probs


def judge_bench(fits, truth, must, may, label, max_per_run=1, check_stop=True,
                other_truths=()):
    """Problems (list of strings) and a summary for one bench's published fits.

    must: truth run numbers that must be fitted whole (true cut, true stop, true friction);
    may: run numbers whose coast a fault broke: a fit of them must have the true cut and
         friction (closed early is fine), or there is none;
    any other complete fit (a cut that is no true cut) is an invented cut;
    other_truths: [(name, truth)] of OTHER motors: a fit matching their friction is wrongly
         attributed to this bench.
    """
    trs = truth_runs(truth)
    cv, cc = truth["c_v"], truth["c_c"]
    probs = truth_sane(truth)
    per_run = {}
    invented = []
    partial = []
    for f in fits:
        if h31lib.is_partial(f):
            partial.append(f)
            # a partial run's friction is still this motor's, never another's
            for name, ot in other_truths:
                okf, _ = h31lib.friction_ok(f, ot["c_v"], ot["c_c"], whole=False)
                okm, _ = h31lib.friction_ok(f, cv, cc, whole=False)
                if okf and not okm:
                    probs.append("%s: a partial fit has %s's friction (%s)" % (label, name, short(f)))
            continue
        tr = match_truth(f, trs)
        if tr is None:
            invented.append(f)
            continue
        per_run.setdefault(tr["run"], []).append((tr, f))
    for f in invented:
        foreign = [name for name, ot in other_truths
                   if h31lib.friction_ok(f, ot["c_v"], ot["c_c"], whole=False)[0]
                   and not h31lib.friction_ok(f, cv, cc, whole=False)[0]]
        if foreign:
            probs.append("%s: %s's motor fitted as this bench's (%s)" % (label, foreign[0], short(f)))
        else:
            probs.append("%s: invented cut: complete fit with a cut no run of the bench had (%s)" % (label, short(f)))
    for rn in sorted(per_run):
        lst = per_run[rn]
        if len(lst) > max_per_run:
            probs.append("%s: truth run %d fitted %d times" % (label, rn, len(lst)))
        for tr, f in lst:
            whole = rn in must
            okf, why = h31lib.friction_ok(f, cv, cc, whole=whole)
            if not okf:
                probs.append("%s: truth run %d (cut %.3f s): wrong friction: %s" % (label, rn, tr["cut"], why))
            for name, ot in other_truths:
                okx, _ = h31lib.friction_ok(f, ot["c_v"], ot["c_c"], whole=False)
                if okx and not okf:
                    probs.append("%s: truth run %d fitted with %s's friction" % (label, rn, name))
            ts = f.get("t_stop_s")
            claims_stop = f.get("stopped") is True or (f.get("end") == "stopped")
            if check_stop and (whole or claims_stop):
                if tr["stop"] is None:
                    if claims_stop:
                        probs.append("%s: truth run %d never stopped but the fit says stopped at %s" % (
                            label, rn, _f(ts)))
                elif ts is None or abs(ts - tr["stop"]) > STOP_TOL_S:
                    probs.append("%s: truth run %d: stop %s vs true %.3f s (end %s, %s)" % (
                        label, rn, _f(ts), tr["stop"], f.get("end"),
                        "whole run" if whole else "a run a fault broke claims to have stopped"))
    missing = [rn for rn in must if rn not in per_run]
    for rn in missing:
        tr = [t for t in trs if t["run"] == rn][0]
        probs.append("%s: truth run %d (cut %.3f s, epoch %d) not fitted" % (label, rn, tr["cut"], tr["epoch"]))
    n_whole = len([rn for rn in must if rn in per_run])
    summary = "%s: %d/%d runs that must be whole fitted, %d invented cuts, %d partial, %d fits" % (
        label, n_whole, len(must), len(invented), len(partial), len(fits))
    return probs, summary


def verdict(case_id, probs, summary, extra=""):
    if probs:
        msg = "; ".join(probs[:6]) + (" (+%d more)" % (len(probs) - 6) if len(probs) > 6 else "")
        print("FAIL %s: %s [%s]%s" % (case_id, msg, summary, extra))
        return 1
    print("PASS %s: %s%s" % (case_id, summary, extra))
    return 0


def by_bench(runs, bench):
    return [r for b, r in runs if b == bench]


def need(runs, what, case_id):
    if runs is None:
        print("FAIL %s: %s is not valid JSON" % (case_id, what))
        sys.exit(0)


# ------------------------------------------------------------------ commands
def cmd_fits(a):
    """fits CASE_ID LIVE_JSON REFIT_JSON SPEC... [key=value...]

    SPEC: BENCH=TRUTH=MUST=MAY (MUST, MAY: comma-separated truth run numbers; '-' for a JSON
    not to judge). key=value: max_per_run=N, other:NAME=TRUTH (another motor's truth: a fit
    with its friction is wrongly attributed), extra=TEXT.
    """
    case_id, live_p, refit_p = a[:3]
    specs = [x for x in a[3:] if x.count("=") >= 3 and not x.startswith(("other:", "extra=", "max_per_run="))]
    opts = dict(x.split("=", 1) for x in a[3:] if x not in specs)
    others = []
    for k, v in opts.items():
        if k.startswith("other:"):
            others.append((k[6:], h31lib.load_truth(v)))
    maxper = int(opts.get("max_per_run", "1"))
    probs, sums = [], []
    for what, p in (("live", live_p), ("refit", refit_p)):
        if p == "-":
            continue
        runs = load_runs_json(p)
        need(runs, p, case_id)
        for spec in specs:
            bench, truth_p, must_s, may_s = spec.split("=", 3)
            truth = h31lib.load_truth(truth_p)
            must = [int(x) for x in must_s.split(",") if x]
            may = [int(x) for x in may_s.split(",") if x]
            oth = [(n, t) for n, t in others if t is not truth]
            pr, s = judge_bench(by_bench(runs, bench), truth, must, may, "%s %s" % (what, bench),
                                max_per_run=maxper, other_truths=oth)
            probs += pr
            sums.append(s)
    extra = opts.get("extra", "")
    return verdict(case_id, probs, "; ".join(sums), (" " + extra) if extra else "")


def cmd_equal(a):
    """equal CASE_ID LIVE_JSON NAME=REFIT_JSON...: every refit lists the live FITs' runs, same numbers.

    Runs are paired by bench and cut (docs/faults.md: a run is identified by its bench and its
    cut's device time); equal means: the same set of runs, cut and stop within 1 ms, c1..c4 of
    every model within a relative 1e-6 (the same code on the same samples).
    """
    case_id, live_p = a[0], a[1]
    live = load_runs_json(live_p)
    need(live, live_p, case_id)
    probs = []
    sums = []

    def key(b, r):
        return (b, round(r.get("t_cut_s") or -1.0, 2))

    lk = {}
    for b, r in live:
        lk.setdefault(key(b, r), r)
    for spec in a[2:]:
        name, p = spec.split("=", 1)
        ref = load_runs_json(p)
        need(ref, p, case_id)
        rk = {}
        for b, r in ref:
            rk.setdefault(key(b, r), r)
        miss = [k for k in lk if k not in rk]
        extra = [k for k in rk if k not in lk]
        diff = []
        for k in lk:
            if k not in rk:
                continue
            x, y = lk[k], rk[k]
            for fld in ("t_cut_s", "t_stop_s"):
                u, v = x.get(fld), y.get(fld)
                if (u is None) != (v is None) or (u is not None and abs(u - v) > 1e-3):
                    diff.append("%s %s %s live %s refit %s" % (k[0], k[1], fld, u, v))
            for model in ("viscous", "coulomb", "combined"):
                for prm in ("c1", "c2", "c3", "c4"):
                    u, _ = h31lib.model_param(x, model, prm)
                    v, _ = h31lib.model_param(y, model, prm)
                    if u is None and v is None:
                        continue
                    if (u is None) != (v is None) or abs(u - v) > 1e-6 * max(abs(u), abs(v), 1e-30):
                        diff.append("%s cut %s %s.%s live %s refit %s" % (k[0], k[1], model, prm, u, v))
        if miss:
            probs.append("%s: %d live runs missing from the refit (%s)" % (
                name, len(miss), ", ".join("%s@%.2f" % m for m in miss[:4])))
        if extra:
            probs.append("%s: %d refit runs the live fitter did not publish (%s)" % (
                name, len(extra), ", ".join("%s@%.2f" % m for m in extra[:4])))
        if diff:
            probs.append("%s: %d numbers differ (%s)" % (name, len(diff), "; ".join(diff[:2])))
        sums.append("%s: %d runs vs %d live" % (name, len(rk), len(lk)))
    return verdict(case_id, probs, "; ".join(sums))


def last_watch_table(path):
    """The last table `spindown watch --plain` printed: its lines from the last header on."""
    try:
        lines = open(path, errors="replace").read().splitlines()
    except OSError:
        return []
    start = None
    for i, ln in enumerate(lines):
        if re.match(r"\s*BENCH\s+RUN\b", ln):
            start = i
    if start is None:
        return []
    out = []
    for ln in lines[start + 1:]:
        if not ln.strip():
            break
        out.append(ln)
    return out


def last_watch_services(path):
    """The SERVICE rows of the last table `spindown watch --plain` printed."""
    try:
        lines = open(path, errors="replace").read().splitlines()
    except OSError:
        return []
    start = None
    for i, ln in enumerate(lines):
        if re.match(r"\s*SERVICE\s+STATE\b", ln):
            start = i
    if start is None:
        return []
    out = []
    for ln in lines[start + 1:]:
        if not ln.strip():
            break
        out.append(ln)
    return out


def cmd_abandoned(a):
    """abandoned CASE_ID MCAP T_TERM_NS T_RESTART_NS BENCH=CUT... exit=RC watch=FILE

    Each bench coasting when the fitter got SIGTERM: a RUN message for its open run (cut within
    CUT_TOL_S of the true cut) whose state or note says it was abandoned, logged after the
    SIGTERM and before the fitter was started again. The fitter exits 0 within 5 s. The last
    table `spindown watch` printed (2 s after the fitter stopped) shows no bench as coasting and
    the fitter not "running" (its last STATUS said it stopped).
    """
    case_id, mcap, t_term, t_restart = a[0], a[1], int(a[2]), int(a[3])
    benches = [x.split("=", 1) for x in a[4:] if not x.startswith(("exit=", "watch="))]
    opts = dict(x.split("=", 1) for x in a[4:] if x.startswith(("exit=", "watch=")))
    probs, got = [], []
    try:
        runs = h31lib.runs_from_mcap(mcap)
    except Exception as e:
        print("FAIL %s: cannot read the exported log %s: %s" % (case_id, mcap, e))
        return 1
    for bench, cut in benches:
        cut = float(cut)
        hit = None
        for b, lt, r in runs:
            if b != bench or not (t_term <= lt <= t_restart):
                continue
            tc = r.get("t_cut_s")
            if tc is None or abs(tc - cut) > CUT_TOL_S:
                continue
            words = ("%s %s" % (r.get("state"), r.get("note"))).lower()
            if "abandon" in words or "stopping" in words:
                hit = r
        if hit is None:
            after = [r for b, lt, r in runs if b == bench and t_term <= lt <= t_restart]
            probs.append("%s: no RUN abandoned for its open run (cut %.3f s) after SIGTERM (%d RUN messages then%s)" % (
                bench, cut, len(after), (": " + ", ".join("%s/%s" % (r.get("state"), r.get("note")) for r in after[:3])) if after else ""))
        else:
            got.append("%s RUN %s (%s)" % (bench, hit.get("state"), hit.get("note")))
    rc = opts.get("exit", "?")
    if rc != "0":
        probs.append("fitter exit %s after SIGTERM (want 0 within 5 s)" % rc)
    table = last_watch_table(opts.get("watch", ""))
    if not table:
        probs.append("spindown watch printed no table")
    for bench, _ in benches:
        rows = [ln for ln in table if ln.split()[:1] == [bench]]
        if not rows:
            probs.append("watch's last table has no row for %s" % bench)
        elif re.search(r"\bcoasting\b", rows[-1], re.I):
            probs.append("watch's last table (after the fitter stopped) still shows %s coasting: %r" % (bench, rows[-1].strip()))
    frows = [ln for ln in last_watch_services(opts.get("watch", "")) if ln.split()[:1] == ["fitter"]]
    if frows and re.search(r"\brunning\b", frows[-1]):
        probs.append("watch's last table (2 s after the fitter exited) shows it running: %r" % frows[-1].strip())
    summary = "fitter exit %s; %s" % (rc, "; ".join(got) if got else "no RUN abandoned")
    return verdict(case_id, probs, summary)


def cmd_doctor(a):
    """doctor CASE_ID DOCTOR_JSON OTHER_HOST OTHER_GROUP

    `spindown doctor --json` on the PC that serves two labs, with lab A's URL: a check at level
    warn or fail names the other lab's traffic on the group and port (its bench PC's host name,
    its group, or the words "another lab"/"other lab"/"two sources"; loose, case-insensitive).
    """
    case_id, p, host, group = a
    try:
        d = json.load(open(p))
    except Exception as e:
        print("FAIL %s: doctor --json gave no JSON (%s)" % (case_id, e))
        return 1
    checks = d.get("checks") or []
    rx = re.compile(r"%s|%s|another lab|other lab|two labs|two sources|second source|another source|foreign" % (
        re.escape(host), re.escape(group)), re.I)
    hits = []
    for c in checks:
        lvl = str(c.get("level", "")).lower()
        text = " ".join(str(c.get(k, "")) for k in ("name", "detail", "fix"))
        if lvl in ("warn", "warning", "fail", "failure", "error") and rx.search(text):
            hits.append("%s %s: %s" % (lvl, c.get("name"), str(c.get("detail"))[:140]))
    levels = ", ".join("%s %s" % (c.get("level"), c.get("name")) for c in checks)
    if hits:
        print("PASS %s: doctor names the other lab: %s" % (case_id, hits[0]))
        return 0
    print("FAIL %s: no doctor check warns about lab B's traffic arriving on lab A's port (checks: %s)" % (case_id, levels))
    return 1


def cmd_collision(a):
    """collision CASE_ID WATCH_TXT FITTER_A_ERR FITTER_B_ERR HOST_A HOST_B

    Two fitters with one instance name on one network are named: either fitter's stderr names
    the other's PC (its host name) or says the instance is taken/collides (loose keywords), or
    the teacher's `spindown watch --once` shows both fitters (rows for both hosts) or says so.
    """
    case_id, watch, fa, fb, ha, hb = a
    rx = re.compile(r"another fitter|other fitter|two fitters|second fitter|same instance|same name|instance .*(taken|in use|collid|clash|twice)|collid|clash|duplicate instance", re.I)

    def read(p):
        try:
            return open(p, errors="replace").read()
        except OSError:
            return ""
    ea, eb, w = read(fa), read(fb), read(watch)
    if hb in ea or rx.search(ea):
        line = [ln for ln in ea.splitlines() if hb in ln or rx.search(ln)][0]
        print("PASS %s: lab A's fitter says: %s" % (case_id, line.strip()[:160]))
        return 0
    if ha in eb or rx.search(eb):
        line = [ln for ln in eb.splitlines() if ha in ln or rx.search(ln)][0]
        print("PASS %s: lab B's fitter says: %s" % (case_id, line.strip()[:160]))
        return 0
    frows = [ln for ln in w.splitlines() if re.match(r"\s*fitter\b", ln)]
    hosts = set(h for h in (ha, hb) for ln in frows if h in ln)
    if len(hosts) == 2 or rx.search(w):
        print("PASS %s: watch shows both fitters: %s" % (case_id, " | ".join(x.strip()[:80] for x in frows)))
        return 0
    print("FAIL %s: the two 'fitter' instances (on %s and %s) are named nowhere: no stderr line, and watch shows %d fitter row(s): %s" % (
        case_id, ha, hb, len(frows), " | ".join(x.strip()[:100] for x in frows)))
    return 1


def main():
    cmd, args = sys.argv[1], sys.argv[2:]
    if cmd == "fits":
        return cmd_fits(args)
    if cmd == "doctor":
        return cmd_doctor(args)
    if cmd == "collision":
        return cmd_collision(args)
    if cmd == "abandoned":
        return cmd_abandoned(args)
    if cmd == "equal":
        return cmd_equal(args)
    print("judge.py: unknown command %s" % cmd, file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main() or 0)
