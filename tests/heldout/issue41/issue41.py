#!/usr/bin/env python3
"""Held-out cases of issue 41: run finding on real-like recordings.

Python 3 standard library only, fixed seeds, deterministic.

    issue41.py gen OUTDIR            write every case's input file and OUTDIR/truth.json
    issue41.py run BIN_DIR SCRATCH   generate, run `BIN_DIR/spindown fit --json` on each case, judge

Every input is made here from physics: J dω/dt = T_drive − (a + bω + cω²) (+ grade, a hand's
brake), integrated by RK4 with the stop as an event (ω reaching 0 ends the motion; the shaft
stays at rest while the drive cannot overcome the Coulomb torque), and then read the way the
device reads it (per-pulse ms timing, counts per window, rounding of a display, an ADC that
clips at 1023, a clock that restarts, a 10 Hz channel held in 1 kHz rows, ...).
`spindown simulate` is never used.  CASES.md says, case by case, what the truth is and why.
"""
import json
import math
import os
import random
import re
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor

TWO_PI = 2.0 * math.pi
RPM = TWO_PI / 60.0          # rad/s per rpm
LAB_J = 1.12687602e-5        # the lab's flywheel + rotor (handout)
LAB_KB = 1.0 / 123.569311    # the lab's K_b (1180 rpm/V)
LAB_A = 1.1389e-4            # the lab's Coulomb torque c4 (handout, 3 V experiment 1)
LAB_B = 1.822e-7             # the lab's viscous coefficient c3


# ----------------------------------------------------------------------------------------------
# physics

class Traj:
    """ω(t), θ(t) on a fixed grid from simulate(); stops[] are the instants ω reached 0."""

    def __init__(self, t0, dt, W, TH, stops, starts):
        self.t0, self.dt, self.W, self.TH = t0, dt, W, TH
        self.stops, self.starts = stops, starts
        self.t_end = t0 + dt * (len(W) - 1)

    def _idx(self, t):
        x = (t - self.t0) / self.dt
        i = int(math.floor(x))
        if i < 0:
            return 0, 0.0
        if i >= len(self.W) - 1:
            return len(self.W) - 2, 1.0
        return i, x - i

    def w(self, t):
        i, f = self._idx(t)
        return self.W[i] + (self.W[i + 1] - self.W[i]) * f

    def th(self, t):
        i, f = self._idx(t)
        return self.TH[i] + (self.TH[i + 1] - self.TH[i]) * f

    def time_of_index(self, i):
        return self.t0 + i * self.dt

    def t_fall(self, t_from, dv):
        """First time after t_from at which ω has fallen by dv below ω(t_from)."""
        target = self.w(t_from) - dv
        i, _ = self._idx(t_from)
        while i < len(self.W) - 1:
            if self.W[i + 1] <= target:
                w0, w1 = self.W[i], self.W[i + 1]
                f = 0.0 if w0 == w1 else (w0 - target) / (w0 - w1)
                return max(t_from, self.time_of_index(i) + f * self.dt)
            i += 1
        return self.t_end

    def t_floor(self, t_stop, v):
        """How long the shaft spends below speed v before it stops at t_stop."""
        i, _ = self._idx(t_stop)
        while i > 0 and self.W[i] < v:
            i -= 1
        if self.W[i] < v:
            return t_stop - self.t0
        w0, w1 = self.W[i], self.W[i + 1]
        f = 0.0 if w0 == w1 else (w0 - v) / (w0 - w1)
        return max(0.0, t_stop - (self.time_of_index(i) + f * self.dt))

    def crossings(self, step, phase=0.0, errs=None):
        """Times at which θ passes phase + k·step (+ errs[k mod n]: a disc's slot errors)."""
        TH, n = self.TH, len(self.TH)

        def level(k):
            return phase + k * step + (errs[k % len(errs)] if errs else 0.0)

        k = int(math.floor((TH[0] - phase) / step)) + 1
        while level(k) <= TH[0]:
            k += 1
        L = level(k)
        out = []
        i = 0
        while i < n - 1:
            if TH[i + 1] >= L:
                f = (L - TH[i]) / (TH[i + 1] - TH[i])
                out.append(self.t0 + (i + f) * self.dt)
                k += 1
                L = level(k)
                continue
            i += 1
        return out


def simulate(J, fric, drive, t_end, dt=1e-3, t0=0.0, w0=0.0, th0=0.0):
    """RK4 of J dω/dt = drive(t, ω, θ) − fric(t, ω) for ω ≥ 0, the stop as an event.

    fric(t, ω) ≥ 0 is the friction torque's magnitude; at rest the shaft starts only when the
    drive exceeds fric(t, 0) (the Coulomb torque), else it stays."""
    n = int(round((t_end - t0) / dt))
    W = [w0]
    TH = [th0]
    stops, starts = [], []
    w, th = w0, th0

    def f(t, w_, th_):
        return (drive(t, w_, th_) - fric(t, max(w_, 0.0))) / J

    for i in range(n):
        t = t0 + i * dt
        if w <= 0.0:
            w = 0.0
            if drive(t, 0.0, th) <= fric(t, 0.0):
                W.append(0.0)
                TH.append(th)
                continue
            starts.append(t)
        k1w = f(t, w, th)
        k1t = w
        k2w = f(t + dt / 2, w + dt / 2 * k1w, th + dt / 2 * k1t)
        k2t = w + dt / 2 * k1w
        k3w = f(t + dt / 2, w + dt / 2 * k2w, th + dt / 2 * k2t)
        k3t = w + dt / 2 * k2w
        k4w = f(t + dt, w + dt * k3w, th + dt * k3t)
        k4t = w + dt * k3w
        wn = w + dt / 6 * (k1w + 2 * k2w + 2 * k3w + k4w)
        thn = th + dt / 6 * (k1t + 2 * k2t + 2 * k3t + k4t)
        if wn < 0.0:
            frac = w / (w - wn) if w > 0 else 0.0
            stops.append(t + frac * dt)
            thn = th + w * frac * dt / 2
            wn = 0.0
        w, th = wn, thn
        W.append(w)
        TH.append(th)
    return Traj(t0, dt, W, TH, stops, starts)


def dc_motor(V_of_t, Kt, Kb, R):
    """A DC motor on a supply V(t): torque Kt (V − Kb ω)/R while powered, 0 once cut (open)."""
    def drive(t, w, th):
        V = V_of_t(t)
        return Kt * (V - Kb * w) / R if V > 0 else 0.0
    return drive


def servo(profile, dprofile, J, fric, kp, enabled):
    """A speed-controlled drive (servo, cruise control, a rider holding cadence)."""
    def drive(t, w, th):
        if not enabled(t):
            return 0.0
        return fric(t, w) + J * (dprofile(t) + kp * (profile(t) - w))
    return drive


def cos_ramp(t, t0, T, v0, v1):
    if t <= t0:
        return v0
    if t >= t0 + T:
        return v1
    return v0 + (v1 - v0) * (1 - math.cos(math.pi * (t - t0) / T)) / 2


def dcos_ramp(t, t0, T, v0, v1):
    if t <= t0 or t >= t0 + T:
        return 0.0
    return (v1 - v0) * math.pi / (2 * T) * math.sin(math.pi * (t - t0) / T)


def first_stop_after(tr, t):
    s = [x for x in tr.stops if x > t]
    if not s:
        raise RuntimeError("generator bug: the coast never stopped in the simulated span")
    return s[0]


# ----------------------------------------------------------------------------------------------
# how devices read

def arduino_millis(t):
    """millis() of an ATmega328P at 16 MHz: timer0 overflows every 1.024 ms, millis() adds 1 and
    every ~42nd tick 2 (its fraction counter), so it is floor(ticks · 1.024)."""
    ticks = math.floor(t / 1.024e-3)
    return int(math.floor(ticks * 1.024 + 1e-9))


