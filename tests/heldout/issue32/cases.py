#!/usr/bin/python3
"""Issue 32 held-out cases: generate inputs from physics, run spindown as a user would, judge.

usage: cases.py BIN_DIR SCRATCH_DIR [CASE_ID...]

Python 3 standard library only; fixed seeds; deterministic.  Truth and criteria: CASES.md.
"""
import json
import math
import os
import random
import re
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from phys import (Coast, friction, quantize, fit_combined, combined, combined_se,  # noqa: E402
                  stretch_stats, _solve3)

RPM = 2 * math.pi / 60.0          # rad/s per rpm
CASES = []


def case(fn):
    CASES.append(fn)
    return fn


# ------------------------------------------------------------------------------------ helpers

def jittered_times(t0, t1, fs, rnd, jitter_s=0.0):
    """A logger's sample times: nominal grid i/fs from t0, each stamped with a little jitter."""
    out = []
    n = int(round((t1 - t0) * fs))
    for i in range(n + 1):
        t = t0 + i / fs
        if jitter_s:
            t += rnd.uniform(-jitter_s, jitter_s)
        out.append(t)
    return out


def write(path, text, newline="\n", encoding="utf-8"):
    with open(path, "wb") as f:
        f.write(text.replace("\n", newline).encode(encoding))


def run_prog(args, timeout=30):
    t0 = time.time()
    try:
        p = subprocess.run(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, timeout=timeout)
        return p.returncode, p.stdout.decode("utf-8", "replace"), p.stderr.decode("utf-8", "replace"), time.time() - t0
    except subprocess.TimeoutExpired:
        return None, "", "timeout after %ds" % timeout, time.time() - t0


def load_json(out):
    try:
        return json.loads(out)
    except Exception:
        return None


def runs_of(js):
    try:
        return js["files"][0]["runs"] or []
    except Exception:
        return []


def model(run, name):
    for m in run.get("models", []) or []:
        if m.get("name") == name:
            return m
    return None


def param(run, mname, pname):
    m = model(run, mname)
    if not m:
        return None, None
    p = (m.get("params") or {}).get(pname)
    if not p:
        return None, None
    return p.get("value"), p.get("stderr")


def fmt_runs(runs):
    parts = []
    for r in runs:
        parts.append("run%s cut=%s stop=%s end=%s doubts=%d" % (
            r.get("run"), _f(r.get("t_cut_s")), _f(r.get("t_stop_s")), r.get("end"),
            len(r.get("doubts") or [])))
    return "[" + "; ".join(parts) + "]"


def _f(x, nd=3):
    if x is None:
        return "null"
    try:
        return ("%." + str(nd) + "f") % x
    except Exception:
        return str(x)


def fit_cmd(bindir, path, *opts):
    return [os.path.join(bindir, "spindown"), "fit", "--json"] + list(opts) + [path]


def explain_cmd(bindir, path, *opts):
    return [os.path.join(bindir, "spindown"), "explain", "--json"] + list(opts) + [path]


def judge_one_run(js, truth, period, tol_stop, extra=None):
    """Common detection judgement: exactly one run, cut within 2 periods, stopped, stop within
    tol_stop.  Returns (ok, message)."""
    runs = runs_of(js)
    msg = "runs=%d %s vs truth 1 run cut=%.3f stop=%.3f (tol cut %.3f s, stop %.3f s)" % (
        len(runs), fmt_runs(runs), truth["t_cut"], truth["t_stop"], 2 * period, tol_stop)
    if len(runs) != 1:
        return False, msg
    r = runs[0]
    tc, tsp = r.get("t_cut_s"), r.get("t_stop_s")
    if tc is None or abs(tc - truth["t_cut"]) > 2 * period + 1e-9:
        return False, msg
    if tsp is None or abs(tsp - truth["t_stop"]) > tol_stop + 1e-9:
        return False, msg
    if r.get("stopped") is False:
        return False, msg + " (not stopped)"
    return True, msg


# A powered phase followed by a free coast: speed(t) for the whole recording.
class Timeline:
    def __init__(self, powered, t_cut, coast):
        self.powered, self.t_cut, self.coast = powered, t_cut, coast

    def __call__(self, t):
        if t < self.t_cut:
            return self.powered(t)
        return self.coast(t - self.t_cut)

    @property
    def t_stop(self):
        return self.t_cut + self.coast.t_stop


# ============================================================================ point 1: short coasts

@case
def p1_fan_coast_10hz(ctx):
    """A 120 mm PC case fan, PWM cut: windage-dominated 3-s coast, tach logged at 10 Hz in 60-rpm
    steps."""
    cid = "p1_fan_coast_10hz"
    rnd = random.Random(3201)
    J, cw, cc = 3e-5, 2.12e-7, 7.54e-4
    w_top = 1800 * RPM
    t_on, t_cut, t_end, fs, q = 2.0, 8.05, 14.0, 10.0, 60.0
    co = Coast(J, friction(cc=cc, cw=cw), w_top, h=1e-4)

    def powered(t):
        return 0.0 if t < t_on else w_top * (1 - math.exp(-(t - t_on) / 0.6))
    tl = Timeline(powered, t_cut, co)
    lines = ["time_s,fan_rpm,pwm_pct"]
    for t in jittered_times(0.0, t_end, fs, rnd, 0.004):
        w = tl(t)
        rpm = 0.0 if w <= 0 else max(0.0, quantize(w / RPM + rnd.gauss(0, 0.3 * q), q))
        pwm = 100 if t_on <= t < t_cut else 0
        lines.append("%.3f,%d,%d" % (t, rpm, pwm))
    path = os.path.join(ctx["dir"], "fan_coast_10hz.csv")
    write(path, "\n".join(lines) + "\n")
    decel_stop = cc / J
    period = 1 / fs
    truth = {"t_cut": t_cut, "t_stop": tl.t_stop}
    tol_stop = 2 * period + (q / 2 + 3 * 0.3 * q) * RPM / decel_stop
    opts = ["--time-column", "time_s", "--value-column", "fan_rpm", "--time-unit", "s",
            "--value-unit", "rpm", "--inertia", "3e-5"]
    code, out, err, dt = run_prog(fit_cmd(ctx["bin"], path, *opts))
    ok, msg = judge_one_run(load_json(out), truth, period, tol_stop)
    ctx["p1_fan"] = (path, opts)
    return ok, "exit %s; %s" % (code, msg)


@case
def p1_fan_coast_explain_windage(ctx):
    """explain on the fan's coast names windage (T = c_w ω² dominates: c_w ω0² = 10 c_c)."""
    if "p1_fan" not in ctx:
        p1_fan_coast_10hz(ctx)
    path, opts = ctx["p1_fan"]
    code, out, err, dt = run_prog(explain_cmd(ctx["bin"], path, *opts))
    js = load_json(out)
    runs = runs_of(js)
    added = []
    for r in runs:
        added.append([s.get("added") for s in (r.get("steps") or [])])
    ok = len(runs) >= 1 and any("windage" in (a or []) for a in added)
    return ok, "exit %s; runs=%d, effects added per run %s vs truth: windage named (c_w = 2.12e-7 N·m·s²/rad², c_c = 7.54e-4 N·m)" % (code, len(runs), added)


