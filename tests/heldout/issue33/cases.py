#!/usr/bin/python3
"""Issue 33 held-out cases: one run window on every path (fit, explain, live FIT, live EXPLAIN,
refit), refit reproducing EXPLAIN, and compact `fit --json` when piped.

Usage: cases.py BIN_DIR SCRATCH_DIR       (run.sh calls it; see CASES.md for each case's truth)
"""
import json
import math
import os
import pty
import re
import select
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import gen  # noqa: E402

BIN = os.path.abspath(sys.argv[1])
TMP = os.path.abspath(sys.argv[2])
PY = "/usr/bin/python3"
SPEED = 4.0
BENCH = "bench33"
results = []


def report(case, ok, msg):
    results.append(ok)
    print("%s %s: %s" % ("PASS" if ok else "FAIL", case, msg), flush=True)


def run(args, timeout=60, **kw):
    try:
        return subprocess.run(args, capture_output=True, timeout=timeout, **kw)
    except subprocess.TimeoutExpired as e:
        class R:
            returncode = -9
            stdout = e.stdout or b""
            stderr = (e.stderr or b"") + b"\n(timed out)"
        return R()


def rel(a, b):
    if a is None or b is None:
        return float("inf")
    a, b = float(a), float(b)
    if a == b:
        return 0.0
    return abs(a - b) / max(abs(a), abs(b), 1e-300)


def close_param(a, b, stderr, rtol=1e-6, sig=1e-3):
    """Equal within 1e-6 relative, or within 1e-3 of a standard error (a difference no
    statistics can see)."""
    if a is None or b is None:
        return False
    return abs(a - b) <= max(rtol * max(abs(a), abs(b)), sig * abs(stderr or 0.0))


# ---------------------------------------------------------------- inputs and truth
os.makedirs(TMP, exist_ok=True)
subprocess.run([PY, os.path.join(HERE, "gen.py"), "lab", TMP], check=True, timeout=60)
subprocess.run([PY, os.path.join(HERE, "gen.py"), "many", TMP, "40"], check=True, timeout=60)
truth = json.load(open(os.path.join(TMP, "lab-run.truth.json")))
LAB = os.path.join(TMP, "lab-run.txt")
PERIOD = truth["max_period_s"]                       # one sample period (21 ms at most)
STOP_TOL = PERIOD + truth["t_unresolved_at_stop_s"]  # the print cannot resolve the last 0.16 s
valid = truth["valid_samples"]


def window_truth(t_from, t_to):
    """(samples in [t_from, t_to] of the recording, of them outliers): what a window holds."""
    n = sum(1 for s in valid if t_from - 1e-9 <= s["t_s"] <= t_to + 1e-9)
    o = sum(1 for s in valid if t_from - 1e-9 <= s["t_s"] <= t_to + 1e-9 and s["outlier"])
    return n, o


def truth_rmse(with_outliers):
    """RMSE of the printed readings about the true back-EMF, cut .. stop + 2 s."""
    acc, n = 0.0, 0
    for s in valid:
        tau = s["t_s"] - truth["t_cut_s"]
        if tau < 0 or tau > truth["coast_s"] + 2.0:
            continue
        if s["outlier"] and not with_outliers:
            continue
        v = truth["Kb"] * gen.omega(tau, truth["omega0"], truth["c3"], truth["c4"])
        acc += (s["printed"] - v) ** 2
        n += 1
    return math.sqrt(acc / n)


RMSE_CLEAN = truth_rmse(False)
RMSE_DIRTY = truth_rmse(True)
RMSE_BOUND = 1.5 * RMSE_CLEAN   # the true model on the samples without the dropouts


