#!/usr/bin/env python3
"""Held-out cases for issue 43 (part b): names inside files, micros() through the live
bridge, and proposals that must work when followed.

usage: python3 gen.py SCRATCH_DIR

Writes SCRATCH_DIR/<case>/<input file> and SCRATCH_DIR/<case>/truth.json for every case.
Standard library only; deterministic (fixed seeds).

Physics (the lab handout, Experiment 6): J*domega/dt = -(c3*omega + c4) after the cut, the
back-EMF E = K_b*omega; under power the motor's terminals sit at the supply voltage V and the
shaft spins up as J*domega/dt = K_t*(V - K_b*omega)/R - (c3*omega + c4) with K_t = K_b (SI).
J = 1.12687602e-5 kg m^2 (flywheel + rotor), K_b = 1/123.569311 V s/rad (1180 rpm/V), and the
handout's four fitted (c3, c4) pairs as four motors. R = 8 ohm (armature, assumed; it only sets
the steady speed under power, ~2.8 V of back-EMF at a 3 V supply as the handout's runs show).
"""
import json
import math
import os
import random
import struct
import sys
import unicodedata

J = 1.12687602e-5
KB = 1.0 / 123.569311
R_ARM = 8.0
RIPPLE = 0.005          # commutator ripple, fraction of the back-EMF
RIPPLE_N = 6            # ripple cycles per revolution
TWO32 = 4294967296

# the handout's combined-damping table, SI (g cm^2 ... x 1e-7)
MOTORS = {
    "exp1": (1.822e-7, 1138.89633e-7),
    "exp2": (2.823e-7, 1005.039132e-7),
    "exp3": (1.800e-7, 1141.930672e-7),
    "exp4": (1.672e-7, 1188.238483e-7),
}

# tolerance on c3 and c4 of each fitted run, relative (fixed before any run of spindown)
C3_RTOL = 0.25
C4_RTOL = 0.06


def f32(x):
    return struct.unpack("f", struct.pack("f", x))[0]


def ard_fmt(x, d=2):
    """Arduino Print::printFloat(x, d) on an AVR (float is 32-bit): round half up, truncate."""
    s = ""
    if x < 0:
        s = "-"
        x = -x
    r = 0.5
    for _ in range(d):
        r /= 10.0
    x = f32(x + r)
    ip = int(x)
    rem = f32(x - ip)
    s += str(ip)
    if d > 0:
        s += "."
    for _ in range(d):
        rem = f32(rem * 10.0)
        dig = int(rem)
        s += str(dig)
        rem = f32(rem - dig)
    return s


def adc10(v):
    """ATmega328P/32u4 10-bit ADC, Vref 5 V, ideal transfer (first step at 0.5 LSB)."""
    code = int(math.floor(v / (5.0 / 1024.0) + 0.5))
    return max(0, min(1023, code))


def sketch_volts(code):
    """float data = analogRead(A0); data = data*5/1023;"""
    return f32(f32(code * 5.0) / 1023.0)


class Motor:
    def __init__(self, name):
        self.name = name
        self.c3, self.c4 = MOTORS[name]

    def _ab(self, V):
        a = (KB * V / R_ARM - self.c4) / J
        b = (KB * KB / R_ARM + self.c3) / J
        return a, b

    def spin(self, w, V, t):
        a, b = self._ab(V)
        wss = a / b
        return wss + (w - wss) * math.exp(-b * t)

    def spin_theta(self, w, V, t):
        a, b = self._ab(V)
        wss = a / b
        return wss * t + (w - wss) * (1.0 - math.exp(-b * t)) / b

    def t_stop(self, w0):
        return J / self.c3 * math.log(1.0 + self.c3 * w0 / self.c4)

    def coast(self, w0, t):
        if t >= self.t_stop(w0):
            return 0.0
        k = self.c4 / self.c3
        return (w0 + k) * math.exp(-self.c3 * t / J) - k

    def coast_theta(self, w0, t):
        ts = self.t_stop(w0)
        t = min(t, ts)
        k = self.c4 / self.c3
        return (w0 + k) * (J / self.c3) * (1.0 - math.exp(-self.c3 * t / J)) - k * t