@case
def p1_quad_prop_gate_tach_30hz(ctx):
    """A 5-inch quadcopter motor with its propeller on a test stand: 1.5-s coast from 2500 rad/s;
    an optical probe counts blade passes (2 blades) in a 1/30-s gate: 900-rpm steps (3.8 %)."""
    rnd = random.Random(3202)
    J, cw, cc = 2e-6, 4.06e-9, 8.46e-4
    w_top = 2500.0
    t_on, t_cut, t_end, fs = 1.0, 3.317, 6.5, 30.0
    gate, blades = 1.0 / fs, 2
    co = Coast(J, friction(cc=cc, cw=cw), w_top, h=2e-5)

    def powered(t):
        if t < t_on:
            return 0.0
        w = w_top * (1 - math.exp(-(t - t_on) / 0.08))
        return w * (1 + 0.004 * math.sin(2 * math.pi * 7.3 * t))
    tl = Timeline(powered, t_cut, co)
    # blade phase on a fine grid
    h = 1e-4
    n = int(t_end / h) + 2
    phase = [0.0] * n
    ph = 0.3
    for i in range(n):
        phase[i] = ph
        ph += tl(i * h) * h * blades / (2 * math.pi)

    def phase_at(t):
        i = min(int(t / h), n - 2)
        return phase[i] + (phase[i + 1] - phase[i]) * (t / h - i)
    rows = []
    for t in jittered_times(gate, t_end, fs, rnd, 0.0):
        cnt = math.floor(phase_at(t)) - math.floor(phase_at(t - gate))
        rpm = cnt * 60.0 / (blades * gate)
        esc = 1000 if (t < t_on or t >= t_cut) else 2000
        thrust = 0.0 if esc == 1000 else 0.62
        rows.append("%.4f,%d,%d,%.3f" % (t, esc, rpm, thrust + rnd.gauss(0, 0.004)))
    text = "Time (s),ESC signal (us),Motor Optical Speed (RPM),Thrust (kgf)\n" + "\n".join(rows) + "\n"
    path = os.path.join(ctx["dir"], "quad_prop_30hz.csv")
    write(path, text, newline="\r\n")
    period = 1 / fs
    # the probe reads 0 once fewer than one blade passes per gate: below q = 900 rpm
    q_rad = 60.0 / (blades * gate) * RPM
    w_lo = q_rad
    decel_lo = (cw * w_lo * w_lo + cc) / J
    tol_stop = 2 * period + w_lo / decel_lo
    truth = {"t_cut": t_cut, "t_stop": tl.t_stop}
    opts = ["--time-column", "Time (s)", "--value-column", "Motor Optical Speed (RPM)",
            "--time-unit", "s", "--value-unit", "rpm", "--inertia", "2e-6"]
    code, out, err, dt = run_prog(fit_cmd(ctx["bin"], path, *opts))
    ok, msg = judge_one_run(load_json(out), truth, period, tol_stop)
    ctx["p1_quad"] = (path, opts)
    return ok, "exit %s; %s" % (code, msg)


@case
def p1_quad_explain_windage(ctx):
    """explain on the propeller's coast names windage (c_w ω0² = 30 c_c)."""
    if "p1_quad" not in ctx:
        p1_quad_prop_gate_tach_30hz(ctx)
    path, opts = ctx["p1_quad"]
    code, out, err, dt = run_prog(explain_cmd(ctx["bin"], path, *opts))
    runs = runs_of(load_json(out))
    added = [[s.get("added") for s in (r.get("steps") or [])] for r in runs]
    ok = len(runs) >= 1 and any("windage" in (a or []) for a in added)
    return ok, "exit %s; runs=%d, effects added per run %s vs truth: windage named (c_w = 4.06e-9, c_c = 8.46e-4)" % (code, len(runs), added)


@case
def p1_tiny_drone_motor_10hz_gate_tach(ctx):
    """A 1104 motor with a 2-inch propeller: 1.5-s coast from 1200 rad/s (c_w ω0² = 20 c_c); a hall
    sensor with 2 magnets counted in a 0.1-s gate, logged at 10 Hz: 300-rpm steps (2.6 %), only
    15 readings from the cut to the stop."""
    rnd = random.Random(3220)
    J, cw, cc = 8e-7, 2.68e-9, 1.93e-4
    w_top = 1200.0
    t_on, t_cut, t_end, fs = 0.5, 4.46, 8.0, 10.0
    gate, ppr = 1.0 / fs, 2
    co = Coast(J, friction(cc=cc, cw=cw), w_top, h=2e-5)

    def powered(t):
        if t < t_on:
            return 0.0
        return w_top * (1 - math.exp(-(t - t_on) / 0.1)) * (1 + 0.003 * math.sin(2 * math.pi * 3.1 * t))
    tl = Timeline(powered, t_cut, co)
    h = 1e-4
    n = int(t_end / h) + 2
    phase = [0.0] * n
    ph = 0.61
    for i in range(n):
        phase[i] = ph
        ph += tl(i * h) * h * ppr / (2 * math.pi)

    def phase_at(t):
        i = min(int(t / h), n - 2)
        return phase[i] + (phase[i + 1] - phase[i]) * (t / h - i)
    rows = []
    for t in jittered_times(gate, t_end, fs, rnd, 0.0):
        cnt = math.floor(phase_at(t)) - math.floor(phase_at(t - gate))
        rows.append("%.1f\t%d" % (t, cnt * 60.0 / (ppr * gate)))
    path = os.path.join(ctx["dir"], "tiny_drone_10hz.tsv")
    write(path, "t [s]\tmotor [rpm]\n" + "\n".join(rows) + "\n")
    period = 1 / fs
    w_lo = 60.0 / (ppr * gate) * RPM
    tol_stop = 2 * period + w_lo / ((cw * w_lo * w_lo + cc) / J)
    truth = {"t_cut": t_cut, "t_stop": tl.t_stop}
    opts = ["--time-column", "t [s]", "--value-column", "motor [rpm]", "--time-unit", "s",
            "--value-unit", "rpm", "--inertia", "8e-7"]
    code, out, err, dt = run_prog(fit_cmd(ctx["bin"], path, *opts))
    ok, msg = judge_one_run(load_json(out), truth, period, tol_stop)
    return ok, "exit %s; %s" % (code, msg)


