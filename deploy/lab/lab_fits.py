#!/usr/bin/env python3
"""The live lab's fits, side by side with the refit of its log and with the virtual benches' truth.

usage:
  lab_fits.py compare LIVE.json REFIT.json [BENCH=TRUTH.json ...]
      LIVE.json  = `spindown refit LOG --live --json` (the FIT messages recorded in the log)
      REFIT.json = `spindown refit LOG --json`
      Prints, per bench and run, the best model and the combined model's c3, c4 (lab units)
      live / refit / truth; exit 0 when every live result equals its refit (timing fields
      latency_s and utime aside), 1 otherwise.
  lab_fits.py check-runs LIVE.json [--cut-tolerance S] BENCH=TRUTH.json ...
      Every run a virtual bench sent (its --truth file) has exactly one live fit whose cut is
      within S seconds (default 0.2) of the true cut; exit 1 naming what is missing or extra.
"""
import json
import math
import sys

LAB_PER_SI = 1e7  # g·cm² units per SI (kg·m² = 1e7 g·cm²)
TIMING = ("latency_s", "utime")


def strip_timing(j):
    if isinstance(j, dict):
        return {k: strip_timing(v) for k, v in j.items() if k not in TIMING}
    if isinstance(j, list):
        return [strip_timing(v) for v in j]
    return j


def runs_of(path):
    with open(path) as f:
        doc = json.load(f)
    runs = {}
    for file in doc.get("files", []):
        for r in file.get("runs", []):
            runs.setdefault((r["bench"]["id"], r["run"]), []).append(r)
    return runs


def value_error(v, e):
    """'1.822 ± 0.011' with the error to two significant digits."""
    if v is None or not math.isfinite(v):
        return "-"
    if e is None or not math.isfinite(e) or e <= 0:
        return f"{v:.4g}"
    decimals = max(0, 1 - math.floor(math.log10(e)))
    return f"{v:.{decimals}f} ± {e:.{decimals}f}"


def param(run, model, name):
    for m in run.get("models", []):
        if m["name"] == model and name in m.get("params", {}):
            p = m["params"][name]
            v, e = p.get("value"), p.get("stderr")
            return (v * LAB_PER_SI if v is not None else None, e * LAB_PER_SI if e is not None else None)
    return (None, None)


def truths(args):
    out = {}
    for a in args:
        bench, _, path = a.partition("=")
        with open(path) as f:
            out[bench] = json.load(f)
    return out


def compare(live_path, refit_path, truth_args):
    live, refit = runs_of(live_path), runs_of(refit_path)
    truth = truths(truth_args)
    rows = [("bench", "run", "best model", "coefficient", "live fit", "refit of the log", "truth", "same")]
    same = differ = 0
    for key in sorted(set(live) | set(refit)):
        bench, run = key
        l, r = live.get(key, []), refit.get(key, [])
        equal = len(l) == 1 and len(r) == 1 and strip_timing(l[0]) == strip_timing(r[0])
        same += equal
        differ += not equal
        shown = (l or r)[0]
        t = truth.get(bench)
        for i, (name, unit, tkey) in enumerate((("c3", "g·cm²·s⁻¹", "c_v"), ("c4", "g·cm²·rad·s⁻²", "c_c"))):
            lv = value_error(*param(l[0], "combined", name)) if l else "(none)"
            rv = value_error(*param(r[0], "combined", name)) if r else "(none)"
            tv = f"{t[tkey] * LAB_PER_SI:.5g}" if t and tkey in t else "-"
            rows.append((bench if i == 0 else "", str(run) if i == 0 else "", (shown.get("best") or "none") if i == 0 else "",
                         f"{name} {unit}", lv, rv, tv, ("yes" if equal else "NO") if i == 0 else ""))
    widths = [max(len(row[c]) for row in rows) for c in range(len(rows[0]))]
    for row in rows:
        print("  " + "  ".join(cell.ljust(w) for cell, w in zip(row, widths)).rstrip())
    print(f"  (combined model c3·ω + c4; truth = the virtual bench's viscous and Coulomb coefficients)")
    return same, differ


def check_runs(live_path, truth_args, cut_tolerance_s=0.2):
    live = runs_of(live_path)
    fits = {}
    for (bench, _), rs in live.items():
        fits.setdefault(bench, []).extend(rs)
    problems = []
    for bench, t in truths(truth_args).items():
        got = list(fits.get(bench, []))
        worst = 0.0
        for tr in t["runs"]:
            # The cut the readings show: a floating pin's connection, else the power cut.
            cut = tr.get("connect_device_us", tr["cut_device_us"]) / 1e6
            match = [f for f in got if f.get("t_cut_s") is not None and abs(f["t_cut_s"] - cut) < cut_tolerance_s]
            if len(match) != 1:
                problems.append(f"{bench}: run {tr['run']} (cut at {cut:.3f} s): {len(match)} fits")
                continue
            worst = max(worst, abs(match[0]["t_cut_s"] - cut))
            got.remove(match[0])
        for f in got:
            problems.append(f"{bench}: fit of run {f['run']} (cut {f.get('t_cut_s')}) matches no run the bench sent")
        sent = len(t["runs"])
        print(f"{bench}: {sent} run{'' if sent == 1 else 's'} sent, {len(fits.get(bench, []))} fitted live; "
              f"cuts within {1e3 * worst:.0f} ms of the truth")
    for p in problems:
        print("  MISSING/EXTRA: " + p)
    return not problems


def main(argv):
    if len(argv) >= 3 and argv[0] == "compare":
        same, differ = compare(argv[1], argv[2], argv[3:])
        return 0 if differ == 0 and same > 0 else 1
    if len(argv) >= 3 and argv[0] == "check-runs":
        rest, tolerance = argv[2:], 0.2
        if len(rest) >= 2 and rest[0] == "--cut-tolerance":
            tolerance, rest = float(rest[1]), rest[2:]
        return 0 if check_runs(argv[1], rest, tolerance) else 1
    print(__doc__, file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