def check_run_times(name, t_cut, t_stop):
    errs = []
    if t_cut is None or abs(t_cut - truth["t_cut_s"]) > PERIOD:
        errs.append("%s cut %s s vs truth %.4f s (tol %.3f s)" % (name, t_cut, truth["t_cut_s"],
                                                                   PERIOD))
    if t_stop is None or not math.isfinite(t_stop) or abs(t_stop - truth["t_stop_s"]) > STOP_TOL:
        errs.append("%s stop %s s vs truth %.4f s (tol %.3f s)" % (name, t_stop,
                                                                    truth["t_stop_s"], STOP_TOL))
    return errs


def model(run, name):
    for m in run.get("models", []):
        if m.get("name") == name:
            return m
    return None


# ---------------------------------------------------------------- path (a): fit, explain
r = run([os.path.join(BIN, "spindown"), "fit", "--json", LAB])
fit = None
try:
    fit = json.loads(r.stdout)["files"][0]["runs"]
except Exception as e:  # noqa: BLE001
    fit_err = "spindown fit --json: rc %s, no JSON (%s)" % (r.returncode, e)
r = run([os.path.join(BIN, "spindown"), "explain", "--json", LAB])
exp = None
try:
    exp = json.loads(r.stdout)["files"][0]["runs"]
except Exception as e:  # noqa: BLE001
    exp_err = "spindown explain --json: rc %s, no JSON (%s)" % (r.returncode, e)

# W1: spindown fit finds the true run and leaves the 7 dropouts out
case = "W1-fit-run-and-dropouts"
if fit is None:
    report(case, False, fit_err)
else:
    errs = []
    if len(fit) != 1:
        errs.append("%d runs vs truth 1" % len(fit))
    f = fit[0]
    errs += check_run_times("fit", f.get("t_cut_s"), f.get("t_stop_s"))
    n_win, o_win = window_truth(f.get("t_cut_s", 0), f.get("t_end_s", 0))
    comb = model(f, "combined") or {}
    if comb.get("n") != n_win - o_win:
        errs.append("combined fitted %s samples vs truth %d (%d in its window %s..%s s less %d "
                    "dropouts)" % (comb.get("n"), n_win - o_win, n_win, f.get("t_cut_s"),
                                   f.get("t_end_s"), o_win))
    if f.get("samples") != n_win:
        errs.append("run samples %s vs %d in its window" % (f.get("samples"), n_win))
    if not (comb.get("rmse") is not None and comb["rmse"] <= RMSE_BOUND):
        errs.append("combined RMSE %s V vs bound %.4f V (truth-curve RMSE %.4f V without the "
                    "dropouts, %.4f V with them)" % (comb.get("rmse"), RMSE_BOUND, RMSE_CLEAN,
                                                     RMSE_DIRTY))
    p = comb.get("params", {})
    for k in ("c3", "c4"):
        v = p.get(k, {})
        if not (v.get("value") is not None and abs(v["value"] - truth[k]) <= 4 * v["stderr"]):
            errs.append("%s %s ± %s vs truth %g (4 sd)" % (k, v.get("value"), v.get("stderr"),
                                                           truth[k]))
    if f.get("best") != "combined":
        errs.append("best %s vs truth combined" % f.get("best"))
    report(case, not errs, "; ".join(errs) if errs else
           "cut %.3f s (truth %.3f), stop %.3f s (truth %.3f), %d samples fitted = %d in window "
           "- %d dropouts, combined RMSE %.5f V <= %.5f V, c3 %.4g c4 %.4g (truth %.4g %.4g)" % (
               f["t_cut_s"], truth["t_cut_s"], f["t_stop_s"], truth["t_stop_s"], comb["n"],
               n_win, o_win, comb["rmse"], RMSE_BOUND, p["c3"]["value"], p["c4"]["value"],
               truth["c3"], truth["c4"]))

# W2: spindown explain sees fit's window: same run, same samples, base = fit's viscous
case = "W2-explain-same-window-as-fit"
if fit is None or exp is None:
    report(case, False, fit_err if fit is None else exp_err)