@case
def p1_centrifuge_cut_alone(ctx):
    """A mini centrifuge's coast from 6000 rpm cut out of a longer log on its own (it starts at
    the last powered reading); display tach in 100-rpm steps read at 12 Hz; 2.5-s coast."""
    rnd = random.Random(3203)
    J, cw, cc = 2e-5, 3.27e-8, 2.586e-3
    w_top = 6000 * RPM
    fs, q = 12.0, 100.0
    t_first = 112.375
    t_cut = t_first + 0.031
    co = Coast(J, friction(cc=cc, cw=cw), w_top, h=1e-4)

    def powered(t):
        return w_top
    tl = Timeline(powered, t_cut, co)
    rows = []
    for t in jittered_times(t_first, t_first + 4.0, fs, rnd, 0.002):
        w = tl(t)
        rpm = 0 if w <= 0 else max(0, int(quantize(w / RPM + rnd.gauss(0, 0.2 * q), q)))
        rows.append("%.3f\t%d" % (t, rpm))
    path = os.path.join(ctx["dir"], "centrifuge_coast_only.tsv")
    write(path, "t\trpm\n" + "\n".join(rows) + "\n")
    period = 1 / fs
    tol_stop = 2 * period + (q / 2 + 3 * 0.2 * q) * RPM / (cc / J)
    truth = {"t_cut": t_cut, "t_stop": tl.t_stop}
    opts = ["--time-column", "t", "--value-column", "rpm", "--time-unit", "s", "--value-unit", "rpm",
            "--inertia", "2e-5"]
    code, out, err, dt = run_prog(fit_cmd(ctx["bin"], path, *opts))
    ok, msg = judge_one_run(load_json(out), truth, period, tol_stop)
    return ok, "exit %s; %s" % (code, msg)


# ====================================================================== point 2: powered steps

@case
def p2_spindle_staircase_then_cut(ctx):
    """A spindle on a VFD: ramp up to 3000 rpm, two powered steps down (3000→2000→1200 rpm at the
    drive's 400 rpm/s decel ramp, 5 s on each plateau), then the supply is cut: a 22-s coast."""
    rnd = random.Random(3204)
    J, cv, cc = 0.01, 1e-4, 0.05
    fs = 50.0
    segs = [(0.0, 1.0, 0.0, 0.0), (1.0, 4.0, 0.0, 3000.0), (4.0, 10.0, 3000.0, 3000.0),
            (10.0, 12.5, 3000.0, 2000.0), (12.5, 17.5, 2000.0, 2000.0),
            (17.5, 19.5, 2000.0, 1200.0), (19.5, 24.507, 1200.0, 1200.0)]
    t_cut = 24.507

    def powered(t):
        for a, b, ya, yb in segs:
            if a <= t < b:
                return RPM * (ya + (yb - ya) * (t - a) / (b - a))
        return RPM * 1200.0
    co = Coast(J, friction(cv=cv, cc=cc), 1200 * RPM, h=1e-3)
    tl = Timeline(powered, t_cut, co)
    rows = []
    for t in jittered_times(0.0, tl.t_stop + 4.0, fs, rnd, 0.0):
        w = tl(t)
        rpm = 0.0 if w <= 0 else round(w / RPM + rnd.gauss(0, 3.0))
        rows.append("%.2f\t%d" % (t, rpm))
    path = os.path.join(ctx["dir"], "spindle_staircase.tsv")
    write(path, "Time[s]\tSpeed[rpm]\n" + "\n".join(rows) + "\n")
    period = 1 / fs
    tol_stop = 2 * period + (0.5 + 9.0) * RPM / (cc / J)
    truth = {"t_cut": t_cut, "t_stop": tl.t_stop}
    opts = ["--time-column", "Time[s]", "--value-column", "Speed[rpm]", "--time-unit", "s",
            "--value-unit", "rpm", "--inertia", "0.01"]
    code, out, err, dt = run_prog(fit_cmd(ctx["bin"], path, *opts))
    ok, msg = judge_one_run(load_json(out), truth, period, tol_stop)
    return ok, "exit %s; %s" % (code, msg)


@case
def p2_conveyor_slow_ramp_plateau_then_cut(ctx):
    """A conveyor drive ramps DOWN under power from 1500 to 600 rpm at 50 rpm/s (slower than the
    load would coast: 69-87 rpm/s), holds 600 rpm for 6 s, then is cut: an 8.6-s coast."""
    rnd = random.Random(3205)
    J, cv, cc = 0.5, 0.01, 3.0
    fs = 20.0
    t_cut = 39.03
    segs = [(0.0, 2.0, 0.0, 0.0), (2.0, 7.0, 0.0, 1500.0), (7.0, 15.0, 1500.0, 1500.0),
            (15.0, 33.0, 1500.0, 600.0), (33.0, t_cut, 600.0, 600.0)]

    def powered(t):
        for a, b, ya, yb in segs:
            if a <= t < b:
                return RPM * (ya + (yb - ya) * (t - a) / (b - a))
        return RPM * 600.0
    co = Coast(J, friction(cv=cv, cc=cc), 600 * RPM, h=1e-3)
    tl = Timeline(powered, t_cut, co)
    rows = []
    for t in jittered_times(0.0, tl.t_stop + 4.0, fs, rnd, 0.003):
        w = tl(t)
        v = 0.0 if w <= 0 else w + rnd.gauss(0, 0.05)
        rows.append("%.3f,%.2f" % (t, v))
    path = os.path.join(ctx["dir"], "conveyor_ramp_plateau.csv")
    write(path, "t_s,motor_speed_rad_s\n" + "\n".join(rows) + "\n")
    period = 1 / fs
    tol_stop = 2 * period + 0.2 / (cc / J)
    truth = {"t_cut": t_cut, "t_stop": tl.t_stop}
    opts = ["--time-column", "t_s", "--value-column", "motor_speed_rad_s", "--time-unit", "s",
            "--value-unit", "rad/s", "--inertia", "0.5"]
    code, out, err, dt = run_prog(fit_cmd(ctx["bin"], path, *opts))
    ok, msg = judge_one_run(load_json(out), truth, period, tol_stop)
    return ok, "exit %s; %s" % (code, msg)


# ================================================================ point 3: start-up transients