class Timeline:
    """Rest (unpowered, still), power (supply V on the terminals, spinning up), coast (cut)."""

    def __init__(self, motor, t0=0.0):
        self.m = motor
        self.t0 = t0
        self.t = t0
        self.w = 0.0
        self.theta = 0.0
        self.segs = []   # (start, end, kind, V, w_start, theta_start, motor)
        self.runs = []
        self.V = 0.0

    def motor(self, m):
        self.m = m

    def rest(self, dur):
        assert self.w == 0.0
        self.segs.append((self.t, self.t + dur, "rest", 0.0, 0.0, self.theta, self.m))
        self.t += dur

    def power(self, V, dur):
        self.segs.append((self.t, self.t + dur, "power", V, self.w, self.theta, self.m))
        self.theta += self.m.spin_theta(self.w, V, dur)
        self.w = self.m.spin(self.w, V, dur)
        self.t += dur
        self.V = V

    def coast(self, after, **extra):
        ts = self.m.t_stop(self.w)
        run = dict(t_cut=self.t, t_stop=self.t + ts, w0=self.w, V=self.V,
                   c3=self.m.c3, c4=self.m.c4, motor=self.m.name)
        run.update(extra)
        self.runs.append(run)
        self.segs.append((self.t, self.t + ts, "coast", 0.0, self.w, self.theta, self.m))
        self.theta += self.m.coast_theta(self.w, ts)
        self.w = 0.0
        self.t += ts
        self.rest(after)

    @property
    def end(self):
        return self.t

    def at(self, t):
        """(kind, omega, V, theta) at time t"""
        lo, hi = 0, len(self.segs) - 1
        if t < self.segs[0][0]:
            return "rest", 0.0, 0.0, 0.0
        while lo < hi:
            mid = (lo + hi + 1) // 2
            if self.segs[mid][0] <= t:
                lo = mid
            else:
                hi = mid - 1
        s0, s1, kind, V, w, th, m = self.segs[lo]
        dt = t - s0
        if kind == "rest":
            return kind, 0.0, 0.0, th
        if kind == "power":
            return kind, m.spin(w, V, dt), V, th + m.spin_theta(w, V, dt)
        return kind, m.coast(w, dt), 0.0, th + m.coast_theta(w, dt)

    def terminal(self, t, rng, white):
        """What an analog input across the motor's terminals sees (V)."""
        kind, w, V, th = self.at(t)
        if kind == "power":
            v = V
        elif kind == "coast":
            e = KB * w
            v = e + RIPPLE * e * math.sin(RIPPLE_N * th)
        else:
            v = 0.0
        return v + rng.gauss(0.0, white)


def tolerances(run, period, scale, white, q, speed=False):
    """2 sample periods + the time the coast takes to fall 2 noise sigmas near the cut and
    near the stop.  scale: reading units per volt of back-EMF (or per rad/s for a speed)."""
    w0 = run["w0"]
    c3, c4 = run["c3"], run["c4"]
    k = 1.0 if speed else KB
    slope_cut = scale * k * (c3 * w0 + c4) / J
    slope_stop = scale * k * c4 / J
    ripple_cut = 0.0 if speed else RIPPLE * scale * KB * w0 / math.sqrt(2.0)
    sig_cut = math.sqrt(white ** 2 + q ** 2 / 12.0 + ripple_cut ** 2)
    sig_stop = math.sqrt(white ** 2 + q ** 2 / 12.0)
    return (2 * period + 2 * sig_cut / slope_cut, 2 * period + 2 * sig_stop / slope_stop,
            dict(slope_cut=slope_cut, slope_stop=slope_stop, sigma_cut=sig_cut,
                 sigma_stop=sig_stop))


def truth_runs(tl, period, scale, white, q, speed=False, keys=()):
    out = []
    for r in tl.runs:
        tc, ts, info = tolerances(r, period, scale, white, q, speed)
        d = dict(t_cut=round(r["t_cut"], 6), t_stop=round(r["t_stop"], 6),
                 tol_cut=round(tc, 4), tol_stop=round(ts, 4),
                 c3=r["c3"], c4=r["c4"], omega0=round(r["w0"], 3), supply_V=r["V"],
                 motor=r["motor"], tol_info={k: round(v, 5) for k, v in info.items()})
        for k in keys:
            d[k] = r[k]
        out.append(d)
    return out