else:
    errs = []
    f, e = fit[0], (exp[0] if exp else {})
    if len(exp) != len(fit):
        errs.append("explain %d runs vs fit %d" % (len(exp), len(fit)))
    for k in ("t_cut_s", "t_stop_s"):
        if e.get(k) is None or abs(e[k] - f[k]) > PERIOD:
            errs.append("explain %s %s vs fit %s" % (k, e.get(k), f[k]))
    visc, comb = model(f, "viscous") or {}, model(f, "combined") or {}
    if e.get("samples") != comb.get("n"):
        errs.append("explain samples %s vs fit's fitted %s" % (e.get("samples"), comb.get("n")))
    if rel(e.get("rmse_base"), visc.get("rmse")) > 1e-6:
        errs.append("base RMSE %s vs fit viscous %s" % (e.get("rmse_base"), visc.get("rmse")))
    for k in ("c1", "omega0"):
        a = (e.get("base_params") or {}).get(k, {}).get("value")
        b = visc.get("params", {}).get(k, {})
        if not close_param(a, b.get("value"), b.get("stderr")):
            errs.append("base %s %s vs fit viscous %s ± %s" % (k, a, b.get("value"),
                                                               b.get("stderr")))
    if e.get("final_model") == "combined":
        for k in ("c3", "c4", "omega0"):
            a = (e.get("final_params") or {}).get(k, {}).get("value")
            b = comb.get("params", {}).get(k, {})
            if not close_param(a, b.get("value"), b.get("stderr")):
                errs.append("final %s %s vs fit combined %s ± %s" % (k, a, b.get("value"),
                                                                     b.get("stderr")))
    else:
        errs.append("final model %s vs truth combined" % e.get("final_model"))
    if not (e.get("rmse_final") is not None and e["rmse_final"] <= RMSE_BOUND):
        errs.append("final RMSE %s V vs bound %.4f V" % (e.get("rmse_final"), RMSE_BOUND))
    if rel(e.get("reading_noise"), f.get("reading_noise")) > 1e-6:
        errs.append("reading noise %s vs fit %s" % (e.get("reading_noise"),
                                                     f.get("reading_noise")))
    report(case, not errs, "; ".join(errs) if errs else
           "explain: cut %.3f stop %.3f, %d samples, base RMSE %.6g V = fit viscous %.6g V, final "
           "%s RMSE %.5g V" % (e["t_cut_s"], e["t_stop_s"], e["samples"], e["rmse_base"],
                               visc["rmse"], e["final_model"], e["rmse_final"]))

# ---------------------------------------------------------------- path (b): the live lab
live_dir = os.path.join(TMP, "live")
os.makedirs(live_dir, exist_ok=True)
ns = ["unshare", "-n"] if os.geteuid() == 0 else ["unshare", "-r", "-n"]
t0 = time.monotonic()
lr = run(ns + [PY, os.path.join(HERE, "live.py"), BIN, os.path.join(TMP, "lab-run.lines.json"),
               live_dir, str(SPEED)], timeout=150)
live = {}
try:
    live = json.load(open(os.path.join(live_dir, "live.json")))
except Exception:  # noqa: BLE001
    live = {"errors": ["live.py: rc %s %s" % (lr.returncode, lr.stderr.decode(errors="replace")
                                              [-400:])]}