@case
def p3_turntable_overshoot_startup(ctx):
    """A belt-drive turntable's speed servo at power-on overshoots to 40 rpm and rings (ζ = 0.45)
    before settling at 33.33 rpm; 16 s later the power is cut: a 15-s coast.  Logged at 10 Hz in
    rpm with 2 decimals; --value-unit rpm is given and right."""
    rnd = random.Random(3206)
    J, cv, cc = 0.0225, 1.5e-3, 3e-3
    fs = 10.0
    w_set = 33.333 * RPM
    t_on, t_cut = 1.0, 20.013
    zeta, wn = 0.45, 3.0
    wd = wn * math.sqrt(1 - zeta * zeta)

    def powered(t):
        if t < t_on:
            return 0.0
        s = t - t_on
        resp = 1 - math.exp(-zeta * wn * s) * (math.cos(wd * s) + zeta / math.sqrt(1 - zeta * zeta) * math.sin(wd * s))
        return w_set * resp * (1 + 0.001 * math.sin(2 * math.pi * 0.5556 * t))
    co = Coast(J, friction(cv=cv, cc=cc), powered(t_cut), h=1e-3)
    tl = Timeline(powered, t_cut, co)
    rows = []
    for t in jittered_times(0.0, tl.t_stop + 5.0, fs, rnd, 0.0):
        w = tl(t)
        v = 0.0 if w <= 0 else max(0.0, w / RPM + rnd.gauss(0, 0.02))
        rows.append("%.1f,%.2f" % (t, v))
    path = os.path.join(ctx["dir"], "turntable_startup.csv")
    write(path, "seconds,platter_rpm\n" + "\n".join(rows) + "\n")
    period = 1 / fs
    tol_stop = 2 * period + (0.005 + 0.06) * RPM / (cc / J)
    truth = {"t_cut": t_cut, "t_stop": tl.t_stop}
    opts = ["--time-column", "seconds", "--value-column", "platter_rpm", "--time-unit", "s",
            "--value-unit", "rpm", "--inertia", "0.0225"]
    code, out, err, dt = run_prog(fit_cmd(ctx["bin"], path, *opts))
    js = load_json(out)
    ok, msg = judge_one_run(js, truth, period, tol_stop)
    unit_doubts = []
    for r in runs_of(js):
        for d in r.get("doubts") or []:
            if re.search(r"value-unit|read as rpm|volts", str(d), re.I):
                unit_doubts.append(d)
    if unit_doubts:
        ok = False
    return ok, "exit %s; %s; unit doubts %s vs truth none (rpm given and right)" % (code, msg, unit_doubts)


@case
def p3_servo_inrush_overshoot_rings(ctx):
    """A servo drive's velocity loop at power-on: the inrush overshoots the 150 rad/s setpoint by
    37 % (ζ = 0.3, ω_n = 25 rad/s) and rings down to it within ~0.6 s, all under power; 5 s later
    the drive is disabled: a ~6-s coast.  100 Hz, rad/s."""
    rnd = random.Random(3221)
    J, cv, cc = 5e-4, 4e-5, 0.012
    fs = 100.0
    w_set = 150.0
    t_on, t_cut = 0.8, 6.305
    zeta, wn = 0.3, 25.0
    wd = wn * math.sqrt(1 - zeta * zeta)

    def powered(t):
        if t < t_on:
            return 0.0
        s = t - t_on
        return w_set * (1 - math.exp(-zeta * wn * s) * (math.cos(wd * s) + zeta / math.sqrt(1 - zeta * zeta) * math.sin(wd * s)))
    co = Coast(J, friction(cv=cv, cc=cc), powered(t_cut), h=1e-4)
    tl = Timeline(powered, t_cut, co)
    rows = []
    for t in jittered_times(0.0, tl.t_stop + 3.0, fs, rnd, 0.0):
        w = tl(t)
        v = 0.0 if w <= 0 else w + rnd.gauss(0, 0.2)
        amps = 0.0 if (t < t_on or t >= t_cut) else 0.6 + 6.0 * math.exp(-(t - t_on) / 0.15)
        rows.append("%.2f,%.2f,%.2f" % (t, v, amps + rnd.gauss(0, 0.02)))
    path = os.path.join(ctx["dir"], "servo_inrush.csv")
    write(path, "time_s,velocity_rad_s,current_A\n" + "\n".join(rows) + "\n")
    period = 1 / fs
    tol_stop = 2 * period + 0.6 / (cc / J)
    truth = {"t_cut": t_cut, "t_stop": tl.t_stop}
    opts = ["--time-column", "time_s", "--value-column", "velocity_rad_s", "--time-unit", "s",
            "--value-unit", "rad/s", "--inertia", "5e-4"]
    code, out, err, dt = run_prog(fit_cmd(ctx["bin"], path, *opts))
    js = load_json(out)
    runs = runs_of(js)
    early_trusted = [r for r in runs if r.get("t_cut_s") is not None and r["t_cut_s"] < t_cut - 2 * period
                     and not r.get("doubts")]
    ok, msg = judge_one_run(js, truth, period, tol_stop)
    return ok, "exit %s; %s; trusted runs before the cut: %d" % (code, msg, len(early_trusted))


@case
def p3_gearmotor_stall_at_start(ctx):
    """A gear motor at power-on kicks to 15 rad/s, the load binds and it stalls to 0 under power
    for 0.6 s, then breaks free and runs up to 180 rad/s; 6 s later it is cut: a ~4-s coast.
    Encoder speed in rad/s at 50 Hz."""
    rnd = random.Random(3207)
    J, cv, cc = 2e-4, 5e-5, 0.008
    fs = 50.0
    w_run = 180.0
    t_on, t_cut = 1.0, 9.413

    def powered(t):
        if t < t_on:
            return 0.0
        s = t - t_on
        if s < 0.15:
            return 15.0 * s / 0.15
        if s < 0.25:
            return 15.0 * (1 - (s - 0.15) / 0.10)
        if s < 0.85:
            return 0.0
        return w_run * (1 - math.exp(-(s - 0.85) / 0.4))
    co = Coast(J, friction(cv=cv, cc=cc), powered(t_cut), h=1e-4)
    tl = Timeline(powered, t_cut, co)
    rows = []
    for t in jittered_times(0.0, tl.t_stop + 3.0, fs, rnd, 0.0):
        w = tl(t)
        v = 0.0 if w <= 0 else w + rnd.gauss(0, 0.15)
        rows.append("%.2f;%.2f" % (t, v))
    path = os.path.join(ctx["dir"], "gearmotor_stall.csv")
    write(path, "time;speed\n" + "\n".join(rows) + "\n")
    period = 1 / fs
    truth = {"t_cut": t_cut, "t_stop": tl.t_stop}
    opts = ["--time-column", "time", "--value-column", "speed", "--time-unit", "s",
            "--value-unit", "rad/s", "--delimiter", ";", "--inertia", "2e-4"]
    code, out, err, dt = run_prog(fit_cmd(ctx["bin"], path, *opts))
    runs = runs_of(load_json(out))
    early = [r for r in runs if r.get("t_cut_s") is not None and r["t_cut_s"] < t_cut - 2 * period]
    trusted_early = [r for r in early if not r.get("doubts")]
    real = [r for r in runs if r.get("t_cut_s") is not None and abs(r["t_cut_s"] - t_cut) <= 2 * period]
    ok = len(real) == 1 and not trusted_early
    return ok, "exit %s; runs %s vs truth: the real run cut at %.3f (±%.2f), no trusted run before it (stall blip 1.0-1.25 s under power)" % (
        code, fmt_runs(runs), t_cut, 2 * period)


# ================================================================ point 4: slow quantized tails