def write_case(root, name, truth, files):
    d = os.path.join(root, name)
    os.makedirs(d, exist_ok=True)
    for fn, data in files.items():
        with open(os.path.join(d, fn), "wb") as f:
            f.write(data)
    truth = dict(truth)
    truth["name"] = name
    truth.setdefault("c3_rtol", C3_RTOL)
    truth.setdefault("c4_rtol", C4_RTOL)
    with open(os.path.join(d, "truth.json"), "w", encoding="utf-8") as f:
        json.dump(truth, f, indent=1, ensure_ascii=False)


PUTTY_HDR = "=~=~=~=~=~=~=~=~=~=~=~= PuTTY log {} =~=~=~=~=~=~=~=~=~=~=~=\r\n"


def uno_loop_times(t_start, t_end, rng, period=0.02035):
    """delay(20) + analogRead (0.11 ms) + buffered prints: ~20.35 ms a loop."""
    t = t_start
    while t < t_end:
        yield t
        t += period + rng.gauss(0.0, 0.00002)


# --------------------------------------------------------------------------------------------
# part 1: names inside a file

def case_names_sendbox_echo(root):
    """PuTTY capture; the sketch echoes whatever is typed into PuTTY's window (a name) with
    Serial.readString(), which blocks the loop for its 1-s timeout."""
    rng = random.Random(4301)
    m = Motor("exp1")
    tl = Timeline(m)
    typed = []   # (time of first key, text)
    tl.rest(3.0); typed.append((0.9, "Ben"))
    tl.power(3.0, 5.0); tl.coast(6.0, student="Ben")
    typed.append((tl.t - 4.5, "Chloé"))
    tl.power(3.5, 5.0); tl.coast(6.0, student="Chloé")
    typed.append((tl.t - 4.0, "Ben"))
    tl.power(3.0, 4.0); tl.coast(5.0, student="Ben")
    end = tl.end
    out = [PUTTY_HDR.format("2024.03.05 14:02:11")]
    t = 0.0
    pend = list(typed)
    while t < end:
        if pend and t >= pend[0][0]:
            t_key, who = pend.pop(0)
            # PuTTY sends each key as typed (~0.15 s apart), Enter as CR; readString()
            # returns 1 s after the last byte; the sketch then println()s it.
            t_last = t_key + 0.15 * len(who)
            t = max(t, t_last) + 1.0
            out.append(who + "\r" + "\r\n")
        v = tl.terminal(t, rng, 0.004)
        out.append("%d\t%s\r\n" % (int(t * 1000), ard_fmt(sketch_volts(adc10(v)))))
        t += 0.02035 + rng.gauss(0.0, 0.00002)
    truth = dict(kind="names", input="putty-bench2.log", base_opts=[],
                 students=["Ben", "Chloé"],
                 runs=truth_runs(tl, 0.02035, 1.0, 0.004, 0.01, keys=("student",)),
                 unit="V", unit_aliases=["V", "volt", "volts"], user_knows={})
    write_case(root, "names_sendbox_echo", truth,
               {"putty-bench2.log": "".join(out).encode("utf-8")})