LOG = live.get("log")
live_fit = live_exp = None
live_samples = None
decode_err = None
pydir = os.path.join(os.path.dirname(BIN), "python")
if LOG:
    code = r"""
import json, sys, math
import spindown_log
log = spindown_log.SpindownLog(sys.argv[1])
def plain(v):
    if isinstance(v, (list, tuple)): return [plain(x) for x in v]
    if isinstance(v, float) and not math.isfinite(v): return None
    if isinstance(v, (bytes,)): return v.decode('latin-1')
    if isinstance(v, (int, float, str, bool)) or v is None: return v
    try: return [plain(x) for x in v]
    except TypeError: return str(v)
out = {"FIT": [], "EXPLAIN": [], "RUN": []}
for m in log.messages(kinds={"FIT", "EXPLAIN", "RUN"}):
    if m.bench != sys.argv[2]: continue
    out[m.kind].append({k: plain(getattr(m.message, k)) for k in m.message.__slots__})
s = log.samples().get(sys.argv[2])
out["samples"] = len(s.value) if s is not None else 0
print(json.dumps(out))
"""
    d = run([PY, "-c", code, LOG, BENCH], env=dict(os.environ, PYTHONPATH=pydir))
    try:
        dec = json.loads(d.stdout)
        live_fit = dec["FIT"][-1] if dec["FIT"] else None
        live_exp = dec["EXPLAIN"][-1] if dec["EXPLAIN"] else None
        live_samples = dec["samples"]
        n_fit, n_exp = len(dec["FIT"]), len(dec["EXPLAIN"])
    except Exception as e:  # noqa: BLE001
        decode_err = "cannot decode the log with %s/spindown_log: %s %s" % (
            pydir, e, d.stderr.decode(errors="replace")[-300:])
live_problem = (decode_err or "; ".join(live.get("errors", [])) or
                ("no log written" if not LOG else None))

# L1: the live FIT sees the same run and samples as spindown fit
case = "L1-live-fit-equals-fit"
if live_fit is None or fit is None:
    report(case, False, "no live FIT for %s in the log (%s; channels %s)" % (
        BENCH, live_problem, live.get("channels")) if live_fit is None else fit_err)
else:
    errs = []
    f = fit[0]
    if n_fit != 1:
        errs.append("%d live FIT messages vs truth 1 run" % n_fit)
    if live_samples != len(valid):
        errs.append("the log holds %s samples vs %d in the recording" % (live_samples,
                                                                           len(valid)))
    for k in ("t_cut_s", "t_stop_s", "t_end_s"):
        if live_fit.get(k) is None or abs(live_fit[k] - f[k]) > PERIOD:
            errs.append("live %s %s vs fit %s" % (k, live_fit.get(k), f[k]))
    errs += check_run_times("live", live_fit.get("t_cut_s"), live_fit.get("t_stop_s"))
    if live_fit.get("samples") != f.get("samples"):
        errs.append("live samples %s vs fit %s" % (live_fit.get("samples"), f.get("samples")))
    names = live_fit.get("model") or []
    for i, nm in enumerate(names):
        m = model(f, nm)
        if m is None:
            errs.append("live model %s not in fit" % nm)
            continue
        ms = (live_fit.get("model_samples") or [None] * len(names))[i]
        if ms != m.get("n"):
            errs.append("%s fitted %s samples live vs %s in fit" % (nm, ms, m.get("n")))
        if rel(live_fit["rmse"][i], m["rmse"]) > 1e-6:
            errs.append("%s RMSE live %s vs fit %s" % (nm, live_fit["rmse"][i], m["rmse"]))
        for j, pm in enumerate(live_fit.get("param_model", [])):
            if pm != i:
                continue
            pn = live_fit["param_name"][j]
            b = m["params"].get(pn, {})
            if not close_param(live_fit["param_value"][j], b.get("value"), b.get("stderr")):
                errs.append("%s %s live %s vs fit %s" % (nm, pn, live_fit["param_value"][j],
                                                         b.get("value")))
    if set(names) != {m["name"] for m in f["models"]}:
        errs.append("live models %s vs fit %s" % (names, [m["name"] for m in f["models"]]))
    report(case, not errs, "; ".join(errs) if errs else
           "live FIT cut %.3f stop %.3f end %.3f, %s samples, model samples %s, RMSEs %s = fit's"
           % (live_fit["t_cut_s"], live_fit["t_stop_s"], live_fit["t_end_s"],
              live_fit["samples"], live_fit["model_samples"],
              ["%.5g" % x for x in live_fit["rmse"]]))


