"""The spin-down's physics and the devices that read it (python3 stdlib only).

J dω/dt = −(c_c + c_v ω) while ω > 0; ω stays 0 once it stops (c_c holds it).
The back-EMF e = K_b ω; what a device reads is e times the wiring's scale (a load across the
terminals makes a divider with the armature resistance), plus noise and commutator ripple,
through its converter, printed as its firmware prints it.
"""
import math
import random

# The lab's bench (docs/design.md §1 and the handout): aluminium cylinder r 2 cm, h 1.5 cm,
# rho 2700, rotor 10.9 g·cm², speed constant 1180 rpm/V.
J_LAB = 1.12687602e-5           # kg·m²
KB_LAB = 1.0 / 123.569311       # V·s/rad = 0.0080926
CV_LAB = 1.8e-7                 # N·m·s/rad  (the handout's combined c3 = 1.822 g·cm²/s)
CC_LAB = 1.14e-4                # N·m        (the handout's c4 ≈ 1139 g·cm²·rad/s²)
R_ARMATURE = 10.0               # Ω, the motor's terminal resistance (assumed; gives the
                                # issue's 47 Ω → viscous ×7.4, reading 0.82× when loaded)


def steel_flywheel_J():
    """The same cylinder in steel (7850 kg/m³) on the same rotor."""
    r, h = 0.02, 0.015
    m = 7850.0 * math.pi * r * r * h
    return 0.5 * m * r * r + 10.9e-7


class Coast:
    """Closed form of J dω/dt = −(cc + cv ω), ω(0) = w0, clamped at the stop."""

    def __init__(self, J, cv, cc, w0):
        self.J, self.cv, self.cc, self.w0 = J, cv, cc, w0
        if cv > 0:
            self.a = cc / cv
            self.tau = J / cv
            self.t_stop = self.tau * math.log((w0 + self.a) / self.a) if cc > 0 else math.inf
        else:
            self.a = None
            self.tau = math.inf
            self.t_stop = J * w0 / cc

    def omega(self, t):
        if t <= 0:
            return self.w0
        if t >= self.t_stop:
            return 0.0
        if self.cv > 0:
            return (self.w0 + self.a) * math.exp(-t / self.tau) - self.a
        return self.w0 - self.cc * t / self.J

    def angle(self, t):
        """θ(t) = ∫ω (for the commutator ripple's phase)."""
        t = min(max(t, 0.0), self.t_stop if math.isfinite(self.t_stop) else t)
        if self.cv > 0:
            return (self.w0 + self.a) * self.tau * (1 - math.exp(-t / self.tau)) - self.a * t
        return self.w0 * t - 0.5 * self.cc * t * t / self.J


class Bench:
    """One motor on one bench: the friction it has and how its terminals are wired.

    r_load: a resistance across the terminals (None: open, the lab's case). With a load R the
    armature current brakes the shaft (extra viscous torque K²/(R_a+R)) and the terminals show
    e·R/(R_a+R) (the meter reads the divider)."""

    def __init__(self, J=J_LAB, kb=KB_LAB, cv=CV_LAB, cc=CC_LAB, r_load=None, e_cut=2.80,
                 supply=None, seed=1):
        self.J, self.kb, self.cv_mech, self.cc = J, kb, cv, cc
        self.r_load = r_load
        self.cv = cv + (kb * kb / (R_ARMATURE + r_load) if r_load else 0.0)
        self.term_scale = (r_load / (R_ARMATURE + r_load)) if r_load else 1.0
        self.e_cut = e_cut            # back-EMF at the cut (V)
        w0 = e_cut / kb
        self.coast = Coast(J, self.cv, cc, w0)
        # Under power the terminals sit at the supply: e + I·R_a with the no-load current.
        i0 = (cc + cv * w0) / kb
        self.supply = supply if supply is not None else e_cut + i0 * R_ARMATURE
        self.rng = random.Random(seed)

    def terminal_volts(self, t_after_cut, noise=0.003, ripple=0.01):
        """What a high-impedance input across the terminals sees, t s after the cut."""
        if t_after_cut < 0:
            return self.supply + self.rng.gauss(0.0, noise)
        w = self.coast.omega(t_after_cut)
        e = self.kb * w * self.term_scale
        if w > 0:
            e *= 1.0 + ripple * math.sin(5.0 * self.coast.angle(t_after_cut))
        return e + self.rng.gauss(0.0, noise)


# ---------------------------------------------------------------- converters and prints

def avr_adc(v, vref=5.0, bits=10):
    """ATmega328P: ADC = Vin·1024/Vref, 0…1023."""
    full = 1 << bits
    c = int(math.floor(v * full / vref))
    return min(max(c, 0), full - 1)


def arduino_print_float(x, digits=2):
    """Print::printFloat: round half up by adding 0.5·10^-digits, then truncate."""
    if x != x:
        return "nan"
    neg = x < 0
    if neg:
        x = -x
    x += 0.5 / (10 ** digits)
    ip = int(x)
    rem = x - ip
    s = ("-" if neg else "") + str(ip)
    if digits > 0:
        s += "."
        for _ in range(digits):
            rem *= 10.0
            d = int(rem)
            s += str(d)
            rem -= d
    return s


class LoopClock:
    """An Arduino loop with delay(20): the true instants of each reading and the device clock.

    period: the loop's real period (delay + conversion + print); start_ms: the device clock at
    the first reading (millis() since reset)."""

    def __init__(self, period_ms=20.35, start_ms=1200.0, jitter_ms=0.05, seed=2):
        self.period = period_ms
        self.start = start_ms
        self.jitter = jitter_ms
        self.rng = random.Random(seed)

    def instants(self, duration_s):
        t = self.start
        out = []
        end = self.start + duration_s * 1000.0
        while t < end:
            out.append(t)
            t += self.period + self.rng.uniform(-self.jitter, self.jitter)
        return out


def record(bench, lead_s=4.0, tail_s=4.0, clock=None, noise=0.003, ripple=0.01, lead="zeros"):
    """Samples of one spin-down as (device_ms_float, input_volts, t_after_cut_s).

    The cut falls lead_s after the first reading; the recording ends tail_s after the stop.
    lead "zeros": the handout's step 6 with A0 held low until it is connected at the cut (the
    input reads 0 before); "supply": the input is on the terminals all along (a scope's probe)."""
    clock = clock or LoopClock()
    dur = lead_s + bench.coast.t_stop + tail_s
    rows = []
    for ms in clock.instants(dur):
        t_rel = (ms - clock.start) / 1000.0 - lead_s
        if t_rel < 0 and lead == "zeros":
            v = bench.rng.gauss(0.0, noise) * 0.3
        else:
            v = bench.terminal_volts(t_rel, noise, ripple)
        rows.append((ms, v, t_rel))
    cut_ms = clock.start + lead_s * 1000.0
    return rows, cut_ms


def truth_dict(b, cut_ms, **extra):
    bench = b
    d = {
        "J_kg_m2": bench.J, "Kb_V_s_per_rad": bench.kb,
        "c_v_mech": bench.cv_mech, "c_v_total": bench.cv, "c_c": bench.cc,
        "cut_device_s": cut_ms / 1000.0,
        "stop_device_s": cut_ms / 1000.0 + bench.coast.t_stop,
        "coast_s": bench.coast.t_stop,
        "e_cut_V": bench.e_cut, "terminal_scale": bench.term_scale,
    }
    d.update(extra)
    return d