def case_names_comment_lines(root):
    """One shared PuTTY capture of two students taking turns, annotated afterwards in an
    editor: '# Dmitri run 1', '--- Chloé ---' (the é pasted from a macOS folder name: NFD)."""
    rng = random.Random(4302)
    m = Motor("exp3")
    tl = Timeline(m)
    tl.rest(4.0)
    marks = []
    plan = [("Dmitri", 3.0, "# Dmitri run 1"),
            ("Chloé", 3.5, "--- " + unicodedata.normalize("NFD", "Chloé") + " ---"),
            ("Dmitri", 3.0, "# Dmitri run 2"),
            ("Chloé", 3.5, "--- " + unicodedata.normalize("NFD", "Chloé") + ", 2nd try ---")]
    for i, (who, V, line) in enumerate(plan):
        marks.append((tl.t - 1.5, line))   # inserted a little above where the values rise
        tl.power(V, 4.5)
        tl.coast(5.0 if i < 3 else 6.0, student=who)
    end = tl.end
    out = [PUTTY_HDR.format("2024.03.12 10:41:57")]
    pend = list(marks)
    for t in uno_loop_times(0.0, end, rng):
        while pend and t >= pend[0][0]:
            out.append(pend.pop(0)[1] + "\r\n")
        v = tl.terminal(t, rng, 0.004)
        out.append("%d\t%s\r\n" % (int(t * 1000), ard_fmt(sketch_volts(adc10(v)))))
    truth = dict(kind="names", input="bench4-shared.log", base_opts=[],
                 students=["Dmitri", "Chloé"],
                 runs=truth_runs(tl, 0.02035, 1.0, 0.004, 0.01, keys=("student",)),
                 unit="V", unit_aliases=["V", "volt", "volts"], user_knows={})
    write_case(root, "names_comment_lines", truth,
               {"bench4-shared.log": "".join(out).encode("utf-8")})


def case_names_third_column(root):
    """Sketch prints millis<TAB>volts<TAB>who; 'who' is set from the Serial Monitor's send
    box (readStringUntil('\\n')), empty until the first name is sent. Copied out of the IDE's
    monitor into a text file (LF)."""
    rng = random.Random(4303)
    m = Motor("exp4")
    tl = Timeline(m)
    names = []
    tl.rest(2.0); names.append((0.8, "Łukasz"))
    tl.power(3.0, 4.0); tl.coast(5.0, student="Łukasz")
    names.append((tl.t - 3.0, "Zoë"))
    tl.power(3.5, 4.0); tl.coast(5.0, student="Zoë")
    names.append((tl.t - 2.0, "Łukasz"))
    tl.power(3.0, 4.0); tl.coast(5.0, student="Łukasz")
    end = tl.end
    out = []
    who = ""
    pend = list(names)
    for t in uno_loop_times(0.0, end, rng):
        while pend and t >= pend[0][0]:
            who = pend.pop(0)[1]
        v = tl.terminal(t, rng, 0.004)
        out.append("%d\t%s\t%s\n" % (int(t * 1000), ard_fmt(sketch_volts(adc10(v))), who))
    truth = dict(kind="names", input="monitor-copy.txt", base_opts=[],
                 students=["Łukasz", "Zoë"],
                 runs=truth_runs(tl, 0.02035, 1.0, 0.004, 0.01, keys=("student",)),
                 unit="V", unit_aliases=["V", "volt", "volts"], user_knows={})
    write_case(root, "names_third_column", truth,
               {"monitor-copy.txt": "".join(out).encode("utf-8")})


def case_names_excel_rows(root):
    """A PuTTY log opened in a German Excel; a row with the student's name typed in column A
    above each run; saved as 'CSV (Trennzeichen-getrennt)': Windows-1252, ';', decimal
    commas, CR LF."""
    rng = random.Random(4304)
    m = Motor("exp2")
    tl = Timeline(m)
    tl.rest(3.0)
    marks = []
    for i, (who, V) in enumerate([("Jürgen", 3.0), ("Begüm", 3.5), ("Jürgen", 3.5)]):
        marks.append((tl.t - 1.0, who))
        tl.power(V, 4.5)
        tl.coast(5.0, student=who)
    end = tl.end
    out = ["Zeit [ms];Spannung [V]\r\n"]
    pend = list(marks)
    for t in uno_loop_times(0.0, end, rng):
        while pend and t >= pend[0][0]:
            out.append(pend.pop(0)[1] + ";\r\n")
        v = tl.terminal(t, rng, 0.004)
        # Excel drops the trailing zero of "2.80" -> "2,8", and "0.00" -> "0"
        val = float(ard_fmt(sketch_volts(adc10(v))))
        sval = ("%.2f" % val).rstrip("0").rstrip(".").replace(".", ",")
        out.append("%d;%s\r\n" % (int(t * 1000), sval))
    truth = dict(kind="names", input="Messung_Gruppe3.csv", base_opts=[],
                 students=["Jürgen", "Begüm"],
                 runs=truth_runs(tl, 0.02035, 1.0, 0.004, 0.01, keys=("student",)),
                 unit="V", unit_aliases=["V", "volt", "volts", "Spannung"], user_knows={})
    write_case(root, "names_excel_rows", truth,
               {"Messung_Gruppe3.csv": "".join(out).encode("cp1252")})