def story_samples(story):
    m = re.search(r"(\d+)\s+samples", story or "")
    return int(m.group(1)) if m else None


def story_base_c1(story):
    """c1 = (9.09 ± 0.23)e-07 under 'base model' in the story: (value, half a printed digit)."""
    i = (story or "").find("base model")
    if i < 0:
        return None
    m = re.search(r"c1 = \(([0-9.]+) ± [0-9.]+\)e([-+]?\d+)", story[i:])
    if not m:
        return None
    mant, ex = m.group(1), int(m.group(2))
    dec = len(mant.split(".")[1]) if "." in mant else 0
    return float(mant) * 10 ** ex, 0.5 * 10 ** (ex - dec)


# L2: the live EXPLAIN is spindown explain's (the bug: dropouts fitted live)
case = "L2-live-explain-equals-explain"
if live_exp is None or exp is None:
    report(case, False, "no live EXPLAIN for %s in the log (%s; channels %s)" % (
        BENCH, live_problem, live.get("channels")) if live_exp is None else exp_err)
else:
    errs = []
    e = exp[0]
    if n_exp != 1:
        errs.append("%d live EXPLAIN messages vs truth 1 run" % n_exp)
    # the samples: a field of the message if it has one, else the story's "N samples"
    ls = None
    for k, v in live_exp.items():
        if k in ("samples", "nsamples", "samples_fitted") and isinstance(v, int):
            ls = v
    if ls is None:
        ls = story_samples(live_exp.get("story"))
    if ls != e.get("samples"):
        errs.append("live EXPLAIN samples %s vs spindown explain %s" % (ls, e.get("samples")))
    for k in ("rmse_base", "rmse_final"):
        if rel(live_exp.get(k), e.get(k)) > 1e-6:
            errs.append("%s live %.6g V vs explain %.6g V" % (k, live_exp.get(k) or float("nan"),
                                                               e.get(k) or float("nan")))
    if rel(live_exp.get("noise_level"), e.get("reading_noise")) > 1e-6:
        errs.append("reading noise live %s vs explain %s" % (live_exp.get("noise_level"),
                                                              e.get("reading_noise")))
    if list(live_exp.get("base") or []) != list(e.get("base") or []):
        errs.append("base live %s vs explain %s" % (live_exp.get("base"), e.get("base")))
    if list(live_exp.get("final_effects") or []) != list(e.get("final") or []):
        errs.append("final live %s vs explain %s" % (live_exp.get("final_effects"),
                                                      e.get("final")))
    fp = e.get("final_params") or {}
    for j, pn in enumerate(live_exp.get("param_name") or []):
        b = fp.get(pn, {})
        if not close_param(live_exp["param_value"][j], b.get("value"), b.get("stderr")):
            errs.append("final %s live %.5g vs explain %s ± %s" % (
                pn, live_exp["param_value"][j], b.get("value"), b.get("stderr")))
    sc = story_base_c1(live_exp.get("story"))
    bc = (e.get("base_params") or {}).get("c1", {}).get("value")
    if sc is not None and bc is not None and abs(sc[0] - bc) > sc[1] * 1.0001:
        errs.append("base c1 live %.4g (story) vs explain %.4g" % (sc[0], bc))
    if not (live_exp.get("rmse_final") is not None and live_exp["rmse_final"] <= RMSE_BOUND):
        errs.append("live final RMSE %s V vs bound %.4f V: the dropouts were fitted" % (
            live_exp.get("rmse_final"), RMSE_BOUND))
    report(case, not errs, "; ".join(errs) if errs else
           "live EXPLAIN %s samples, base RMSE %.6g V, final RMSE %.5g V, sigma %.4g V = "
           "spindown explain's" % (ls, live_exp["rmse_base"], live_exp["rmse_final"],
                                   live_exp["noise_level"]))