def round_half_up(v, nd):
    s = 10 ** nd
    return math.floor(v * s + 0.5) / s


def fmt2(v):
    """Serial.print(float): 2 decimals, rounded half up (Arduino's printFloat adds 0.005)."""
    r = round_half_up(v, 2)
    if r == 0:
        r = 0.0
    return "%.2f" % r


def adc10(v):
    """analogRead on a 5 V reference: floor(V·1024/5), clipped to 0…1023."""
    code = int(math.floor(v * 1024.0 / 5.0))
    return min(1023, max(0, code))


def lab_sample_times(rng, t_end, t_first=0.012, period=20.21e-3, jitter=0.03e-3):
    """loop(): analogRead, print, delay(20): ~20.2 ms a loop, printed by millis()."""
    out = []
    t = t_first
    while t < t_end:
        out.append(t)
        t += period + rng.gauss(0.0, jitter)
    return out


PUTTY = "=~=~=~=~=~=~=~=~=~=~=~= PuTTY log %s =~=~=~=~=~=~=~=~=~=~=~=\r\n"


def median(xs):
    s = sorted(xs)
    n = len(s)
    return s[n // 2] if n % 2 else 0.5 * (s[n // 2 - 1] + s[n // 2])


def local_period(times, t, span=1.0):
    """The median interval between readings within ±span of t."""
    sel = [x for x in times if t - span <= x <= t + span]
    d = [b - a for a, b in zip(sel, sel[1:]) if b > a]
    return median(d) if d else 0.02


# ----------------------------------------------------------------------------------------------
# truth helpers

def run_truth(t_cut, tol_cut, t_stop, tol_stop, **kw):
    d = {"t_cut": t_cut, "tol_cut": tol_cut, "t_stop": t_stop, "tol_stop": tol_stop,
         "stop_mode": "stopped"}
    d.update(kw)
    return d


def r4(x):
    return None if x is None else float("%.6g" % x)


# ----------------------------------------------------------------------------------------------
# the lab's rig: motor and flywheel of the handout, read by the lab's sketch

def lab_rig_traj(V_sched, t_end, brake=None, dt=1e-3):
    """V_sched: list of (t_on, t_off, volts). brake(t) adds a hand's friction torque."""
    R = 2.5

    def V_of_t(t):
        for (a_, b_, v) in V_sched:
            if a_ <= t < b_:
                return v
        return 0.0

    drive = dc_motor(V_of_t, LAB_KB, LAB_KB, R)
    if brake is None:
        fric = lambda t, w: LAB_A + LAB_B * w
    else:
        fric = lambda t, w: LAB_A + LAB_B * w + brake(t)
    return simulate(LAB_J, fric, drive, t_end, dt=dt), V_of_t


def lab_reading(rng, tr, t, connected, noise=0.004, ripple=0.005, pickup=0.0, terminal=None):
    """What A0 sees: back-EMF K_b ω with commutator ripple (7 slots) and noise when the pin is
    on the motor, 0 when the student holds it to ground; `terminal` overrides (supply on)."""
    if terminal is not None:
        v = terminal + rng.gauss(0.0, noise)
    elif connected:
        w = tr.w(t)
        v = LAB_KB * w * (1 + ripple * math.sin(7 * tr.th(t))) + rng.gauss(0.0, noise)
        v += pickup * math.sin(TWO_PI * 50.0 * t + 0.3)
    else:
        v = rng.gauss(0.0, 0.0008)
    return adc10(v) * 5.0 / 1023.0


def lab_sigma(noise, ripple_v=0.0, pickup=0.0, q=0.01):
    return math.sqrt(noise ** 2 + ripple_v ** 2 / 2 + pickup ** 2 / 2 + q ** 2 / 12)


def lab_tol_stop(tr, t_stop, dtp, sigma, q=0.01):
    v_vis = max(q, 3 * sigma)
    return 2 * dtp + tr.t_floor(t_stop, v_vis / LAB_KB), v_vis


# ----------------------------------------------------------------------------------------------
# cases

def case_hall(name, V, t_cut, seed):
    """1. Per-pulse Hall rpm: one magnet, the sketch prints millis<TAB>60000/Δms per pulse."""
    rng = random.Random(seed)
    t_on = 1.0
    tr, _ = lab_rig_traj([(t_on, t_cut, V)], t_cut + 34.0)
    T_stop = first_stop_after(tr, t_cut)
    pulses = tr.crossings(TWO_PI, phase=1.0)
    lines = []
    times = []
    last_ms = 0
    deltas = []
    for tp in pulses:
        ms = arduino_millis(tp)                      # the ISR's millis()
        d = ms - last_ms
        last_ms = ms
        if d <= 0:
            continue
        t_print = tp + rng.uniform(0.0, 0.6e-3)     # loop() prints shortly after
        pm = arduino_millis(t_print)
        lines.append("%d\t%d\r\n" % (pm, 60000 // d))
        times.append(pm / 1000.0)
        deltas.append(d)
    w_cut = tr.w(t_cut)
    P = TWO_PI / w_cut * 1000.0                      # ms per revolution at the cut
    q_rpm = 60000.0 / math.floor(P) - 60000.0 / math.ceil(P)
    q = q_rpm * RPM                                  # the reading's step at the cut, rad/s
    # the reading alternates between neighbouring integer periods: its error is ±q/2, so
    # 2σ ≈ q; the coast is resolved once it has fallen by one step
    t_res = tr.t_fall(t_cut, q) - t_cut
    tol_cut = 2 * P / 1000.0 + t_res
    t_last = times[-1]
    d_last = deltas[-1] / 1000.0
    truth = {
        "n_runs": 1,
        "runs": [run_truth(t_cut, tol_cut, T_stop, None, stop_mode="stopped_or_lost",
                           stop_window=[t_last - 2 * d_last, T_stop + 2 * d_last],
                           t_last_data=t_last, lost_min_end=t_last - 2 * d_last,
                           omega0=[w_cut, q])],
        "notes": {"omega_cut_rad_s": w_cut, "rpm_cut": w_cut / RPM, "period_ms_at_cut": P,
                  "step_rpm_at_cut": q_rpm, "t_res_s": t_res, "last_pulse_s": t_last,
                  "last_reading_rpm": 60000 // deltas[-1], "rows": len(lines)},
    }
    return {"name": name, "file": name + ".txt", "text": "".join(lines),
            "options": ["--time-unit", "ms", "--value-unit", "rpm"], "truth": truth}


def case_encoder(seed=2):
    """2. Encoder counts per 50 ms window: a 24-slot disc and an LM393 module, rpm = counts·50."""
    name = "encoder-counts-50ms"
    rng = random.Random(seed)
    J, a, b = 2.0e-3, 0.012, 4e-5
    Kt = Kb = 0.14
    R, V = 3.0, 24.0
    t_on, t_cut = 1.5, 7.3183
    drive = dc_motor(lambda t: V if t_on <= t < t_cut else 0.0, Kt, Kb, R)
    fric = lambda t, w: a + b * w
    t_end = t_cut + 30.0
    tr = simulate(J, fric, drive, t_end)
    T_stop = first_stop_after(tr, t_cut)
    slots, Wd = 24, 0.05
    pitch = TWO_PI / slots
    errs = [rng.gauss(0.0, 0.015 * pitch) for _ in range(slots)]
    edges = tr.crossings(pitch, phase=0.2, errs=errs)
    step = 60.0 / (slots * Wd)                   # 50 rpm per count
    lines = ["time_ms,speed_rpm\r\n"]
    times = []
    j = 0
    k = 1
    while k * Wd <= t_end - 0.5:
        t1 = k * Wd
        c = 0
        while j < len(edges) and edges[j] <= t1:
            if edges[j] > t1 - Wd:
                c += 1
            j += 1
        ms = int(round(t1 * 1000)) + (1 if rng.random() < 0.3 else 0)
        lines.append("%d,%.1f\r\n" % (ms, c * step))
        times.append(ms / 1000.0)
        k += 1
    q = step * RPM
    t_res = tr.t_fall(t_cut, q) - t_cut          # ±1 count: 2σ ≈ one count
    tol_cut = 2 * Wd + t_res
    t_floor = tr.t_floor(T_stop, q)               # below one count per window nothing shows
    tol_stop = 2 * Wd + t_floor
    truth = {"n_runs": 1, "runs": [run_truth(t_cut, tol_cut, T_stop, tol_stop)],
             "notes": {"rpm_cut": tr.w(t_cut) / RPM, "step_rpm": step, "t_res_s": t_res,
                       "t_floor_s": t_floor}}
    return {"name": name, "file": name + ".csv", "text": "".join(lines),
            "options": ["--time-column", "time_ms", "--value-column", "speed_rpm",
                        "--time-unit", "ms", "--value-unit", "rpm", "--inertia", "2e-3"],
            "truth": truth}


def case_display(seed=3):
    """3. A tachogenerator read by a logging multimeter: 10 readings/s, 2 decimals (0.01 V)."""
    name = "two-decimal-display"
    rng = random.Random(seed)
    J, a, b = 3e-6, 6e-5, 3e-8
    Kt = Kb = 0.0025
    R, V = 4.0, 3.0
    Kg = 0.00075                                   # tachogenerator V·s/rad
    offset, sigma = 0.0035, 0.0012
    t_on, t_cut = 3.0, 14.62
    drive = dc_motor(lambda t: V if t_on <= t < t_cut else 0.0, Kt, Kb, R)
    tr = simulate(J, lambda t, w: a + b * w, drive, t_cut + 62.0)
    T_stop = first_stop_after(tr, t_cut)
    t_end = T_stop + 15.0
    lines = ["Time [s],Voltage [V]\r\n"]
    k = 0
    last = -1.0
    while True:
        t = 0.1 * k + rng.gauss(0.0, 0.004)
        k += 1
        if t > t_end:
            break
        if t <= last:
            continue
        last = t
        v = Kg * tr.w(t) + offset + rng.gauss(0.0, sigma)
        lines.append("%.3f,%s\r\n" % (t, fmt2(v)))
    q = 0.01
    s_eff = math.sqrt(sigma ** 2 + q ** 2 / 12)
    r = max(q, 2 * s_eff)
    t_res = tr.t_fall(t_cut, r / Kg) - t_cut
    tol_cut = 2 * 0.1 + t_res
    v_vis = max(q, 3 * s_eff)
    t_floor = tr.t_floor(T_stop, v_vis / Kg)
    tol_stop = 2 * 0.1 + t_floor
    truth = {"n_runs": 1, "runs": [run_truth(t_cut, tol_cut, T_stop, tol_stop)],
             "notes": {"volts_cut": Kg * tr.w(t_cut) + offset, "t_res_s": t_res,
                       "t_floor_s": t_floor, "sigma_eff_V": s_eff}}
    return {"name": name, "file": name + ".csv", "text": "".join(lines),
            "options": ["--time-column", "Time [s]", "--value-column", "Voltage [V]",
                        "--time-unit", "s", "--value-unit", "V", "--kb", "0.00075",
                        "--inertia", "3e-6"],
            "truth": truth}


def lab_file(rng, tr, times, reading_of_t, putty=None, drop_idx=()):
    lines = []
    if putty:
        lines.append(PUTTY % putty)
    vals = []
    for i, t in enumerate(times):
        v = 0.0 if i in drop_idx else reading_of_t(t)
        vals.append(v)
        lines.append("%d\t%s\r\n" % (arduino_millis(t), fmt2(v)))
    return "".join(lines), vals


def case_adc_top(name, V, t_cut, seed, terminal_all_along, regulated=False, clean=False,
                 putty=None):
    """4. The lab's sketch with A0 straight on the motor: the ADC clips at 1023 (5.00 V)."""
    rng = random.Random(seed)
    t_on = 1.0
    tr0, _ = lab_rig_traj([(t_on, t_cut, V)], t_cut + 60.0)
    T_stop = first_stop_after(tr0, t_cut)
    t_end = T_stop + 4.0
    times = lab_sample_times(rng, t_end)
    noise = 0.004

    def reading(t):
        if terminal_all_along:
            if t_on <= t < t_cut:            # supply on: the terminal is the supply
                return lab_reading(rng, tr0, t, True, noise=0.0015 if regulated else noise,
                                   terminal=V)
            if t < t_on:
                return lab_reading(rng, tr0, t, False)
            return lab_reading(rng, tr0, t, True, noise=noise)
        # the handout's step 6: A0 goes onto the motor at the power-off
        return lab_reading(rng, tr0, t, t >= t_cut, noise=noise)

    text, vals = lab_file(rng, tr0, times, reading, putty=putty)
    dtp = local_period(times, t_cut)
    pinned = [t for t, v in zip(times, vals) if v >= 5.0 - 1e-9]
    after = [(t, v) for t, v in zip(times, vals) if t > t_cut]
    t_leave = next((t for t, v in after if v < 5.0 - 1e-9), None)
    s_eff = lab_sigma(noise, ripple_v=0.0)
    tol_stop, v_vis = lab_tol_stop(tr0, T_stop, dtp, s_eff)
    E_cut = LAB_KB * tr0.w(t_cut)
    if terminal_all_along and not clean:
        # the cut is hidden under the clipped supply: it lies somewhere in the pinned stretch
        run = run_truth(t_cut, None, T_stop, tol_stop,
                        cut_range=[t_cut - 2 * dtp, t_leave + 2 * dtp])
    else:
        # a jump (0 → back-EMF) or the IR drop (supply → back-EMF), many σ in one sample
        run = run_truth(t_cut, 2 * dtp, T_stop, tol_stop)
    truth = {"n_runs": 1, "runs": [run], "top_mention": not clean,
             "notes": {"supply_V": V, "backemf_at_cut_V": E_cut, "period_s": dtp,
                       "pinned_samples": len(pinned),
                       "pinned_from_s": pinned[0] if pinned else None,
                       "pinned_to_s": pinned[-1] if pinned else None,
                       "t_leave_s": t_leave, "v_vis_V": v_vis}}
    return {"name": name, "file": name + ".txt", "text": text, "options": [], "truth": truth}


def case_spin_bike(seed=5):
    """5. A spin bike's coast-down exports, concatenated: the clock restarts at 0 per coast."""
    name = "clock-restart-spin-bike"
    rng = random.Random(seed)
    J, a = 0.36, 0.12
    teeth = 60
    pitch = TWO_PI / teeth
    errs = [rng.gauss(0.0, 0.003 * pitch) for _ in range(teeth)]
    dT = 0.25
    timeout = 2.0
    # (kind, rpm at the cut, viscous b of the magnetic brake, local cut time, how it ends)
    segs = [("pedal", 440.0, 0.015, 4.0, ("after_stop", 5.0)),
            ("at_start", 410.0, 0.020, 0.0, ("after_stop", 3.5)),
            ("at_start", 460.0, 0.012, 0.0, ("after_last_edge", 1.5)),
            ("pedal", 380.0, 0.025, 3.0, ("after_last_edge", 1.5)),
            ("at_start", 450.0, 0.018, 0.0, ("after_stop", 4.0))]
    lines = ["time_s,flywheel_rpm\r\n"]
    runs = []
    seg_notes = []
    for si, (kind, rpm0, b, c_loc, (end_kind, end_s)) in enumerate(segs):
        w_set = rpm0 * RPM
        fc = 2 * (rpm0 / 5.2) / 60.0                # two pedal strokes per crank turn
        eps = 0.012 if kind == "pedal" else 0.0
        fric = lambda t, w, b=b: a + b * w
        prof = lambda t, w_set=w_set, eps=eps, fc=fc: w_set * (1 + eps * math.sin(TWO_PI * fc * t))
        dprof = lambda t, w_set=w_set, eps=eps, fc=fc: w_set * eps * TWO_PI * fc * math.cos(TWO_PI * fc * t)
        drive = servo(prof, dprof, J, fric, 60.0, lambda t, c_loc=c_loc: t < c_loc)
        tr = simulate(J, fric, drive, c_loc + 80.0, dt=1e-3, t0=-3.0, w0=prof(-3.0))
        T_stop = first_stop_after(tr, c_loc)
        edges = tr.crossings(pitch, phase=0.0, errs=errs)
        last_edge = max(e for e in edges if e <= T_stop + 1e-9)
        prev_edge = max(e for e in edges if e < last_edge)
        seg_end = T_stop + end_s if end_kind == "after_stop" else last_edge + end_s
        if end_kind == "after_last_edge" and not (T_stop < seg_end and seg_end - last_edge < timeout):
            raise RuntimeError("generator bug: segment %d does not end as designed" % si)
        k = 0
        j = 0
        times = []
        vals = []
        last_local = 0.0
        while k * dT <= seg_end + 1e-9:
            t = k * dT
            while j < len(edges) and edges[j] <= t:
                j += 1
            if j >= 2 and t - edges[j - 1] <= timeout:
                v = 1.0 / (edges[j - 1] - edges[j - 2])   # 60 teeth: rpm = 1/Δs
            else:
                v = 0.0
            lines.append("%.2f,%.1f\r\n" % (t, v))
            times.append(t)
            vals.append(v)
            last_local = t
            k += 1
        # tolerances
        if kind == "pedal":
            A = eps * rpm0                                # pedal-stroke ripple amplitude, rpm
            r = max(0.1, 2 * A) * RPM
            t_res = tr.t_fall(c_loc, r) - c_loc
            tol_cut = 2 * dT + t_res
        else:
            t_res = 0.0
            tol_cut = 2 * dT                              # the export begins at the cut
        t_floor = T_stop - prev_edge                      # the last reading averages from here
        tol_stop = 2 * dT + t_floor
        runs.append(run_truth(c_loc, tol_cut, T_stop, tol_stop, segment=si,
                              seg_last_local=last_local))
        seg_notes.append({"segment": si + 1, "kind": kind, "rpm_cut": rpm0,
                          "cut_local_s": c_loc, "stop_local_s": T_stop,
                          "last_reading_rpm": vals[-1],
                          "last_nonzero_rpm": max([v for v in vals[-12:]] + [0.0]),
                          "ends": end_kind, "last_local_s": last_local,
                          "t_floor_s": t_floor})
    truth = {"n_runs": len(segs), "runs": runs, "clock_restarts": True,
             "notes": {"segments": seg_notes}}
    return {"name": name, "file": name + ".csv", "text": "".join(lines),
            "options": ["--time-column", "time_s", "--value-column", "flywheel_rpm",
                        "--time-unit", "s", "--value-unit", "rpm", "--inertia", "0.36"],
            "truth": truth}


def case_held_channel(seed=6):
    """6. A 1 kHz DAQ log whose speed column is a drive's 10 Hz CAN value, held between messages."""
    name = "slow-channel-held-1khz"
    rng = random.Random(seed)
    J, a, b, c = 0.004, 0.02, 1.0e-4, 2e-8
    Kt = 0.1
    t_cut = 11.437
    fric = lambda t, w: a + b * w + c * w * w
    prof = lambda t: cos_ramp(t, 2.0, 2.0, 0.0, 300.0)
    dprof = lambda t: dcos_ramp(t, 2.0, 2.0, 0.0, 300.0)
    drive = servo(prof, dprof, J, fric, 80.0, lambda t: 2.0 <= t < t_cut)
    tr = simulate(J, fric, drive, t_cut + 45.0)
    T_stop = first_stop_after(tr, t_cut)
    t_end = T_stop + 5.0
    sig = 2.0
    # CAN messages every 100 ms (±3 ms arrival jitter): the drive's speed estimate, whole rpm,
    # 0 below 5 rpm (the drive's zero clamp)
    msgs = []
    j = 0
    while True:
        u = 0.0371 + 0.1 * j + rng.uniform(-0.003, 0.003)
        if u > t_end:
            break
        rpm = tr.w(u) / RPM
        msgs.append((u, 0 if rpm < 5.0 else int(round(rpm + rng.gauss(0.0, sig)))))
        j += 1
    lines = ["Time [s],Current [A],Speed [rpm]\r\n"]
    mi = -1
    n = int(t_end * 1000)
    for i in range(n + 1):
        t = i / 1000.0
        while mi + 1 < len(msgs) and msgs[mi + 1][0] <= t:
            mi += 1
        spd = msgs[mi][1] if mi >= 0 else 0
        torque = drive(t, tr.w(t), tr.th(t))
        cur = abs(torque) / Kt + rng.gauss(0.0, 0.02)
        lines.append("%.3f,%.3f,%d\n" % (t, cur, spd))
    q = 1.0
    s_eff = math.sqrt(sig ** 2 + q ** 2 / 12)
    r = max(q, 2 * s_eff) * RPM
    t_res = tr.t_fall(t_cut, r) - t_cut
    tol_cut = 2 * 0.1 + t_res
    v_vis = max(5.0, 3 * s_eff) * RPM
    t_floor = tr.t_floor(T_stop, v_vis)
    tol_stop = 2 * 0.1 + t_floor
    truth = {"n_runs": 1, "runs": [run_truth(t_cut, tol_cut, T_stop, tol_stop)],
             "period": [0.075, 0.135], "noise": {"value": s_eff, "unit": "rpm",
                                                 "lo": 0.5, "hi": 2.0},
             "notes": {"rpm_cut": tr.w(t_cut) / RPM, "readings": len(msgs), "rows": n + 1,
                       "sigma_eff_rpm": s_eff, "t_res_s": t_res, "t_floor_s": t_floor}}
    return {"name": name, "file": name + ".csv", "text": "".join(lines),
            "options": ["--time-column", "Time [s]", "--value-column", "Speed [rpm]",
                        "--time-unit", "s", "--value-unit", "rpm", "--inertia", "0.004"],
            "truth": truth}


def case_startup_blip(seed=7):
    """7. A 200 W dyno: the servo's start-up jog (powered up and powered down), then the run."""
    name = "powered-startup-blip"
    rng = random.Random(seed)
    J, a, b = 0.0025, 0.03, 6e-5
    Kt = 0.08
    tb = 2.0                                       # blip: up 0.4 s, down 0.35 s (S-curves)
    pk = 200.0 * RPM
    t_up, t_dn = 0.15, 0.25
    en_b = (tb - 0.3, tb + t_up + t_dn + 0.5)
    t_run, ramp, top = 5.0, 3.0, 3000.0 * RPM
    t_cut = 13.2731
    fric = lambda t, w: a + b * w

    def prof(t):
        if t < tb + t_up:
            return cos_ramp(t, tb, t_up, 0.0, pk)
        if t < t_run:
            return cos_ramp(t, tb + t_up, t_dn, pk, 0.0)
        return cos_ramp(t, t_run, ramp, 0.0, top)

    def dprof(t):
        if t < tb + t_up:
            return dcos_ramp(t, tb, t_up, 0.0, pk)
        if t < t_run:
            return dcos_ramp(t, tb + t_up, t_dn, pk, 0.0)
        return dcos_ramp(t, t_run, ramp, 0.0, top)

    enabled = lambda t: (en_b[0] <= t < en_b[1]) or (t_run - 0.2 <= t < t_cut)
    drive = servo(prof, dprof, J, fric, 150.0, enabled)
    tr = simulate(J, fric, drive, t_cut + 30.0)
    T_stop = first_stop_after(tr, t_cut)
    t_end = T_stop + 4.0
    lines = ["t [s],I [A],n [rpm]\r\n"]
    blip_i = []
    k = 0
    while k * 0.01 <= t_end:
        t = k * 0.01
        w = tr.w(t)
        # the drive's encoder estimate: 0 below 1 rpm (less than a count per 10 ms)
        rpm = 0.0 if w / RPM < 1.0 else max(0.0, w / RPM + rng.gauss(0.0, 1.0))
        if enabled(t):
            iq = drive(t, w, tr.th(t)) / Kt
            idd = 3.0 if en_b[0] <= t < en_b[1] else 0.0   # the start-up's alignment current
            cur = math.hypot(iq, idd) + rng.gauss(0.0, 0.03)
        else:
            cur = rng.gauss(0.0, 0.02)
        if tb - 0.3 <= t < tb + t_up + t_dn + 0.5:
            blip_i.append(cur)
        lines.append("%.2f,%.2f,%.1f\r\n" % (t, cur, rpm))
        k += 1
    q, sig = 0.1, 1.0
    r = max(q, 2 * sig) * RPM
    t_res = tr.t_fall(t_cut, r) - t_cut
    tol_cut = 2 * 0.01 + t_res
    v_vis = max(q, 3 * sig) * RPM
    t_floor = tr.t_floor(T_stop, v_vis)
    tol_stop = 2 * 0.01 + t_floor
    # how far the jog's fall is from a free coast of this machine
    free_decel = (a + b * pk) / J
    jog_decel = pk * math.pi / (2 * t_dn)
    truth = {"n_runs": 1, "runs": [run_truth(t_cut, tol_cut, T_stop, tol_stop)],
             "notes": {"blip_peak_rpm": pk / RPM, "blip_window_s": [tb, tb + t_up + t_dn],
                       "blip_current_A": [min(blip_i), max(blip_i)], "free_decel_at_peak": free_decel,
                       "jog_peak_decel": jog_decel, "rpm_cut": tr.w(t_cut) / RPM,
                       "t_res_s": t_res, "t_floor_s": t_floor}}
    return {"name": name, "file": name + ".csv", "text": "".join(lines),
            "options": ["--time-column", "t [s]", "--value-column", "n [rpm]",
                        "--time-unit", "s", "--value-unit", "rpm", "--inertia", "0.0025"],
            "truth": truth}


def case_ripple(seed=8):
    """E1. A flywheel whose encoder disc sits off-centre: once-per-revolution ripple, 500 Hz."""
    name = "per-rev-ripple-500hz"
    rng = random.Random(seed)
    J, a, b, c = 0.01, 0.05, 2e-4, 1e-7
    t_cut = 12.0417
    fric = lambda t, w: a + b * w + c * w * w
    top = 3000.0 * RPM
    prof = lambda t: cos_ramp(t, 1.0, 4.0, 0.0, top)
    dprof = lambda t: dcos_ramp(t, 1.0, 4.0, 0.0, top)
    drive = servo(prof, dprof, J, fric, 100.0, lambda t: 1.0 <= t < t_cut)
    tr = simulate(J, fric, drive, t_cut + 50.0)
    T_stop = first_stop_after(tr, t_cut)
    t_end = T_stop + 3.0
    eps, sig = 0.004, 1.0
    lines = ["time_s,wheel_rpm\n"]
    k = 0
    while k * 0.002 <= t_end:
        t = k * 0.002
        w = tr.w(t)
        if w <= 0.0:
            v = 0.0
        else:
            v = max(0.0, w / RPM * (1 + eps * math.cos(tr.th(t) + 0.7)) + rng.gauss(0.0, sig))
        lines.append("%.3f,%.1f\n" % (t, v))
        k += 1
    A = eps * tr.w(t_cut) / RPM
    r = max(0.1, 2 * sig, 2 * A) * RPM
    t_res = tr.t_fall(t_cut, r) - t_cut
    tol_cut = 2 * 0.002 + t_res
    v_vis = max(0.1, 3 * sig) * RPM
    t_floor = tr.t_floor(T_stop, v_vis)
    tol_stop = 2 * 0.002 + t_floor
    # the 0.25-s means of the true reading fall monotonically after the cut (checked here)
    means = []
    t = t_cut
    while t + 0.25 < T_stop:
        s = 0.0
        for i in range(125):
            tt = t + i * 0.002
            s += tr.w(tt) * (1 + eps * math.cos(tr.th(tt) + 0.7))
        means.append(s / 125)
        t += 0.25
    mono = all(m1 < m0 for m0, m1 in zip(means, means[1:]))
    if not mono:
        raise RuntimeError("generator bug: ripple case's 0.25-s means do not fall monotonically")
    truth = {"n_runs": 1, "runs": [run_truth(t_cut, tol_cut, T_stop, tol_stop)],
             "notes": {"rpm_cut": tr.w(t_cut) / RPM, "ripple_amplitude_rpm": A,
                       "noise_rpm": sig, "t_res_s": t_res, "t_floor_s": t_floor,
                       "quarter_second_means_fall_monotonically": mono}}
    return {"name": name, "file": name + ".csv", "text": "".join(lines),
            "options": ["--time-column", "time_s", "--value-column", "wheel_rpm",
                        "--time-unit", "s", "--value-unit", "rpm", "--inertia", "0.01"],
            "truth": truth}


def case_grade(seed=9):
    """E2. An electric cart's coast-down on a track with a dip: an unpowered speed-up."""
    name = "track-grade-speedup"
    rng = random.Random(seed)
    m, r_w, g = 500.0, 0.25, 9.81
    J = m * r_w * r_w + 0.75                       # 32.0 kg·m² at the wheel
    a, b, c = 0.012 * m * g * r_w, 0.3, 0.5 * 1.2 * 0.9 * r_w ** 3
    t_cut = 8.3
    v0 = 30.0 / 3.6
    w_set = v0 / r_w

    def grade(x):                                  # rise over run, + uphill
        if 140.0 <= x < 170.0:
            return -0.025
        if 170.0 <= x < 200.0:
            return 0.010
        return 0.0

    fric = lambda t, w: a + b * w + c * w * w
    prof = lambda t: w_set * (1 + 0.003 * math.sin(TWO_PI * t / 3.1))
    dprof = lambda t: w_set * 0.003 * TWO_PI / 3.1 * math.cos(TWO_PI * t / 3.1)
    cruise = servo(prof, dprof, J, fric, 5.0, lambda t: t < t_cut)

    def drive(t, w, th):
        gt = -m * g * r_w * math.sin(math.atan(grade(r_w * th)))
        return cruise(t, w, th) + gt - (gt if t < t_cut else 0.0)

    tr = simulate(J, fric, drive, t_cut + 70.0, dt=2e-3, w0=w_set)
    T_stop = first_stop_after(tr, t_cut)
    x_stop = r_w * tr.th(T_stop)
    if grade(x_stop) != 0.0:
        raise RuntimeError("generator bug: the cart stops on a slope")
    # the speed-up in the dip
    wmin, wmax, seen_min = 1e9, 0.0, False
    t = t_cut
    rise = 0.0
    while t < T_stop:
        w = tr.w(t)
        if w < wmin:
            wmin = w
        rise = max(rise, w - wmin)
        t += 0.05
    t_end = T_stop + 5.0
    sig = 0.3
    lines = ["Time [s],Wheel speed [rpm]\r\n"]
    k = 0
    while True:
        t = 0.1 * k + rng.uniform(-0.002, 0.002)
        if t > t_end:
            break
        k += 1
        if t < 0:
            continue
        w = tr.w(t)
        v = 0.0 if w <= 0 else max(0.0, w / RPM + rng.gauss(0.0, sig))
        lines.append("%.3f,%.1f\r\n" % (t, v))
    A = 0.003 * w_set / RPM
    rr = max(0.1, 2 * sig, 2 * A) * RPM
    t_res = tr.t_fall(t_cut, rr) - t_cut
    tol_cut = 2 * 0.1 + t_res
    v_vis = max(0.1, 3 * sig) * RPM
    t_floor = tr.t_floor(T_stop, v_vis)
    tol_stop = 2 * 0.1 + t_floor
    truth = {"n_runs": 1, "runs": [run_truth(t_cut, tol_cut, T_stop, tol_stop)],
             "notes": {"rpm_cut": w_set / RPM, "speedup_rpm": rise / RPM,
                       "speedup_in_noise_sd": rise / RPM / sig, "x_stop_m": x_stop,
                       "t_res_s": t_res, "t_floor_s": t_floor}}
    return {"name": name, "file": name + ".csv", "text": "".join(lines),
            "options": ["--time-column", "Time [s]", "--value-column", "Wheel speed [rpm]",
                        "--time-unit", "s", "--value-unit", "rpm"],
            "truth": truth}


def case_hand_brake(seed=10):
    """E3. The lab's rig: a student grabs the flywheel 15 s into the coast."""
    name = "hand-brake-at-end"
    rng = random.Random(seed)
    V, t_on, t_cut = 3.5, 1.0, 6.1327
    tb = t_cut + 15.0
    brake = lambda t: 0.0 if t < tb else 2.5e-3 * min(1.0, (t - tb) / 0.15)
    tr, _ = lab_rig_traj([(t_on, t_cut, V)], t_cut + 30.0, brake=brake)
    T_stop = first_stop_after(tr, t_cut)
    times = lab_sample_times(rng, T_stop + 5.0)
    text, _ = lab_file(rng, tr, times, lambda t: lab_reading(rng, tr, t, t >= t_cut))
    dtp = local_period(times, t_cut)
    s_eff = lab_sigma(0.004)
    tol_stop, v_vis = lab_tol_stop(tr, T_stop, local_period(times, T_stop), s_eff)
    truth = {"n_runs": 1, "runs": [run_truth(t_cut, 2 * dtp, T_stop, tol_stop)],
             "notes": {"brake_from_s": tb, "omega_at_brake": tr.w(tb),
                       "free_stop_would_be_s": None, "period_s": dtp}}
    return {"name": name, "file": name + ".txt", "text": text, "options": [], "truth": truth}


def case_bursts(seed=11):
    """E4. A Raspberry Pi logging a laser tachometer at 50 Hz, losing samples in bursts."""
    name = "logger-burst-drops"
    rng = random.Random(seed)
    J, a, b = 5e-5, 6e-4, 4e-7
    Kt = Kb = 0.01
    R, V = 2.0, 6.0
    t_on, t_cut = 1.0, 9.0613
    drive = dc_motor(lambda t: V if t_on <= t < t_cut else 0.0, Kt, Kb, R)
    tr = simulate(J, lambda t, w: a + b * w, drive, t_cut + 60.0)
    T_stop = first_stop_after(tr, t_cut)
    t_end = T_stop + 4.0
    gaps_rel = [(-4.0, -3.5), (-0.10, 0.30), (3.0, 3.5), (7.2, 7.36), (12.0, 12.8),
                (18.5, 19.9), (25.1, 25.3), (31.0, 31.6)]
    gaps = [(t_cut + x, t_cut + y) for x, y in gaps_rel] + [(T_stop - 0.3, T_stop + 0.4)]
    lines = ["elapsed_s,rpm\n"]
    times = []
    k = 0
    while True:
        t = 0.02 * k + rng.gauss(0.0, 0.0015)
        k += 1
        if t > t_end:
            break
        if t < 0 or any(g0 <= t < g1 for g0, g1 in gaps):
            continue
        rpm = tr.w(t) / RPM
        sd = math.sqrt(1.0 + (0.001 * rpm) ** 2)
        v = 0.0 if rpm < 10.0 else max(0.0, rpm + rng.gauss(0.0, sd))
        lines.append("%.3f,%.1f\n" % (t, v))
        times.append(t)
    rpm_cut = tr.w(t_cut) / RPM
    sd_cut = math.sqrt(1.0 + (0.001 * rpm_cut) ** 2)
    r = max(0.1, 2 * sd_cut) * RPM
    t_res = tr.t_fall(t_cut, r) - t_cut
    tol_cut = 2 * 0.02 + 0.40 + t_res
    v_vis = max(10.0, 3 * 1.0) * RPM
    t_floor = tr.t_floor(T_stop, v_vis)
    tol_stop = 2 * 0.02 + t_floor + 0.70
    truth = {"n_runs": 1, "runs": [run_truth(t_cut, tol_cut, T_stop, tol_stop)],
             "no_end": ["gap"],
             "notes": {"rpm_cut": rpm_cut, "gaps_s": [[r4(x), r4(y)] for x, y in gaps],
                       "t_res_s": t_res, "t_floor_s": t_floor}}
    return {"name": name, "file": name + ".csv", "text": "".join(lines),
            "options": ["--time-column", "elapsed_s", "--value-column", "rpm",
                        "--time-unit", "s", "--value-unit", "rpm", "--inertia", "5e-5"],
            "truth": truth}


def case_dropouts(seed=12):
    """E5. The lab's sketch, a loose jumper: single 0.00 readings (and one double) mid-coast."""
    name = "zero-dropouts-midcoast"
    rng = random.Random(seed)
    V, t_on, t_cut = 3.0, 1.0, 5.8119
    tr, _ = lab_rig_traj([(t_on, t_cut, V)], t_cut + 40.0)
    T_stop = first_stop_after(tr, t_cut)
    times = lab_sample_times(rng, T_stop + 4.0)
    drops = set()
    for rel in (3.1, 7.7, 12.4, 19.9, 9.3):
        i = min(range(len(times)), key=lambda i: abs(times[i] - (t_cut + rel)))
        drops.add(i)
        if rel == 9.3:
            drops.add(i + 1)
    text, _ = lab_file(rng, tr, times, lambda t: lab_reading(rng, tr, t, t >= t_cut),
                       drop_idx=drops)
    dtp = local_period(times, t_cut)
    tol_stop, v_vis = lab_tol_stop(tr, T_stop, dtp, lab_sigma(0.004))
    truth = {"n_runs": 1, "runs": [run_truth(t_cut, 2 * dtp, T_stop, tol_stop)],
             "notes": {"dropouts_s": sorted(r4(times[i]) for i in drops),
                       "volts_at_dropouts": sorted(r4(LAB_KB * tr.w(times[i])) for i in drops)}}
    return {"name": name, "file": name + ".txt", "text": text, "options": [], "truth": truth}


def case_student(seed=13):
    """E6. The lab's own format, three runs, a typical student's noise (loose wires, mains)."""
    name = "lab-student-noisy-3runs"
    rng = random.Random(seed)
    sched = [(1.0, 6.2113, 3.0), (40.5, 45.0371, 3.5), (83.0, 88.4229, 2.6)]
    unplug = [37.5, 80.0, None]
    t_end_total = 125.0
    tr, _ = lab_rig_traj(sched, t_end_total)
    stops = [first_stop_after(tr, c) for (_, c, _) in sched]
    for k, s in enumerate(stops):
        nxt = unplug[k] if unplug[k] is not None else t_end_total - 3
        if s > nxt - 2.0:
            raise RuntimeError("generator bug: run %d still moving at the unplug" % (k + 1))
    times = lab_sample_times(rng, t_end_total)

    def connected(t):
        for k, (_, c, _) in enumerate(sched):
            end = unplug[k] if unplug[k] is not None else 1e9
            if c <= t < end:
                return True
        return False

    noise, pickup, rip = 0.02, 0.015, 0.015
    text, _ = lab_file(rng, tr, times,
                       lambda t: lab_reading(rng, tr, t, connected(t), noise=noise,
                                             ripple=rip, pickup=pickup),
                       putty="2024.10.08 11:42:07")
    runs = []
    notes = []
    for k, (_, c, V) in enumerate(sched):
        dtp = local_period(times, c)
        E0 = LAB_KB * tr.w(c)
        s_eff = lab_sigma(noise, pickup=pickup)
        tol_stop, v_vis = lab_tol_stop(tr, stops[k], dtp, s_eff)
        runs.append(run_truth(c, 2 * dtp, stops[k], tol_stop))
        notes.append({"supply_V": V, "backemf_cut_V": E0, "sigma_eff_V": s_eff,
                      "v_vis_V": v_vis})
    truth = {"n_runs": 3, "runs": runs, "notes": {"runs": notes}}
    return {"name": name, "file": name + ".txt", "text": text, "options": [], "truth": truth}


def case_drift(seed=14):
    """E7. A heavy flywheel's 4½-minute coast, tachogenerator on a 12-bit logger whose offset drifts."""
    name = "offset-drift-long-coast"
    rng = random.Random(seed)
    J, a, b = 0.3, 0.08, 1.5e-3
    Kt = Kb = 0.5
    R = 1.5
    t_on, t_cut = 5.0, 35.27
    V = (150.0 * (Kt * Kb / R + b) + a) * R / Kt
    drive = dc_motor(lambda t: V if t_on <= t < t_cut else 0.0, Kt, Kb, R)
    tr = simulate(J, lambda t, w: a + b * w, drive, 430.0, dt=5e-3)
    T_stop = first_stop_after(tr, t_cut)
    t_end = T_stop + 120.0
    Kg, sig = 0.02, 0.0015
    off = lambda t: 0.005 + 0.025 * (1 - math.exp(-t / 250.0))
    lines = ["t_s,tach_V\r\n"]
    k = 0
    while k * 0.1 <= t_end:
        t = k * 0.1
        v = Kg * tr.w(t) + off(t) + rng.gauss(0.0, sig)
        code = min(4095, max(0, int(math.floor(v / 0.001))))
        lines.append("%.1f,%.3f\r\n" % (t, code * 0.001))
        k += 1
    q = 0.001
    s_eff = math.sqrt(sig ** 2 + q ** 2 / 12)
    r = max(q, 2 * s_eff)
    t_res = tr.t_fall(t_cut, r / Kg) - t_cut
    tol_cut = 2 * 0.1 + t_res
    v_vis = max(q, 3 * s_eff)
    t_floor = tr.t_floor(T_stop, v_vis / Kg)
    tol_stop = 2 * 0.1 + t_floor
    truth = {"n_runs": 1, "runs": [run_truth(t_cut, tol_cut, T_stop, tol_stop)],
             "notes": {"V_supply": V, "tach_cut_V": Kg * tr.w(t_cut),
                       "offset_at_cut_V": off(t_cut), "offset_at_stop_V": off(T_stop),
                       "offset_at_end_V": off(t_end), "coast_s": T_stop - t_cut,
                       "t_res_s": t_res, "t_floor_s": t_floor}}
    return {"name": name, "file": name + ".csv", "text": "".join(lines),
            "options": ["--time-column", "t_s", "--value-column", "tach_V", "--time-unit", "s",
                        "--value-unit", "V", "--kb", "0.02", "--inertia", "0.3"],
            "truth": truth}


def all_cases():
    return [
        lambda: case_hall("hall-per-pulse-3333-3157", 2.8, 7.4137, 101),
        lambda: case_hall("hall-per-pulse-2608-2500", 2.25, 6.2291, 102),
        case_encoder,
        case_display,
        lambda: case_adc_top("adc-top-lab-procedure", 5.45, 7.8113, 41, False,
                             putty="2024.09.12 14:03:51"),
        lambda: case_adc_top("adc-top-terminal-throughout", 5.45, 7.8113, 42, True),
        lambda: case_adc_top("clean-twin-lab-procedure", 3.0, 6.4407, 43, False, clean=True,
                             putty="2024.09.12 14:11:09"),
        lambda: case_adc_top("clean-twin-terminal-regulated", 3.0, 8.2731, 44, True,
                             regulated=True, clean=True),
        case_spin_bike,
        case_held_channel,
        case_startup_blip,
        case_ripple,
        case_grade,
        case_hand_brake,
        case_bursts,
        case_dropouts,
        case_student,
        case_drift,
    ]


def generate(outdir):
    os.makedirs(outdir, exist_ok=True)
    cases = []
    for mk in all_cases():
        c = mk()
        with open(os.path.join(outdir, c["file"]), "w", newline="") as fh:
            fh.write(c["text"])
        del c["text"]
        cases.append(c)
    with open(os.path.join(outdir, "truth.json"), "w") as fh:
        json.dump(cases, fh, indent=1, default=float)
    return cases


# ----------------------------------------------------------------------------------------------
# judge

TOP_RE = re.compile(r"pinned|saturat|converter'?s top|full[- ]scale|clip\w*\s+(at|near)\s+(the\s+)?(top|5)",
                    re.I)
CLIP_RE = re.compile(r"pinned|saturat|converter'?s top|full[- ]scale|clip", re.I)


def _num(d, k):
    v = d.get(k)
    return v if isinstance(v, (int, float)) and not isinstance(v, bool) else None


def _f(x):
    return "null" if x is None else ("%.3f" % x)


def best_model(run):
    best = run.get("best")
    for m in run.get("models") or []:
        if m.get("name") == best:
            return m
    return None


def unit_factor(unit):
    """Reading-unit conversion from rpm (for the held-channel noise check)."""
    u = (unit or "").strip().lower()
    if u in ("rpm", "1/min", "u/min"):
        return 1.0
    if u in ("rad/s",):
        return RPM
    if u in ("rev/s", "rps", "hz"):
        return 1.0 / 60.0
    if u in ("deg/s",):
        return 6.0
    return None


def check_stop(run, tr, why, label):
    stopped = run.get("stopped")
    t_stop = _num(run, "t_stop_s")
    end = run.get("end")
    if tr["stop_mode"] == "stopped_or_lost":
        lo, hi = tr["stop_window"]
        if stopped is True:
            if t_stop is None or not (lo <= t_stop <= hi):
                why.append("%sstop %s s outside [%.3f, %.3f] (true stop %.3f s, last pulse %.3f s)"
                           % (label, _f(t_stop), lo, hi, tr["t_stop"], tr["t_last_data"]))
        else:
            t_end = _num(run, "t_end_s")
            if end not in ("signal lost", "end of data"):
                why.append("%snot stopped and end %r (truth: stopped at %.3f s, or the sensor's "
                           "signal lost after the last pulse at %.3f s)"
                           % (label, end, tr["t_stop"], tr["t_last_data"]))
            elif t_end is None or t_end < tr["lost_min_end"]:
                why.append("%sfitted only to %s s, the last pulse is at %.3f s"
                           % (label, _f(t_end), tr["t_last_data"]))
        return
    if stopped is not True:
        why.append("%snot stopped (end %r, t_end %s) vs truth stopped at %.3f s ± %.3f"
                   % (label, end, _f(_num(run, "t_end_s")), tr["t_stop"], tr["tol_stop"]))
        return
    if t_stop is None or abs(t_stop - tr["t_stop"]) > tr["tol_stop"]:
        why.append("%sstop %s s vs truth %.3f ± %.3f s" % (label, _f(t_stop), tr["t_stop"],
                                                          tr["tol_stop"]))


def judge(case, js, rc, err):
    truth = case["truth"]
    why = []
    files = (js or {}).get("files") or []
    if not files:
        tail = " | ".join(err.strip().splitlines()[-3:])
        return ["no JSON result (exit %d): %s" % (rc, tail[:300])]
    f = files[0]
    runs = sorted(f.get("runs") or [], key=lambda r: (r.get("run") or 0))
    exp = truth["runs"]
    diags = f.get("diagnostics") or []
    if len(runs) != truth["n_runs"]:
        got = ", ".join("cut %s stop %s" % (_f(_num(r, "t_cut_s")), _f(_num(r, "t_stop_s")))
                        for r in runs)
        want = ", ".join("cut %.3f stop %.3f" % (e["t_cut"], e["t_stop"]) for e in exp)
        why.append("runs: got %d [%s] vs truth %d [%s]" % (len(runs), got, truth["n_runs"], want))
        if truth.get("top_mention") is not None:
            pass
        return why
    restart = truth.get("clock_restarts")
    offset_lo = 0.0
    offset_slack = 0.0
    for k, (run, tr) in enumerate(zip(runs, exp)):
        label = "run %d: " % (k + 1) if len(exp) > 1 else ""
        t_cut = _num(run, "t_cut_s")
        t_stop = _num(run, "t_stop_s")
        if t_cut is None:
            why.append("%sno t_cut_s" % label)
            continue
        if restart:
            # the file's clock restarts per coast: accept the segment's own clock, or a clock
            # unwrapped by stacking the segments (gap 0 to 5 periods each)
            local_ok = abs(t_cut - tr["t_cut"]) <= tr["tol_cut"]
            lo = offset_lo + tr["t_cut"] - tr["tol_cut"]
            hi = offset_lo + offset_slack + tr["t_cut"] + tr["tol_cut"]
            unwrapped_ok = lo <= t_cut <= hi
            if not (local_ok or unwrapped_ok):
                why.append("%scut %.3f s vs truth %.3f ± %.3f s on the segment's clock "
                           "(or %.3f…%.3f s stacked)" % (label, t_cut, tr["t_cut"], tr["tol_cut"],
                                                          lo, hi))
            offset_lo += tr["seg_last_local"]
            offset_slack += 5 * 0.25
            if run.get("stopped") is not True or run.get("end") == "clock restart":
                why.append("%snot stopped (end %r) vs truth stopped %.3f s after the cut"
                           % (label, run.get("end"), tr["t_stop"] - tr["t_cut"]))
            elif t_stop is not None:
                dur = t_stop - t_cut
                tdur = tr["t_stop"] - tr["t_cut"]
                tol = tr["tol_cut"] + tr["tol_stop"]
                if abs(dur - tdur) > tol:
                    why.append("%scoast %.3f s (cut→stop) vs truth %.3f ± %.3f s"
                               % (label, dur, tdur, tol))
            else:
                why.append("%sstopped but no t_stop_s" % label)
            continue
        if tr.get("cut_range"):
            lo, hi = tr["cut_range"]
            if not (lo <= t_cut <= hi):
                why.append("%scut %.3f s outside [%.3f, %.3f] (true power-off %.3f s hidden under "
                           "the converter's top; the reading leaves it at %.3f s)"
                           % (label, t_cut, lo, hi, tr["t_cut"], hi))
        elif abs(t_cut - tr["t_cut"]) > tr["tol_cut"]:
            why.append("%scut %.3f s vs truth %.3f ± %.3f s" % (label, t_cut, tr["t_cut"],
                                                               tr["tol_cut"]))
        check_stop(run, tr, why, label)
        if tr.get("omega0"):
            m = best_model(run)
            w0 = None
            if m:
                p = (m.get("params") or {}).get("omega0") or {}
                w0 = p.get("value") if isinstance(p, dict) else None
            want, tol = tr["omega0"]
            if w0 is None:
                why.append("%sno omega0 in the best model" % label)
            elif abs(w0 - want) > tol:
                why.append("%sbest model's omega0 %.1f rad/s vs truth %.1f ± %.1f rad/s"
                           % (label, w0, want, tol))
        for bad in truth.get("no_end", []):
            if run.get("end") == bad:
                why.append("%send %r: the coast is not cut short there" % (label, bad))
    # converter's top
    if truth.get("top_mention") is not None:
        doubt_text = " ".join(json.dumps(r.get("doubts"), ensure_ascii=False) for r in runs)
        warn_text = " ".join(str(d.get("message", "")) for d in diags
                             if str(d.get("severity", "")).lower() in ("warning", "error"))
        any_text = " ".join(str(d.get("message", "")) for d in diags)
        if truth["top_mention"]:
            if not (CLIP_RE.search(doubt_text) or CLIP_RE.search(warn_text)):
                why.append("the reading pinned at the ADC's top (5.00 V) is not said in the run's "
                           "doubts or a warning")
        else:
            hit = TOP_RE.search(doubt_text) or TOP_RE.search(any_text)
            if hit:
                ctx = doubt_text if TOP_RE.search(doubt_text) else any_text
                i = hit.start()
                why.append("clean run said to be at the converter's top: …%s…"
                           % ctx[max(0, i - 60): i + 60])
    if truth.get("period"):
        lo, hi = truth["period"]
        for k, run in enumerate(runs):
            p = _num(run, "period_s")
            if p is not None and not (lo <= p <= hi):
                why.append("period_s %.4f s vs truth 0.100 s (one reading per 10 Hz message; "
                           "accepted %.3f…%.3f)" % (p, lo, hi))
    if truth.get("noise"):
        nz = truth["noise"]
        for k, run in enumerate(runs):
            s = _num(run, "reading_noise")
            fac = unit_factor(run.get("residual_unit") or run.get("quantity"))
            if s is None or fac is None:
                continue
            want = nz["value"] * fac
            if not (nz["lo"] * want <= s <= nz["hi"] * want):
                why.append("reading_noise %.4g %s vs truth %.4g (σ of one 10 Hz reading; accepted "
                           "%.1f×…%.1f×)" % (s, run.get("residual_unit") or run.get("quantity"),
                                             want, nz["lo"], nz["hi"]))
    return why


def run_one(binp, scratch, case):
    path = os.path.join(scratch, case["file"])
    cmd = [os.path.join(binp, "spindown"), "fit", "--json", path] + case["options"]
    t0 = time.time()
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
        rc, out, err = p.returncode, p.stdout, p.stderr
    except subprocess.TimeoutExpired:
        return case, ["spindown fit did not finish in 120 s"], time.time() - t0
    with open(os.path.join(scratch, case["name"] + ".out.json"), "w") as fh:
        fh.write(out)
    with open(os.path.join(scratch, case["name"] + ".err.txt"), "w") as fh:
        fh.write(err)
    try:
        js = json.loads(out) if out.strip() else None
    except ValueError as e:
        return case, ["output is not JSON (exit %d): %s" % (rc, e)], time.time() - t0
    return case, judge(case, js, rc, err), time.time() - t0


def main(argv):
    if len(argv) >= 3 and argv[1] == "gen":
        cases = generate(argv[2])
        print("wrote %d cases to %s" % (len(cases), argv[2]))
        return 0
    if len(argv) >= 4 and argv[1] == "run":
        binp, scratch = argv[2], argv[3]
        if not os.access(os.path.join(binp, "spindown"), os.X_OK):
            print("FAIL setup: %s/spindown is not an executable" % binp)
            print("SUMMARY: 0/0 passed")
            return 1
        t0 = time.time()
        cases = generate(scratch)
        print("generated %d cases in %.1f s into %s" % (len(cases), time.time() - t0, scratch),
              flush=True)
        with ThreadPoolExecutor(max_workers=2) as ex:
            results = list(ex.map(lambda c: run_one(binp, scratch, c), cases))
        passed = 0
        for case, why, dt in results:
            if why:
                print("FAIL %s: %s" % (case["name"], "; ".join(why)))
            else:
                passed += 1
                print("PASS %s" % case["name"])
        print("SUMMARY: %d/%d passed" % (passed, len(results)))
        return 0 if passed == len(results) else 1
    print(__doc__)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv))
