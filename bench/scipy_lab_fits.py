#!/usr/bin/python3
"""The lab's own analysis, as a student would write it with Debian's python3-scipy, for the
side-by-side with `spindown fit` (bench/fit_vs_scipy.sh) and the Monte Carlo study
(bench/monte_carlo.sh).

usage:
  scipy_lab_fits.py fit DIR        fits every file named in DIR/index.tsv (written by make_runs or
                                   monte_carlo); one TSV row per file on stdout, timings on stderr
  scipy_lab_fits.py mc-summary DIR bias, spread, efficiency and stderr calibration from
                                   DIR/spindown.tsv, DIR/scipy.tsv and DIR/crb.json (and
                                   DIR/spindown-unweighted.tsv when there)

The fits are the lab's three seed curves (design §1), each with scipy.optimize.curve_fit on the
samples between the cut and the stop, both given for free from index.tsv (the lab chose them by
eye): viscous y = A e^(−Bx) (c1 = B·J), Coulomb y = Ax + B (c2 = −A·J/K_b), combined
y = A + B e^(Cx) (c3 = −C·J, c4 = A·C·J/K_b); x is seconds since the cut. Starting points are
the lab's hand values (they had to fix A by hand for the exponential fit).
"""
import json
import math
import os
import sys
import time

T_START = time.perf_counter()

import numpy as np  # noqa: E402  (imports are timed as part of the process)
from scipy.optimize import curve_fit  # noqa: E402

T_IMPORTED = time.perf_counter()


def viscous(x, a, b):
    return a * np.exp(-b * x)


def coulomb(x, a, b):
    return a * x + b


def combined(x, a, b, c):
    return a + b * np.exp(c * x)


def read_index(directory):
    rows = []
    with open(f"{directory}/index.tsv") as f:
        header = f.readline().rstrip("\n").split("\t")
        for line in f:
            cells = line.rstrip("\n").split("\t")
            row = dict(zip(header, cells))
            for k in header[1:]:
                row[k] = float(row[k])
            rows.append(row)
    return rows


def read_file(path):
    return np.loadtxt(path, skiprows=1)  # the PuTTY header line, then millis<TAB>volts


def fit_one(data, t_cut, t_stop, J, Kb):
    """The three lab fits of one file's data; returns ([c1, c2, c3, c4, se3, se4], ok)."""
    t = data[:, 0] / 1000.0
    y = data[:, 1]
    coast = (t >= t_cut) & (t < t_stop)
    x, y = t[coast] - t_cut, y[coast]
    y0 = y[0]
    out = [math.nan] * 6
    ok = True
    try:
        (a, b), _ = curve_fit(viscous, x, y, p0=(y0, 0.1))
        out[0] = b * J
    except RuntimeError:
        ok = False
    try:
        (a, b), _ = curve_fit(coulomb, x, y, p0=(-0.1, y0))
        out[1] = -a * J / Kb
    except RuntimeError:
        ok = False
    try:
        (a, b, c), cov = curve_fit(combined, x, y, p0=(-5.0, y0 + 5.0, -0.016))
        out[2] = -c * J
        out[3] = a * c * J / Kb
        # Standard errors by the delta method from curve_fit's covariance.
        g3 = np.array([0.0, 0.0, -J])
        g4 = np.array([c * J / Kb, 0.0, a * J / Kb])
        out[4] = math.sqrt(g3 @ cov @ g3)
        out[5] = math.sqrt(max(g4 @ cov @ g4, 0.0))
    except RuntimeError:
        ok = False
    return out, ok


def cmd_fit(directory):
    rows = read_index(directory)
    read_s = fit_s = 0.0
    failed = 0
    print("file\tc1\tc2\tc3\tc4\tse3\tse4")
    for r in rows:
        t0 = time.perf_counter()
        data = read_file(f"{directory}/{r['file']}")
        t1 = time.perf_counter()
        out, ok = fit_one(data, r["t_cut_s"], r["t_stop_s"], r["J"], r["Kb"])
        read_s += t1 - t0
        fit_s += time.perf_counter() - t1
        failed += not ok
        print(r["file"] + "\t" + "\t".join(f"{v:.9g}" for v in out))
    sys.stdout.flush()
    print(json.dumps({
        "files": len(rows), "failed": failed,
        "import_s": round(T_IMPORTED - T_START, 4),
        "read_s": round(read_s, 4),
        "fit_s": round(fit_s, 4),
    }), file=sys.stderr)
    return 0 if failed == 0 else 1