# ---------------------------------------------------------------- path (c): refit of the log
refit = None
refit_doc = None
refit_err = "no log"
if LOG:
    rr = run([os.path.join(BIN, "spindown"), "refit", "--json", LOG])
    try:
        refit_doc = json.loads(rr.stdout)
        refit = [x for fl in refit_doc["files"] for x in fl["runs"]]
    except Exception as ex:  # noqa: BLE001
        refit_err = "refit --json: rc %s, no JSON (%s)" % (rr.returncode, ex)

case = "R1-refit-equals-live-fit"
if refit is None or live_fit is None:
    report(case, False, refit_err if refit is None else "no live FIT (%s)" % live_problem)
else:
    errs = []
    if len(refit) != 1:
        errs.append("refit %d runs vs 1" % len(refit))
    q = refit[0] if refit else {}
    for k in ("t_cut_s", "t_stop_s", "t_end_s"):
        if rel(q.get(k), live_fit.get(k)) > 1e-9:
            errs.append("%s refit %s vs live %s" % (k, q.get(k), live_fit.get(k)))
    if q.get("samples") != live_fit.get("samples"):
        errs.append("samples refit %s vs live %s" % (q.get("samples"), live_fit.get("samples")))
    for i, nm in enumerate(live_fit.get("model") or []):
        m = model(q, nm) or {}
        if m.get("n") != live_fit["model_samples"][i]:
            errs.append("%s n refit %s vs live %s" % (nm, m.get("n"),
                                                      live_fit["model_samples"][i]))
        if rel(m.get("rmse"), live_fit["rmse"][i]) > 1e-9:
            errs.append("%s RMSE refit %s vs live %s" % (nm, m.get("rmse"), live_fit["rmse"][i]))
        for j, pm in enumerate(live_fit["param_model"]):
            if pm == i:
                pn = live_fit["param_name"][j]
                a = m.get("params", {}).get(pn, {}).get("value")
                if rel(a, live_fit["param_value"][j]) > 1e-9:
                    errs.append("%s %s refit %s vs live %s" % (nm, pn, a,
                                                               live_fit["param_value"][j]))
    report(case, not errs, "; ".join(errs) if errs else
           "refit run: cut %.3f stop %.3f, %d samples, every model's n, RMSE and parameters = "
           "the live FIT's (1e-9)" % (q["t_cut_s"], q["t_stop_s"], q["samples"]))


def find_explain(obj, depth=0):
    """The explain result in a refit run: any nested object with explain's rmse_base."""
    if depth > 6:
        return None
    if isinstance(obj, dict):
        if "rmse_base" in obj and "rmse_final" in obj:
            return obj
        for v in obj.values():
            x = find_explain(v, depth + 1)
            if x is not None:
                return x
    elif isinstance(obj, list):
        for v in obj:
            x = find_explain(v, depth + 1)
            if x is not None:
                return x
    return None


refit_flag = ""
if refit is not None and LOG and find_explain(refit_doc) is None:
    # an option of refit's own that asks for EXPLAIN (e.g. --explain), if its --help names one
    hr = run([os.path.join(BIN, "spindown"), "refit", "--help"])
    flags = [fl for fl in re.findall(r"(--[a-z][a-z-]*)", hr.stdout.decode(errors="replace"))
             if "explain" in fl and not fl.startswith("--no-")]
    if flags:
        refit_flag = flags[0]
        rr2 = run([os.path.join(BIN, "spindown"), "refit", "--json", refit_flag, LOG])
        try:
            refit_doc = json.loads(rr2.stdout)
            refit = [x for fl in refit_doc["files"] for x in fl["runs"]]
        except Exception:  # noqa: BLE001
            pass

case = "R2-refit-reproduces-live-explain"
if refit is None or live_exp is None:
    report(case, False, refit_err if refit is None else "no live EXPLAIN (%s)" % live_problem)