@case
def p4_flywheel_battery_1rpm_tail(ctx):
    """A flywheel energy store in vacuum (eddy-current drag + bearing friction) cut at 3000 rpm
    coasts ~61 min; the logger writes integer rpm once a second; near the end the reading falls
    one count every ~8 s."""
    rnd = random.Random(3208)
    J = 0.5
    tau = 1200.0
    cv = J / tau
    cc = J * 0.125 * RPM            # decel at standstill 0.125 rpm/s: one count per 8 s
    t_cut = 60.4
    co = Coast(J, friction(cv=cv, cc=cc), 3000 * RPM, h=0.01)
    tl = Timeline(lambda t: 3000 * RPM * (1 + 0.0002 * math.sin(t / 7.0)), t_cut, co)
    rows = []
    temp = 24.0
    for i, t in enumerate(jittered_times(0.0, tl.t_stop + 240.0, 1.0, rnd, 0.0)):
        w = tl(t)
        rpm = 0 if w <= 0 else max(0, int(round(w / RPM + rnd.gauss(0, 0.3))))
        temp += rnd.gauss(0, 0.01)
        rows.append("%d,%d,%.2f,%.1e" % (i, rpm, temp, 2.1e-3))
    path = os.path.join(ctx["dir"], "flywheel_battery.csv")
    write(path, "elapsed_s,rotor_speed_rpm,housing_temp_C,vacuum_mbar\n" + "\n".join(rows) + "\n")
    period = 1.0
    tol_stop = 2 * period + (0.5 + 0.9) / 0.125
    truth = {"t_cut": t_cut, "t_stop": tl.t_stop}
    opts = ["--time-column", "elapsed_s", "--value-column", "rotor_speed_rpm", "--time-unit", "s",
            "--value-unit", "rpm", "--inertia", "0.5"]
    code, out, err, dt = run_prog(fit_cmd(ctx["bin"], path, *opts))
    js = load_json(out)
    ok, msg = judge_one_run(js, truth, period, tol_stop)
    runs = runs_of(js)
    if len(runs) == 1 and runs[0].get("end") != "stopped":
        ok = False
        msg += " (end %s, truth stopped)" % runs[0].get("end")
    return ok, "exit %s; %s" % (code, msg)


@case
def p4_bearing_tachogenerator_2dec_tail(ctx):
    """A bearing rig's tachogenerator (0.02 V·s/rad) printed with 2 decimals every 200 ms
    (millis): a 32-min coast whose last minutes fall 0.01 V per ~12 s."""
    rnd = random.Random(3209)
    J, kb = 0.004, 0.02
    cv = J / 1000.0
    cc = J * (0.5 / 12.0)           # decel at standstill: 0.5 rad/s (0.01 V) per 12 s
    t_cut = 30.1
    co = Coast(J, friction(cv=cv, cc=cc), 250.0, h=0.01)
    tl = Timeline(lambda t: 0.0 if t < 5.0 else 250.0 * (1 - math.exp(-(t - 5.0) / 2.0)), t_cut, co)
    rows = []
    t_ms = 1234
    while t_ms / 1000.0 < tl.t_stop + 180.0:
        t = t_ms / 1000.0
        w = tl(t)
        v = 0.0 if w <= 0 else max(0.0, round(w * kb + rnd.gauss(0, 0.003), 2))
        rows.append("%d,%.2f" % (t_ms, v))
        t_ms += 200 + rnd.choice((0, 0, 0, 1))
    path = os.path.join(ctx["dir"], "bearing_rig_tach.csv")
    write(path, "ms,tach_V\n" + "\n".join(rows) + "\n", newline="\r\n")
    period = 0.2
    tol_stop = 2 * period + ((0.005 + 0.009) / kb) / (cc / J)
    truth = {"t_cut": t_cut, "t_stop": tl.t_stop}
    opts = ["--time-column", "ms", "--value-column", "tach_V", "--time-unit", "ms", "--value-unit", "V",
            "--kb", "0.02", "--inertia", "0.004"]
    code, out, err, dt = run_prog(fit_cmd(ctx["bin"], path, *opts))
    js = load_json(out)
    ok, msg = judge_one_run(js, truth, period, tol_stop)
    runs = runs_of(js)
    if len(runs) == 1 and runs[0].get("end") != "stopped":
        ok = False
        msg += " (end %s, truth stopped)" % runs[0].get("end")
    return ok, "exit %s; %s" % (code, msg)


# ===================================================================== point 5: doubts

def _doubts_of(js):
    runs = runs_of(js)
    return runs, [r.get("doubts") or [] for r in runs]


@case
def p5_short_coast_brake_gross_misfit(ctx):
    """A short coast (92 samples at 50 Hz, window < 200 samples) during which a safety brake
    engages 1.0 s after the cut (Coulomb torque 1e-3 → 3e-3 N·m): no friction model fits (the
    combined model misses by RMSE 16 rad/s against a reading noise of 0.3 rad/s).  The best
    model's doubt must fire."""
    rnd = random.Random(3210)
    J, cv, cc, cb, tb_rel = 1.2e-5, 2e-7, 1e-3, 2e-3, 1.0
    fs = 50.0
    t_cut = 4.007
    c1 = Coast(J, friction(cv=cv, cc=cc), 300.0, h=1e-4)
    c2 = Coast(J, friction(cv=cv, cc=cc + cb), c1(tb_rel), h=1e-4)

    class Braked:
        t_stop = tb_rel + c2.t_stop

        def __call__(self, s):
            return c1(s) if s < tb_rel else c2(s - tb_rel)
    br = Braked()
    tl = Timeline(lambda t: 0.0 if t < 1.0 else 300.0 * (1 - math.exp(-(t - 1.0) / 0.3)), t_cut, br)
    rows = []
    ts, ys = [], []
    for t in jittered_times(0.0, t_cut + br.t_stop + 3.0, fs, rnd, 0.0):
        w = tl(t)
        v = 0.0 if w <= 0 else w + rnd.gauss(0, 0.3)
        rows.append("%.2f,%.2f" % (t, v))
        if t_cut <= t <= t_cut + br.t_stop + 2.0:
            ts.append(t - t_cut)
            ys.append(w)
    path = os.path.join(ctx["dir"], "short_coast_brake.csv")
    write(path, "time_s,speed_rad_s\n" + "\n".join(rows) + "\n")
    p, rss, _ = fit_combined(ts, ys, (300.0, cv / J, cc / J))
    rmse = math.sqrt(rss / len(ts))
    opts = ["--time-column", "time_s", "--value-column", "speed_rad_s", "--time-unit", "s",
            "--value-unit", "rad/s", "--inertia", "1.2e-5"]
    code, out, err, dt = run_prog(fit_cmd(ctx["bin"], path, *opts))
    runs, doubts = _doubts_of(load_json(out))
    ok = len(runs) >= 1 and all(doubts) and len(ts) < 200
    return ok, "exit %s; runs %s doubts %s vs truth: doubted (noiseless combined fit misses by RMSE %.1f rad/s vs noise 0.3, %d samples in the window)" % (
        code, fmt_runs(runs), [len(d) for d in doubts], rmse, len(ts))