# --------------------------------------------------------------------------------------------
# part 2: micros() through the live bridge

def live_lines(tl, rng, t_first, fmt, sep, digits, start_mid_line=True):
    """A Leonardo (native USB: opening the port does not reset it) printing micros() and the
    volts, delay(20). Returns [(device_time, bytes)] and the truth-clock of each line."""
    lines = []
    for t in uno_loop_times(t_first, tl.end, rng):
        us = int(t * 1e6) // 4 * 4            # micros() counts in 4-us steps at 16 MHz
        v = tl.terminal(t, rng, 0.004)
        s = "%d%s%s\r\n" % (us % TWO32, sep, ard_fmt(sketch_volts(adc10(v)), digits))
        lines.append((t, s.encode("ascii")))
    if start_mid_line:
        t0, b0 = lines[0]
        lines[0] = (t0, b0[len(b0) // 2:])    # the bridge joins mid-line
    return lines


def write_live(root, name, tl, lines, truth, fname):
    data = b"".join(b for _, b in lines)
    t0 = lines[0][0]
    times = [[round(t - t0, 6), len(b)] for t, b in lines]
    write_case(root, name, truth, {fname: data,
                                   "serial_times.json": json.dumps(times).encode()})


def case_live_micros_wrap_tab(root):
    rng = random.Random(4311)
    m = Motor("exp1")
    t_first = (TWO32 - 24_000_000) / 1e6          # 71.2 min after the board powered up
    tl = Timeline(m, t_first)
    tl.rest(3.0); tl.power(3.0, 4.0); tl.coast(5.0)
    tl.power(3.0, 5.0); tl.coast(8.0)
    lines = live_lines(tl, rng, t_first, "us", "\t", 2)
    wrap = TWO32 / 1e6
    assert tl.runs[0]["t_cut"] < wrap < tl.runs[0]["t_stop"]
    truth = dict(kind="live", input="leonardo-capture.txt", base_opts=[], bench="bench-l1",
                 runs=truth_runs(tl, 0.02035, 1.0, 0.004, 0.01),
                 wrap_at_s=wrap, unit="V", unit_aliases=["V"], user_knows={},
                 note="device times are micros()/1e6 unwrapped (past 4294.967296 s)")
    write_live(root, "live_micros_wrap_tab", tl, lines, truth, "leonardo-capture.txt")


def case_live_micros_comma_wrap_near_stop(root):
    rng = random.Random(4312)
    m = Motor("exp2")
    # plan the timeline from 0, then shift so that micros() wraps 0.5 s before run 2's stop
    probe = Timeline(m, 0.0)
    probe.rest(2.0); probe.power(3.5, 4.0); probe.coast(5.0); probe.power(3.5, 4.0); probe.coast(8.0)
    shift = TWO32 / 1e6 - (probe.runs[1]["t_stop"] - 0.5)
    t_first = shift
    tl = Timeline(m, t_first)
    tl.rest(2.0); tl.power(3.5, 4.0); tl.coast(5.0); tl.power(3.5, 4.0); tl.coast(8.0)
    lines = live_lines(tl, rng, t_first, "us", ",", 3)
    wrap = TWO32 / 1e6
    assert tl.runs[1]["t_stop"] - 0.6 < wrap < tl.runs[1]["t_stop"]
    truth = dict(kind="live", input="plotter-style.txt", base_opts=[], bench="bench-l2",
                 runs=truth_runs(tl, 0.02035, 1.0, 0.004, 0.005),
                 wrap_at_s=wrap, unit="V", unit_aliases=["V"], user_knows={},
                 note="device times are micros()/1e6 unwrapped (past 4294.967296 s)")
    write_live(root, "live_micros_comma_wrap_near_stop", tl, lines, truth, "plotter-style.txt")


# --------------------------------------------------------------------------------------------
# part 3: files spindown has to propose options for

def case_prop_counter_two_channels(root):
    """Sketch with a timer loop (exactly 20 ms) printing a sample counter n, A0 (motor) and
    A1 (the supply rail through a 2:1 divider) in volts. PuTTY log, no header row."""
    rng = random.Random(4321)
    m = Motor("exp1")
    tl = Timeline(m)
    tl.rest(2.5); tl.power(3.0, 5.0); tl.coast(4.0); tl.power(3.0, 5.0); tl.coast(5.0)
    out = [PUTTY_HDR.format("2024.04.02 09:15:03")]
    n = 0
    t = 0.0
    while t < tl.end:
        v0 = tl.terminal(t, rng, 0.004)
        kind, _, V, _ = tl.at(t)
        v1 = (V / 2.0 if kind == "power" else 0.0) + rng.gauss(0.0, 0.003)
        out.append("%d\t%s\t%s\r\n" % (n, ard_fmt(sketch_volts(adc10(v0))),
                                        ard_fmt(sketch_volts(adc10(v1)))))
        n += 1
        t = n * 0.020
    truth = dict(kind="proposal", input="putty-counter.log", base_opts=[],
                 runs=truth_runs(tl, 0.020, 1.0, 0.004, 0.01),
                 unit="V", unit_aliases=["V", "volt", "volts", "back-emf"],
                 user_knows={"period-ms": "20", "value-unit": "V", "value-column": "2"},
                 facts="column 1 is a sample counter n (not a clock); rows every 20 ms exactly; "
                       "row k (from the first data row, n = 0) is at k*20 ms")
    write_case(root, "prop_counter_two_channels", truth,
               {"putty-counter.log": "".join(out).encode("ascii")})


def case_prop_tek_scope(root):
    """Tektronix TBS1000/TDS2000-style 'Save CSV': the setup in columns 1-3 of the first 18
    rows, time (s) and volts in columns 4-5, a trailing comma on every row. 2500 points at
    10 s/div (40 ms), triggered on the falling edge of the cut at 10 %."""
    rng = random.Random(4322)
    m = Motor("exp1")
    dt = 0.04
    trig_idx = 250
    # the cut falls 10 ms before the trigger sample (time 0 on the scope's axis)
    tl = Timeline(m, t0=-12.0)
    tl.rest(1.0)
    tl.power(3.0, 12.0 - 1.0 - 0.01)          # cut at t = -0.01 s
    tl.coast(100.0)
    assert abs(tl.runs[0]["t_cut"] + 0.01) < 1e-9
    hdr = [("Record Length", "2.500000e+03", "Points"),
           ("Sample Interval", "4.000000e-02", "s"),
           ("Trigger Point", "2.500000000000e+02", "Samples"),
           ("", "", ""), ("", "", ""), ("", "", ""),
           ("Source", "CH1", ""),
           ("Vertical Units", "V", ""),
           ("Vertical Scale", "5.000000e-01", ""),
           ("Vertical Offset", "-1.500000e+00", ""),
           ("Horizontal Units", "s", ""),
           ("Horizontal Scale", "1.000000e+01", ""),
           ("Pt Fmt", "Y", ""),
           ("Yzero", "0.000000e+00", ""),
           ("Probe Atten", "1.000000e+00", ""),
           ("Model Number", "TBS1052B", ""),
           ("Serial Number", "C011234", ""),
           ("Firmware Version", "FV:v4.07", "")]
    out = []
    for i in range(2500):
        t = (i - trig_idx) * dt
        v = tl.terminal(t, rng, 0.01)
        code = round(v / 0.02)                 # 8 bits, 25 levels a division at 500 mV/div
        code = max(-50, min(205, code))        # screen: -1.0 V .. 4.1 V around the offset
        val = code * 0.02
        h = hdr[i] if i < len(hdr) else ("", "", "")
        out.append("%s,%s,%s,%.12f,%s,\r\n" % (h[0], h[1], h[2], t, "%.2f" % val))
    truth = dict(kind="proposal", input="F0003CH1.CSV", base_opts=[],
                 runs=truth_runs(tl, dt, 1.0, 0.01, 0.02),
                 unit="V", unit_aliases=["V", "volt", "volts"],
                 user_knows={"time-unit": "s", "value-unit": "V"},
                 facts="time in s in column 4 (0 at the trigger, pre-trigger negative), volts "
                       "in column 5; columns 1-3 hold the scope's setup in the first 18 rows")
    write_case(root, "prop_tek_scope", truth, {"F0003CH1.CSV": "".join(out).encode("ascii")})


def case_prop_raw_counts(root):
    """The handout's sketch with the conversion line left out: Serial.println(analogRead(A0))
    -> millis<TAB>counts 0..1023. PuTTY log."""
    rng = random.Random(4323)
    m = Motor("exp3")
    tl = Timeline(m)
    tl.rest(3.0); tl.power(3.0, 5.0); tl.coast(5.0); tl.power(3.0, 5.0); tl.coast(5.0)
    out = [PUTTY_HDR.format("2024.04.09 11:20:44")]
    for t in uno_loop_times(0.0, tl.end, rng, period=0.02030):
        v = tl.terminal(t, rng, 0.004)
        out.append("%d\t%d\r\n" % (int(t * 1000), adc10(v)))
    scale = 1023.0 / 5.0   # counts per volt as spindown's --value-unit counts reads them
    truth = dict(kind="proposal", input="putty-raw.log", base_opts=[],
                 runs=truth_runs(tl, 0.0203, scale, 0.004 * scale, 1.0),
                 unit="counts", unit_aliases=["counts", "count", "adc", "analogread", "raw",
                                               "10-bit"],
                 user_knows={"value-unit": "counts"},
                 facts="values are raw analogRead() counts of a 5 V 10-bit ADC (x 5/1023 V)")
    write_case(root, "prop_raw_counts", truth, {"putty-raw.log": "".join(out).encode("ascii")})


def case_prop_encoder_rad_s(root):
    """The handout's suggested improvement, a rotary encoder (500 lines, x4 = 2000 counts a
    revolution) read by a Raspberry Pi script that writes f"{t:.3f},{omega:.2f},{amps:.3f}"
    (time.perf_counter() since start, rad/s from the counts, the motor current from an
    INA219), no header."""
    rng = random.Random(4324)
    m = Motor("exp4")
    tl = Timeline(m)
    tl.rest(2.0); tl.power(3.0, 6.0); tl.coast(4.0); tl.power(3.0, 6.0); tl.coast(5.0)
    cpr = 2000
    out = []
    prev = None
    nxt = 0.0
    while nxt < tl.end:
        t = nxt + rng.uniform(0.0001, 0.0012)      # time.sleep() overshoot
        kind, w, V, th = tl.at(t)
        cnt = math.floor(th / (2 * math.pi / cpr))
        if prev is None:
            omega = 0.0
        else:
            omega = (cnt - prev[1]) * (2 * math.pi / cpr) / (t - prev[0])
        amps = ((V - KB * w) / R_ARM if kind == "power" else 0.0) + rng.gauss(0.0, 0.0005)
        out.append("%.3f,%.2f,%.3f\n" % (t, omega, amps))
        prev = (t, cnt)
        nxt += 0.02
    q = 2 * math.pi / cpr / 0.02                       # rad/s per count in one interval
    truth = dict(kind="proposal", input="encoder_log.csv", base_opts=[],
                 runs=truth_runs(tl, 0.02, 1.0, q / math.sqrt(12.0), q, speed=True),
                 unit="rad/s", unit_aliases=["rad/s", "rad s", "rad/sec", "radians",
                                              "omega", "ω"],
                 user_knows={"value-unit": "rad/s", "time-unit": "s"},
                 facts="column 1 time in s, column 2 shaft speed in rad/s, column 3 motor "
                       "current in A")
    write_case(root, "prop_encoder_rad_s", truth,
               {"encoder_log.csv": "".join(out).encode("ascii")})


def case_prop_millivolt_ints(root):
    """Integer millivolts to avoid floats: Serial.println(analogRead(A0) * 5000L / 1023).
    PuTTY log, millis<TAB>mV."""
    rng = random.Random(4325)
    m = Motor("exp2")
    tl = Timeline(m)
    tl.rest(3.0); tl.power(3.5, 5.0); tl.coast(5.0); tl.power(3.5, 5.0); tl.coast(5.0)
    out = [PUTTY_HDR.format("2024.04.16 15:03:29")]
    for t in uno_loop_times(0.0, tl.end, rng, period=0.02030):
        v = tl.terminal(t, rng, 0.004)
        out.append("%d\t%d\r\n" % (int(t * 1000), adc10(v) * 5000 // 1023))
    truth = dict(kind="proposal", input="putty-mV.log", base_opts=[],
                 runs=truth_runs(tl, 0.0203, 1000.0, 4.0, 5000.0 / 1023.0),
                 unit="mV", unit_aliases=["mV", "millivolt", "millivolts"],
                 user_knows={"value-unit": "mV"},
                 facts="values are millivolts (integers, steps of 4-5 mV)")
    write_case(root, "prop_millivolt_ints", truth, {"putty-mV.log": "".join(out).encode("ascii")})


def case_prop_lvm_no_x(root):
    """LabVIEW 'Write To Measurement File' (.lvm) from an NI USB-6008 at 100 S/s, X_Columns
    'No': the readings alone, their period in the header (Delta_X 0.010000)."""
    rng = random.Random(4326)
    m = Motor("exp3")
    tl = Timeline(m)
    tl.rest(3.0); tl.power(3.0, 5.0); tl.coast(5.0); tl.power(3.0, 5.0); tl.coast(5.0)
    dt = 0.01
    n = int(tl.end / dt)
    lsb = 20.0 / 4096.0
    hdr = ("LabVIEW Measurement\t\nWriter_Version\t2\nReader_Version\t2\nSeparator\tTab\n"
           "Decimal_Separator\t.\nMulti_Headings\tNo\nX_Columns\tNo\nTime_Pref\tRelative\n"
           "Operator\tlab\nDate\t2024/04/23\nTime\t14:02:13.5351095\n***End_of_Header***\t\n"
           "\t\nChannels\t1\t\nSamples\t%d\t\nDate\t2024/04/23\t\nTime\t14:02:13.5351095\t\n"
           "Y_Unit_Label\tVolts\t\nX_Dimension\tTime\t\nX0\t0.0000000000000000E+0\t\n"
           "Delta_X\t0.010000\t\n***End_of_Header***\t\nVoltage\tComment\n" % n)
    out = [hdr]
    for k in range(n):
        v = tl.terminal(k * dt, rng, 0.003)
        out.append("%.6f\t\n" % (round(v / lsb) * lsb))
    truth = dict(kind="proposal", input="spindown_run.lvm", base_opts=[],
                 runs=truth_runs(tl, dt, 1.0, 0.003, lsb),
                 unit="V", unit_aliases=["V", "volt", "volts"],
                 user_knows={"period-ms": "10", "value-unit": "V"},
                 facts="readings alone, every 10 ms (Delta_X 0.010000 in the header)")
    write_case(root, "prop_lvm_no_x", truth, {"spindown_run.lvm": "".join(out).encode("ascii")})


CASES = [
    case_names_sendbox_echo,
    case_names_comment_lines,
    case_names_third_column,
    case_names_excel_rows,
    case_live_micros_wrap_tab,
    case_live_micros_comma_wrap_near_stop,
    case_prop_counter_two_channels,
    case_prop_tek_scope,
    case_prop_raw_counts,
    case_prop_encoder_rad_s,
    case_prop_millivolt_ints,
    case_prop_lvm_no_x,
]


def main():
    if len(sys.argv) != 2:
        sys.exit("usage: gen.py SCRATCH_DIR")
    root = sys.argv[1]
    os.makedirs(root, exist_ok=True)
    for c in CASES:
        c(root)
    print("generated %d cases in %s" % (len(CASES), root))


if __name__ == "__main__":
    main()