else:
    errs = []
    x = find_explain(refit[0] if refit else {}) or find_explain(refit_doc)
    if x is None:
        errs.append("refit --json's run holds no EXPLAIN (no object with rmse_base/rmse_final; "
                    "keys %s)" % sorted((refit[0] if refit else {}).keys()))
    else:
        for k in ("rmse_base", "rmse_final"):
            if rel(x.get(k), live_exp.get(k)) > 1e-9:
                errs.append("%s refit %s vs live %s" % (k, x.get(k), live_exp.get(k)))
        fin = x.get("final") or x.get("final_effects")
        if list(fin or []) != list(live_exp.get("final_effects") or []):
            errs.append("final refit %s vs live %s" % (fin, live_exp.get("final_effects")))
        fp = x.get("final_params") or x.get("params") or {}
        for j, pn in enumerate(live_exp.get("param_name") or []):
            a = fp.get(pn, {}).get("value") if isinstance(fp.get(pn), dict) else fp.get(pn)
            if rel(a, live_exp["param_value"][j]) > 1e-9:
                errs.append("final %s refit %s vs live %s" % (pn, a, live_exp["param_value"][j]))
    report(case, not errs, "; ".join(errs) if errs else
           "refit%s's EXPLAIN: base RMSE %.6g, final RMSE %.6g, final params = the live "
           "EXPLAIN's" % (" " + refit_flag if refit_flag else "", x["rmse_base"],
                          x["rmse_final"]))

case = "R3-refit-compare-covers-explain"
if not LOG:
    report(case, False, "no log (%s)" % live_problem)
else:
    rc = run([os.path.join(BIN, "spindown"), "refit", "--compare", LOG])
    text = (rc.stdout + rc.stderr).decode(errors="replace")
    errs = []
    if rc.returncode != 0:
        errs.append("exit %s vs 0" % rc.returncode)
    exp_lines = [ln for ln in text.splitlines() if re.search(r"explain", ln, re.I)]
    ident = [int(n) for ln in exp_lines for n in re.findall(r"(\d+)\s+identical", ln, re.I)]
    if not exp_lines or not ident or max(ident) < 1:
        errs.append("its report says nothing of EXPLAIN messages being identical (%r)" %
                    text.strip()[:300])
    if re.search(r"\b[1-9]\d*\s+(different|differ)", text, re.I):
        errs.append("a difference reported: %r" % text.strip()[:300])
    report(case, not errs, "; ".join(errs) if errs else
           "refit --compare exit 0, EXPLAIN covered: %r" % exp_lines[0].strip()[:200])

# ---------------------------------------------------------------- fit --json's size
many = sorted(os.path.join(TMP, "many", f) for f in os.listdir(os.path.join(TMP, "many")))
CONTRACT_RUN = ["run", "t_cut_s", "t_stop_s", "samples", "models", "best"]
DOC_RUN = ["best_reason", "doubts", "reading_step", "stopped", "end", "t_end_s", "lead_in",
           "zero_level", "noise_level", "reading_noise", "period_s", "quantity", "bench"]
CONTRACT_MODEL = ["name", "params", "rmse", "residual_unit", "r2", "aic", "bic"]
DOC_MODEL = ["reduced_chi2", "correlation"]
CONTRACT_PARAM = ["value", "stderr", "unit"]
DOC_PARAM = ["ci95", "bench_stderr", "total_stderr"]
CONTRACT_FILE = ["file", "runs"]
DOC_FILE = ["samples_read", "lines_read", "lines_skipped", "diagnostics", "failures"]
BOUND_PER_RUN = 6000
rp = run([os.path.join(BIN, "spindown"), "fit", "--json"] + many, timeout=120)
piped = rp.stdout
case = "J1-fit-json-compact-when-piped"
try:
    doc = json.loads(piped)
except Exception as ex:  # noqa: BLE001
    doc = None
    report(case, False, "spindown fit --json of %d files: rc %s, not JSON (%s)" % (
        len(many), rp.returncode, ex))