@case
def p5_short_plateau_in_window_must_doubt(ctx):
    """A 4-s coast at 20 Hz (80 samples) 3 s after a powered step down (2400→1500 rpm): if a run's
    window takes in the powered plateau (its cut ≥ 1 s before the true cut) the fit grossly
    misses and it must be doubted; a run cut at the true cut is fine."""
    rnd = random.Random(3211)
    J, cv, cc = 1e-4, 2e-6, 0.0035
    fs = 20.0
    t_cut = 9.52
    segs = [(0.0, 1.0, 0.0, 0.0), (1.0, 3.0, 0.0, 2400.0), (3.0, 6.0, 2400.0, 2400.0),
            (6.0, 6.5, 2400.0, 1500.0), (6.5, t_cut, 1500.0, 1500.0)]

    def powered(t):
        for a, b, ya, yb in segs:
            if a <= t < b:
                return RPM * (ya + (yb - ya) * (t - a) / (b - a))
        return RPM * 1500
    co = Coast(J, friction(cv=cv, cc=cc), 1500 * RPM, h=1e-4)
    tl = Timeline(powered, t_cut, co)
    rows = []
    for t in jittered_times(0.0, tl.t_stop + 3.0, fs, rnd, 0.0):
        w = tl(t)
        v = 0 if w <= 0 else int(round(w / RPM + rnd.gauss(0, 8)))
        rows.append("%.2f,%d" % (t, max(0, v)))
    path = os.path.join(ctx["dir"], "short_step_then_cut.csv")
    write(path, "t,rpm\n" + "\n".join(rows) + "\n")
    opts = ["--time-column", "t", "--value-column", "rpm", "--time-unit", "s", "--value-unit", "rpm",
            "--inertia", "1e-4"]
    code, out, err, dt = run_prog(fit_cmd(ctx["bin"], path, *opts))
    runs = runs_of(load_json(out))
    bad = [r for r in runs if r.get("t_cut_s") is not None and r["t_cut_s"] <= t_cut - 1.0
           and (r.get("t_stop_s") or 0) > t_cut and not r.get("doubts")]
    ok = len(runs) >= 1 and not bad
    return ok, "exit %s; runs %s vs truth: coast cut at %.2f; a run whose window holds the powered plateau must be doubted (undoubted such runs: %d)" % (
        code, fmt_runs(runs), t_cut, len(bad))


LONG = dict(J=0.02, w0=300.0, cv=1.5e-4, cc=0.03, fs=100.0, q=0.01)


def _long_run(ctx, cid, seed, T, noise, tau_filter, label):
    """A long coast (~12,000 samples at 100 Hz) of a 0.02 kg·m² flywheel from 300 rad/s, powered
    lead-in, speed in rad/s (2 decimals).  Returns (path, truth dict with the noiseless combined
    fit's bias in units of its white-noise standard error)."""
    L = LONG
    rnd = random.Random(seed)
    J, w0, cv, cc, fs, q = L["J"], L["w0"], L["cv"], L["cc"], L["fs"], L["q"]
    co = Coast(J, T, w0, h=2e-3)
    t_cut = 5.005
    tl = Timeline(lambda t: 0.0 if t < 0.5 else w0 * (1 - math.exp(-(t - 0.5) / 0.5)), t_cut, co)
    a = (1 - math.exp(-1.0 / fs / tau_filter)) if tau_filter else 1.0
    f = fc = 0.0
    rows, ts_c, ys_c = [], [], []
    n = int((tl.t_stop + 4.0) * fs)
    for i in range(n + 1):
        t = i / fs
        w = tl(t)
        f += a * (w + rnd.gauss(0, noise) - f)
        fc += a * (w - fc)
        rows.append("%.2f,%.2f" % (t, quantize(f, q)))
        if t_cut <= t <= tl.t_stop + 2.0:
            ts_c.append(t - t_cut)
            ys_c.append(fc)
    path = os.path.join(ctx["dir"], cid + ".csv")
    write(path, "time_s,speed_rad_s\n" + "\n".join(rows) + "\n")
    # σ of one reading as the second differences see it (white noise: = noise; filtered: less)
    if tau_filter:
        # the empirical second-difference σ of the generated readings (what E[d²] = 6σ² gives)
        vals = [float(r.split(",")[1]) for r in rows]
        i0, i1 = int((t_cut + 1) * fs), int((tl.t_stop - 1) * fs)
        d2 = [vals[i + 1] - 2 * vals[i] + vals[i - 1] for i in range(i0, i1)]
        sig = math.sqrt(sum(d * d for d in d2) / len(d2) / 6.0)
    else:
        sig = math.hypot(noise, q / math.sqrt(12))
    p, rss, A = fit_combined(ts_c, ys_c, (w0, cv / J, cc / J))
    se = combined_se(A, sig)
    truth = {"t_cut": t_cut, "t_stop": tl.t_stop, "c3": cv, "c4": cc,
             "fit_c3": p[1] * J, "fit_c4": p[2] * J,
             "bias_c3_se": (p[1] - cv / J) / se[1], "bias_c4_se": (p[2] - cc / J) / se[2],
             "se_c3": se[1] * J, "se_c4": se[2] * J, "sigma": sig, "n": len(ts_c),
             "misfit_rms": math.sqrt(rss / len(ts_c))}
    if tau_filter:
        # the filtered noise's long-run (zero-frequency) variance is the raw noise's, s²: the honest
        # standard error of a slowly varying fit is s·sqrt(diag((JᵀJ)⁻¹)), not σ·…
        se_lr = combined_se(A, math.hypot(noise, q / math.sqrt(12)))
        truth["bias_c3_se_longrun"] = (p[1] - cv / J) / se_lr[1]
        truth["bias_c4_se_longrun"] = (p[2] - cc / J) / se_lr[2]
    return path, truth