def stats(values):
    v = np.asarray([x for x in values if math.isfinite(x)])
    return v, float(np.mean(v)), float(np.std(v, ddof=1))


def cmd_mc_summary(directory):
    def load(name):
        with open(f"{directory}/{name}") as f:
            header = f.readline().rstrip("\n").split("\t")
            return {c[0]: dict(zip(header[1:], map(float, c[1:])))
                    for c in (line.rstrip("\n").split("\t") for line in f)}
    ours, theirs = load("spindown.tsv"), load("scipy.tsv")
    estimators = [("spindown", ours)]
    if os.path.exists(f"{directory}/spindown-unweighted.tsv"):
        estimators.append(("spindown unweighted", load("spindown-unweighted.tsv")))
    estimators.append(("SciPy curve_fit", theirs))
    with open(f"{directory}/crb.json") as f:
        crb = json.load(f)
    common = sorted(set.intersection(*(set(data) for _, data in estimators)))
    truth = {"c3": crb["c_v"], "c4": crb["c_c"]}
    bits, decimals = crb.get("adc_bits", 10), crb.get("decimals", 2)
    adc = f"{bits}-bit ADC" if bits > 0 else "no ADC"
    printed = f"{decimals} decimals" if decimals >= 0 else "full precision"
    print(f"Monte Carlo: {len(common)} runs in both ({len(ours)} spindown, {len(theirs)} SciPy); "
          f"truth c_v = {crb['c_v']:.6g} N·m·s/rad, c_c = {crb['c_c']:.6g} N·m; "
          f"reading error (white {1e3 * crb['noise_v']:.1f} mV, {100 * crb['ripple']:.0f} % ripple, {adc}, {printed}) "
          f"measured: RMS {1e3 * crb['sigma_eff_v']:.2f} mV, σ²(u) = α + β·u² with "
          f"√α = {1e3 * crb['sigma_at_zero_v']:.2f} mV, √(2β) = {100 * math.sqrt(2 * max(crb['sigma2_beta'], 0)):.2f} %")
    hdr = ("coef", "estimator", "bias", "bias/sd", "sd", "CRB sd", "efficiency", "CRB sd (flat σ)", "mean stderr",
           "stderr/sd")
    table = []
    result = {}
    for coef, se in (("c3", "se3"), ("c4", "se4")):
        crb_sd = crb[f"crb_sd_{coef}"]
        for who, data in estimators:
            v, mean, sd = stats(data[k][coef] for k in common)
            _, mse, _ = stats(data[k][se] for k in common)
            bias = mean - truth[coef]
            eff = (crb_sd / sd) ** 2
            result[(coef, who)] = dict(bias=bias, sd=sd, eff=eff, se_ratio=mse / sd)
            table.append((coef, who, f"{bias / truth[coef] * 100:+.3f} %", f"{bias / sd:+.2f}",
                          f"{sd / truth[coef] * 100:.3f} %", f"{crb_sd / truth[coef] * 100:.3f} %",
                          f"{eff:.3f}", f"{crb[f'crb_flat_sd_{coef}'] / truth[coef] * 100:.3f} %",
                          f"{mse / truth[coef] * 100:.3f} %", f"{mse / sd:.3f}"))
    widths = [max(len(str(r[i])) for r in table + [hdr]) for i in range(len(hdr))]
    for row in [hdr] + table:
        print("  " + "  ".join(str(c).ljust(w) for c, w in zip(row, widths)).rstrip())
    print("  (bias, sd and stderr relative to the truth; efficiency = CRB variance / observed variance, with the "
          "bound for σ²(u); 'flat σ' = the bound for one constant σ = the RMS error)")
    return 0


def main(argv):
    if len(argv) == 3 and argv[1] == "fit":
        return cmd_fit(argv[2])
    if len(argv) == 3 and argv[1] == "mc-summary":
        return cmd_mc_summary(argv[2])
    print(__doc__, file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv))