if doc is not None:
    errs = []
    files = doc.get("files", [])
    nruns = sum(len(fl.get("runs", [])) for fl in files)
    if len(files) != len(many) or nruns != len(many):
        errs.append("%d files, %d runs vs %d of each" % (len(files), nruns, len(many)))
    indented = [ln for ln in piped.split(b"\n") if ln[:1] in (b" ", b"\t")]
    if indented:
        errs.append("%d indented lines (e.g. %r)" % (len(indented), indented[0][:40]))
    compact = len(json.dumps(doc, separators=(",", ":"), ensure_ascii=False).encode())
    if len(piped) > 1.02 * compact + 2:
        errs.append("%d bytes vs %d for the same object without whitespace (+%.0f %%)" % (
            len(piped), compact, 100.0 * (len(piped) / compact - 1)))
    per_run = len(piped) / max(nruns, 1)
    if per_run > BOUND_PER_RUN:
        errs.append("%.0f bytes per run vs bound %d" % (per_run, BOUND_PER_RUN))
    missing = set()
    if "files" not in doc:
        missing.add("files")
    for fl in files:
        missing |= {"file." + k for k in CONTRACT_FILE + DOC_FILE if k not in fl}
        for ru in fl.get("runs", []):
            missing |= {"run." + k for k in CONTRACT_RUN + DOC_RUN if k not in ru}
            for m in ru.get("models", []):
                missing |= {"model." + k for k in CONTRACT_MODEL + DOC_MODEL if k not in m}
                for pn, pv in m.get("params", {}).items():
                    missing |= {"param." + k for k in CONTRACT_PARAM + DOC_PARAM if k not in pv}
    if missing:
        errs.append("documented keys missing: %s" % sorted(missing))
    report(case, not errs, "; ".join(errs) if errs else
           "%d runs, %d bytes (%.0f B/run <= %d), no indentation, every documented key present"
           % (nruns, len(piped), per_run, BOUND_PER_RUN))

# J2: on a terminal the same JSON is indented for a reader
case = "J2-fit-json-indented-on-terminal"
out = b""
try:
    pid, fd = pty.fork()
    if pid == 0:
        try:
            os.execv(os.path.join(BIN, "spindown"), ["spindown", "fit", "--json", many[0]])
        finally:
            os._exit(127)
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline:
        rdy, _, _ = select.select([fd], [], [], 1.0)
        if rdy:
            try:
                chunk = os.read(fd, 65536)
            except OSError:
                break
            if not chunk:
                break
            out += chunk
    try:
        os.kill(pid, 9)
    except OSError:
        pass
    os.waitpid(pid, 0)
    os.close(fd)
except Exception as ex:  # noqa: BLE001
    out = b""
    report(case, False, "cannot run on a pty: %s" % ex)
if out:
    # the terminal's stdout and stderr are one: keep from the first '{' to the matching end
    txt = out.replace(b"\r\n", b"\n").decode(errors="replace")
    i = txt.find("{")
    j = txt.rfind("}")
    errs = []
    try:
        tdoc = json.loads(txt[i:j + 1])
    except Exception as ex:  # noqa: BLE001
        tdoc = None
        errs.append("not JSON on a terminal (%s)" % ex)
    rp1 = run([os.path.join(BIN, "spindown"), "fit", "--json", many[0]])
    try:
        pdoc = json.loads(rp1.stdout)
    except Exception:  # noqa: BLE001
        pdoc = None
    if tdoc is not None and tdoc != pdoc:
        errs.append("the terminal's JSON is not the piped JSON's object")
    ind = [ln for ln in txt[i:j + 1].split("\n") if ln[:1] in (" ", "\t")]
    if len(ind) < 10:
        errs.append("%d indented lines on a terminal (expected an indented document)" % len(ind))
    report(case, not errs, "; ".join(errs) if errs else
           "%d indented lines on a terminal, same object as piped" % len(ind))

print("SUMMARY: %d/%d passed" % (sum(results), len(results)))
sys.exit(0 if all(results) else 1)