def _judge_doubt(ctx, path, truth, must_fire):
    opts = ["--time-column", "time_s", "--value-column", "speed_rad_s", "--time-unit", "s",
            "--value-unit", "rad/s", "--inertia", "0.02"]
    code, out, err, dt = run_prog(fit_cmd(ctx["bin"], path, *opts))
    runs = runs_of(load_json(out))
    info = "truth: noiseless combined fit moves c3 by %.2f se, c4 by %.2f se (white-noise se at σ %.3g, n %d, misfit RMS %.3g)" % (
        truth["bias_c3_se"], truth["bias_c4_se"], truth["sigma"], truth["n"], truth["misfit_rms"])
    if "bias_c3_se_longrun" in truth:
        info += "; at the correlated noise's honest se: %.2f, %.2f" % (truth["bias_c3_se_longrun"], truth["bias_c4_se_longrun"])
    if len(runs) != 1:
        return False, "exit %s; runs %s (truth 1 run); %s" % (code, fmt_runs(runs), info)
    r = runs[0]
    doubts = r.get("doubts") or []
    c3, s3 = param(r, "combined", "c3")
    c4, s4 = param(r, "combined", "c4")
    def dev(v, se, tv):
        return "null" if (v is None or not se) else "%+.1f" % ((v - tv) / se)
    meas = "exit %s; doubts %s; combined c3 = %s ± %s (truth %.4g, %s of its se), c4 = %s ± %s (truth %.4g, %s of its se); best %s" % (
        code, [str(d)[:90] for d in doubts], "null" if c3 is None else "%.7g" % c3,
        "null" if s3 is None else "%.2g" % s3, truth["c3"], dev(c3, s3, truth["c3"]),
        "null" if c4 is None else "%.7g" % c4, "null" if s4 is None else "%.2g" % s4, truth["c4"],
        dev(c4, s4, truth["c4"]), r.get("best"))
    if must_fire:
        honest = (c3 is not None and s3 and c4 is not None and s4 and
                  abs(c3 - truth["c3"]) <= 2 * s3 and abs(c4 - truth["c4"]) <= 2 * s4)
        ok = bool(doubts) or honest
        return ok, meas + "; must doubt (or its ± must cover the truth); " + info
    ok = not doubts
    return ok, meas + "; must stay quiet; " + info


@case
def p5_long_windage_tiny_quiet(ctx):
    """12,400-sample coast; windage 0.001 % of the torque at ω0 (c_w = 8.33e-12): c3/c4 move by
    < 0.3 of their errors; white reading noise 0.1 rad/s.  No doubt."""
    L = LONG
    cw = 1e-5 * (L["cv"] * L["w0"] + L["cc"]) / L["w0"] ** 2
    path, truth = _long_run(ctx, "long_windage_tiny", 3212, friction(L["cv"], L["cc"], cw), 0.1, 0, "")
    return _judge_doubt(ctx, path, truth, must_fire=False)


@case
def p5_long_filtered_sensor_stribeck_tiny_quiet(ctx):
    """12,300-sample coast; Stribeck 0.03 % (c_s = 1.0003 c_c, ω_s = 9 rad/s) read through a drive's
    50-ms speed filter (raw noise 0.5 rad/s): the readings' noise is correlated, the model is right
    (c3/c4 move < 0.3 of their white-noise errors at the second-difference σ, less at honest
    ones).  No doubt."""
    L = LONG
    T = friction(L["cv"], L["cc"], 0.0, L["cc"] * 1.0003, 9.0)
    path, truth = _long_run(ctx, "long_filtered_stribeck_tiny", 3213, T, 0.5, 0.05, "")
    return _judge_doubt(ctx, path, truth, must_fire=False)


@case
def p5_long_windage_1pct_fire(ctx):
    """12,400-sample coast; windage 1 % of the torque at ω0 (c_w = 8.33e-9 N·m·s²/rad²): invisible
    stretch by stretch (misfit RMS 0.028 vs σ 0.1) but it moves c3 by ~160 and c4 by ~60 standard
    errors.  The doubt must fire (or the ± must cover the truth)."""
    L = LONG
    cw = 1e-2 * (L["cv"] * L["w0"] + L["cc"]) / L["w0"] ** 2
    path, truth = _long_run(ctx, "long_windage_1pct", 3214, friction(L["cv"], L["cc"], cw), 0.1, 0, "")
    return _judge_doubt(ctx, path, truth, must_fire=True)


@case
def p5_long_stribeck_fire(ctx):
    """12,300-sample coast; Stribeck c_s = 1.3 c_c, ω_s = 9 rad/s (3 % of ω0): moves c3 by ~100 and
    c4 by ~130 standard errors.  The doubt must fire (or the ± must cover the truth)."""
    L = LONG
    T = friction(L["cv"], L["cc"], 0.0, L["cc"] * 1.3, 9.0)
    path, truth = _long_run(ctx, "long_stribeck_30pct", 3215, T, 0.1, 0, "")
    return _judge_doubt(ctx, path, truth, must_fire=True)


# ======================================================================= point 6: files

def _dyno_rows(rnd, fs=50.0):
    """A small dyno: DC motor at 2800 rpm, cut at 6.013 s, combined friction coast (~14 s)."""
    J, cv, cc = 1.12687602e-5, 1.8e-7, 1.14e-4
    w_top = 2800 * RPM
    t_cut = 6.013
    co = Coast(J, friction(cv=cv, cc=cc), w_top, h=1e-3)
    tl = Timeline(lambda t: 0.0 if t < 1.0 else w_top * (1 - math.exp(-(t - 1.0) / 0.5)), t_cut, co)
    rows = []
    for t in jittered_times(0.0, tl.t_stop + 3.0, fs, rnd, 0.0):
        w = tl(t)
        rpm = 0.0 if w <= 0 else w / RPM + rnd.gauss(0, 2.0)
        powered = 1.0 <= t < t_cut
        cur = (0.35 + 2.5 * math.exp(-(t - 1.0) / 0.3) if powered else 0.0) + rnd.gauss(0, 0.01)
        torque = (0.012 if powered else 0.0) + rnd.gauss(0, 0.0005)
        rows.append((t, torque, rpm, cur, 24.0 + 0.1 * t / 10))
    return rows, {"t_cut": t_cut, "t_stop": tl.t_stop, "omega0": w_top, "c3": cv, "c4": cc, "J": J}


def _judge_dyno(js, truth, period=0.02):
    ok, msg = judge_one_run(js, truth, period, 2 * period + 8.0 * RPM / (truth["c4"] / truth["J"]))
    runs = runs_of(js)
    if len(runs) == 1:
        w0, _ = param(runs[0], "combined", "omega0")
        msg += "; combined ω0 = %s rad/s vs truth %.1f (±3 %%)" % (_f(w0, 1), truth["omega0"])
        if w0 is None or abs(w0 - truth["omega0"]) > 0.03 * truth["omega0"]:
            ok = False
    return ok, msg


@case
def p6_quoted_header_commas_named(ctx):
    """A dyno's CSV export: quoted header names with commas inside ("Time, s","Torque, N·m",
    "Motor speed, rpm","Current, A"), CR LF; the user names the columns by their full names."""
    rnd = random.Random(3216)
    rows, truth = _dyno_rows(rnd)
    lines = ['"Time, s","Torque, N·m","Motor speed, rpm","Current, A"']
    for t, tq, rpm, cur, _ in rows:
        lines.append("%.3f,%.5f,%.1f,%.3f" % (t, tq, rpm, cur))
    path = os.path.join(ctx["dir"], "dyno_quoted_header.csv")
    write(path, "\n".join(lines) + "\n", newline="\r\n")
    opts = ["--time-column", "Time, s", "--value-column", "Motor speed, rpm", "--time-unit", "s",
            "--value-unit", "rpm"]
    code, out, err, dt = run_prog(fit_cmd(ctx["bin"], path, *opts))
    ok, msg = _judge_dyno(load_json(out), truth)
    if code != 0:
        ok = False
    return ok, "exit %s; %s%s" % (code, msg, "" if ok else "; stderr: " + err.strip()[:200].replace("\n", " | "))


@case
def p6_quoted_header_commas_raw(ctx):
    """The same kind of export fitted raw (no options): "Time, s","Supply current, A",
    "Motor speed, rpm","Winding temp, °C".  The header says everything: the time in s and the speed
    in rpm must be used (or the error must propose "Motor speed, rpm" whole)."""
    rnd = random.Random(3217)
    rows, truth = _dyno_rows(rnd)
    lines = ['"Time, s","Supply current, A","Motor speed, rpm","Winding temp, °C"']
    for t, tq, rpm, cur, temp in rows:
        lines.append("%.3f,%.3f,%.1f,%.2f" % (t, cur, rpm, temp))
    path = os.path.join(ctx["dir"], "dyno_quoted_header_raw.csv")
    write(path, "\n".join(lines) + "\n", newline="\r\n")
    code, out, err, dt = run_prog(fit_cmd(ctx["bin"], path))
    js = load_json(out)
    ok, msg = _judge_dyno(js, truth)
    if code != 0:
        ok = False
    if not ok and code not in (0, None) and "Motor speed, rpm" in err:
        ok, msg = True, msg + "; refused, naming \"Motor speed, rpm\" whole"
    return ok, "exit %s; %s; stderr: %s" % (code, msg, err.strip()[:240].replace("\n", " | "))


@case
def p6_no_header_propose_columns(ctx):
    """A logger's file with no header: columns time in s (0.02-s steps), speed in rpm, current in A,
    temperature.  Fitted raw: either it is fitted right (time in s, the speed column) or the error
    proposes the time column (1) and the speed column (2)."""
    rnd = random.Random(3218)
    rows, truth = _dyno_rows(rnd)
    lines = []
    for t, tq, rpm, cur, temp in rows:
        lines.append("%.2f,%.1f,%.3f,%.2f" % (t, rpm, cur, temp))
    path = os.path.join(ctx["dir"], "logger_no_header.csv")
    write(path, "\n".join(lines) + "\n")
    code, out, err, dt = run_prog(fit_cmd(ctx["bin"], path))
    js = load_json(out)
    tcol, vcol = ctx.get("col_base", 1), ctx.get("col_base", 1) + 1
    if code == 0:
        runs = runs_of(js)
        ok = (len(runs) == 1 and runs[0].get("t_cut_s") is not None
              and abs(runs[0]["t_cut_s"] - truth["t_cut"]) <= 0.04)
        return ok, "exit 0; fitted raw: %s vs truth cut %.3f s (time column in s)" % (fmt_runs(runs), truth["t_cut"])
    tprop = re.search(r"time[-_ ]column[ =]+\"?%d\b" % tcol, err, re.I)
    vprop = re.search(r"value[-_ ]column[ =]+\"?%d\b" % vcol, err, re.I)
    ok = bool(tprop and vprop)
    return ok, "exit %s; proposal of --time-column %d: %s, --value-column %d: %s; stderr: %s" % (
        code, tcol, bool(tprop), vcol, bool(vprop), err.strip()[:300].replace("\n", " | "))


@case
def p6_per_rev_sensor_holds_at_rest(ctx):
    """A trainer roller with one magnet per revolution: speed = 60/(time between pulses), logged at
    10 Hz, held between pulses; after the last pulse it holds that last value (43.5 rpm, the mean
    speed over the last revolution) for 20 s at rest.  The recording starts powered (no zeros before).  The zero level is 0, not the held
    value."""
    rnd = random.Random(3219)
    J, cv, cc = 0.015, 2e-3, 0.015
    w_top = 600 * RPM
    t_cut = 8.04
    co = Coast(J, friction(cv=cv, cc=cc), w_top, h=1e-3)
    tl = Timeline(lambda t: w_top * (1 + 0.003 * math.sin(2 * math.pi * 0.9 * t)), t_cut, co)
    # pulse times: revolutions of the roller
    h = 1e-3
    ang, t, pulses = 0.37, 0.0, []
    t_end = tl.t_stop + 20.0
    while t < t_end:
        w = tl(t)
        ang_n = ang + w * h / (2 * math.pi)
        if math.floor(ang_n) > math.floor(ang):
            frac = (math.floor(ang_n) - ang) / (ang_n - ang)
            pulses.append(t + frac * h)
        ang, t = ang_n, t + h
    rows = []
    k = 0
    last = None
    for t in jittered_times(0.0, t_end, 10.0, rnd, 0.0):
        while k < len(pulses) and pulses[k] <= t:
            if k > 0:
                last = 60.0 / (pulses[k] - pulses[k - 1])
            k += 1
        rows.append("%.1f,%.1f" % (t, last if last is not None else 0.0))
    held = last
    path = os.path.join(ctx["dir"], "trainer_per_rev.csv")
    write(path, "t_s,wheel_rpm\n" + "\n".join(rows) + "\n")
    opts = ["--time-column", "t_s", "--value-column", "wheel_rpm", "--time-unit", "s", "--value-unit", "rpm",
            "--inertia", "0.015"]
    code, out, err, dt = run_prog(fit_cmd(ctx["bin"], path, *opts))
    runs = runs_of(load_json(out))
    zl = [r.get("zero_level") for r in runs]
    real = [r for r in runs if r.get("t_cut_s") is not None and abs(r["t_cut_s"] - t_cut) <= 0.2]
    ok = len(real) == 1 and all(z is not None and abs(z) < 0.05 * held * RPM for z in zl)
    return ok, "exit %s; runs %s zero_level %s vs truth: 1 run cut %.2f (±0.2), zero level 0 (held value %.1f rpm = %.2f rad/s is the last pulse's speed)" % (
        code, fmt_runs(runs), zl, t_cut, held, held * RPM)


# =================================================================================== main

def main():
    bindir, scratch = sys.argv[1], sys.argv[2]
    only = set(sys.argv[3:])
    ctx = {"bin": bindir, "dir": scratch}
    # column numbers are 1-based (spindown fit --help: "header name or 1-based index")
    ctx["col_base"] = 1
    passed = total = 0
    t_start = time.time()
    for fn in CASES:
        cid = fn.__name__
        if only and cid not in only:
            continue
        total += 1
        if time.time() - t_start > 270:
            print("FAIL %s: not run: the runner's time budget (270 s) was used up" % cid, flush=True)
            continue
        try:
            ok, msg = fn(ctx)
        except Exception as e:  # a bug in the runner is a failure too, said as such
            ok, msg = False, "runner error: %r" % (e,)
        passed += ok
        print("%s %s: %s" % ("PASS" if ok else "FAIL", cid, msg), flush=True)
    print("SUMMARY: %d/%d passed" % (passed, total))
    return 0 if passed == total else 1


if __name__ == "__main__":
    sys.exit(main())
