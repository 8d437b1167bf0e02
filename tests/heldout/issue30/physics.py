"""Physics and recording habits for issue 30's held-out cases (Python 3 standard library only).

Nothing here uses spindown's own simulator.  A motor with a flywheel coasts under
    J dω/dt = -(c3·ω + c4 + cw·ω²)            (cw = 0 except in one case)
and its back-EMF K_b·ω (or its speed) is read the way a class reads it: an Arduino loop of
`analogRead; print(millis()); print('\t'); println(value); delay(20)`, a 10-bit converter that
rounds or truncates, a 12-bit or 16-bit converter, a speed sensor printing rpm, a PuTTY log.
"""
import math
import random

# The handout's bench (lab-handout.txt): J = I_cylinder + I_rotor, K_b = 1/(1180 rpm/V).
J_LAB = 1.12687602e-5
KB_LAB = 1.0 / 123.569311
C3_LAB = 1.8e-7
C4_LAB = 1.14e-4


def putty_header(stamp="2024.09.14 14:03:22"):
    return ("=~=~=~=~=~=~=~=~=~=~=~= PuTTY log %s =~=~=~=~=~=~=~=~=~=~=~=\r\n" % stamp)


def arduino_float(x, digits=2):
    """Print.cpp's printFloat: add 0.5·10^-digits, print the integer part, then digit by digit."""
    if x < 0:
        return "-" + arduino_float(-x, digits)
    x = x + 0.5 / (10 ** digits)
    ip = int(x)
    rem = x - ip
    s = str(ip)
    if digits > 0:
        s += "."
        for _ in range(digits):
            rem *= 10.0
            d = int(rem)
            s += str(d)
            rem -= d
    return s


class Converter:
    """An ADC as a sketch uses it: counts = f(volts), printed value = counts*scale."""

    def __init__(self, bits=10, vref=5.0, mode="round", divisor=None, digits=2, offset_v=0.0):
        self.bits = bits
        self.vref = vref
        self.mode = mode            # "round": ideal ½-LSB-centred; "floor": truncating
        self.full = 1 << bits
        self.divisor = divisor if divisor is not None else (self.full - 1)   # the sketch's ×5/1023
        self.digits = digits
        self.offset_v = offset_v

    def counts(self, v):
        x = (v + self.offset_v) * self.full / self.vref
        c = math.floor(x + 0.5) if self.mode == "round" else math.floor(x)
        return max(0, min(self.full - 1, c))

    def printed(self, v):
        c = self.counts(v)
        return arduino_float(c * self.vref / self.divisor, self.digits)

    @property
    def step(self):
        return self.vref / self.divisor


def omega_combined(t, w0, J, c3, c4):
    """Speed t seconds after the cut for T = c3·ω + c4 (c4 may be 0); 0 after the stop."""
    if t <= 0:
        return w0
    if c3 == 0:
        return max(0.0, w0 - c4 / J * t)
    if c4 == 0:
        return w0 * math.exp(-c3 * t / J)
    w = (w0 + c4 / c3) * math.exp(-c3 * t / J) - c4 / c3
    return max(0.0, w)


def stop_time(w0, J, c3, c4):
    if c4 == 0:
        return math.inf
    if c3 == 0:
        return J * w0 / c4
    return J / c3 * math.log(1.0 + c3 * w0 / c4)


def integrate_with_windage(w0, J, c3, c4, cw, dt=1e-4, tmax=400.0):
    """RK4 of J dω/dt = -(c3 ω + c4 + cw ω²) until ω = 0; returns (times, speeds) every dt and the stop."""
    def f(w):
        return -(c3 * w + c4 + cw * w * w) / J
    ts, ws = [0.0], [w0]
    t, w = 0.0, w0
    while w > 0 and t < tmax:
        k1 = f(w); k2 = f(w + dt / 2 * k1); k3 = f(w + dt / 2 * k2); k4 = f(w + dt * k3)
        wn = w + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        if wn <= 0:
            # linear interpolation of the stop inside the step
            t_stop = t + dt * w / (w - wn)
            ts.append(t_stop); ws.append(0.0)
            return ts, ws, t_stop
        t += dt; w = wn
        ts.append(t); ws.append(w)
    return ts, ws, t


def interp(ts, ws, t, dt):
    if t <= 0:
        return ws[0]
    i = int(t / dt)
    if i + 1 >= len(ws):
        return 0.0
    f = (t - i * dt) / dt
    return ws[i] * (1 - f) + ws[i + 1] * f


class ArduinoClock:
    """The sketch's loop: delay(20) plus analogRead and the print's CPU time; millis() printed."""

    def __init__(self, rng, t0_ms=None, period_ms=None):
        self.rng = rng
        self.T = t0_ms if t0_ms is not None else rng.uniform(0.0, 2.0)
        self.period = period_ms if period_ms is not None else 20.0 + rng.uniform(0.25, 0.45)

    def next(self):
        T = self.T
        self.T += self.period + self.rng.gauss(0.0, 0.012)
        return T

    @staticmethod
    def millis(T):
        return int(math.floor(T))


# ---------------------------------------------------------------------------------------------
# Point 1: the handout's step 6 -- the pin floats until it is connected after the cut.
# ---------------------------------------------------------------------------------------------

def floating_pin_recording(seed, late=False):
    """A PuTTY log of the lab sketch whose A0 floats until the student connects it to the motor.

    Before the connection the pin is a high-impedance node: its level wanders (an
    Ornstein-Uhlenbeck walk, 3 s correlation, anywhere in 0.5-2.5 V) and it picks up the mains
    (50 or 60 Hz, 0.05-0.5 V), which the ~20.3 ms loop aliases.  The connection comes 0-1 s
    after the cut (late: 2-5 s), with 1-3 samples of contact bounce, then the coast of a
    viscous+Coulomb motor read through the 10-bit converter, to the stop and some zeros after.
    """
    rng = random.Random(1000003 * (seed + 1) + (17 if late else 0))
    conv = Converter(10, 5.0, "round")
    clock = ArduinoClock(rng)
    c3 = C3_LAB * rng.uniform(0.85, 1.15)
    c4 = C4_LAB * rng.uniform(0.9, 1.1)
    v_supply = rng.uniform(2.8, 3.4)
    v_emf0 = v_supply - rng.uniform(0.05, 0.2)
    w0 = v_emf0 / KB_LAB
    t_cut = rng.uniform(4.0, 12.0)            # seconds on the sketch's clock (reset at port open)
    delay = rng.uniform(2.0, 5.0) if late else rng.uniform(0.0, 1.0)
    t_conn = t_cut + delay
    T_stop = stop_time(w0, J_LAB, c3, c4)
    t_end = t_cut + T_stop + rng.uniform(4.0, 12.0)
    mains = rng.choice([50.0, 60.0]) + rng.uniform(-0.03, 0.03)
    pick_a = rng.uniform(0.05, 0.5)
    phase = rng.uniform(0, 2 * math.pi)
    L_mean = rng.uniform(0.8, 2.2)
    L = L_mean + rng.gauss(0, 0.2)
    theta, sd = 3.0, 0.25
    noise_c = rng.uniform(0.002, 0.005)
    ripple = rng.uniform(0.0, 0.005)
    n_bounce = rng.randint(1, 3)

    lines = []
    stamp = "2024.%02d.%02d %02d:%02d:%02d" % (rng.randint(9, 11), rng.randint(1, 28), rng.randint(8, 17),
                                               rng.randint(0, 59), rng.randint(0, 59))
    out = [putty_header(stamp)]
    cut_first = rng.random() < 0.3
    t_contact = None
    t_coast0 = None
    bounces_left = n_bounce
    prev_T = None
    while True:
        T = clock.next()
        t = T / 1000.0
        if t > t_end:
            break
        if prev_T is not None:
            dt = (T - prev_T) / 1000.0
            a = math.exp(-dt / theta)
            L = L_mean + (L - L_mean) * a + sd * math.sqrt(1 - a * a) * rng.gauss(0, 1)
            L = min(2.5, max(0.5, L))
        prev_T = T
        float_v = L + pick_a * math.sin(2 * math.pi * mains * t + phase) + rng.gauss(0, 0.015)
        emf = KB_LAB * omega_combined(t - t_cut, w0, J_LAB, c3, c4)
        if t < t_conn:
            v = float_v
        elif bounces_left > 0:
            if t_contact is None:
                t_contact = ArduinoClock.millis(T) / 1000.0
            bounces_left -= 1
            r = rng.random()
            if r < 0.6:
                v = float_v + rng.random() * (emf - float_v)
            elif r < 0.85:
                v = 0.0
            else:
                v = 5.0
        else:
            if t_coast0 is None:
                t_coast0 = ArduinoClock.millis(T) / 1000.0
            v = emf * (1 + ripple * math.sin(rng.uniform(0, 2 * math.pi))) + rng.gauss(0, noise_c)
        line = "%d\t%s\r\n" % (ArduinoClock.millis(T), conv.printed(v))
        out.append(line)
    if cut_first:
        # logging started on a running board: the first line is cut mid-number
        first = out[1]
        out[1] = first[rng.randint(1, max(1, len(first) - 4)):]
    # PuTTY closed mid-line half of the time
    if rng.random() < 0.5:
        last = out[-1]
        out[-1] = last[:rng.randint(1, len(last) - 2)]
    truth = {
        "kind": "floating-late" if late else "floating",
        "seed": seed, "t_cut_true_s": t_cut, "t_contact_s": t_contact, "t_coast0_s": t_coast0,
        "delay_s": delay, "t_stop_s": t_cut + T_stop, "c3": c3, "c4": c4, "omega0": w0,
        "period_s": clock.period / 1000.0, "mains_hz": mains, "float_level_mean_v": L_mean,
        "pickup_v": pick_a, "bounce_samples": n_bounce,
    }
    return "".join(out).encode("ascii"), truth


# ---------------------------------------------------------------------------------------------
# Point 2: a purely viscous motor read by quiet converters.
# ---------------------------------------------------------------------------------------------

def converter_kind(name):
    if name == "ard10-round":
        return Converter(10, 5.0, "round", digits=2), 0.001
    if name == "ard10-floor":
        return Converter(10, 5.0, "floor", digits=2), 0.001
    if name == "due12":
        # Arduino Due: analogReadResolution(12), v = counts*3.3/4095, Serial.println(v, 3)
        return Converter(12, 3.3, "round", divisor=4095, digits=3), 0.0005
    if name == "ads16":
        # ADS1115 at gain ±4.096 V: 0.125 mV per count, Serial.println(v, 4)
        c = Converter(15, 4.096, "round", divisor=32768, digits=4)
        return c, 0.00015
    raise ValueError(name)


def viscous_recording(seed, conv_name):
    """Zeros (motor at rest, pin connected), the supply's voltage while powered, then a purely
    viscous coast (c4 = 0) from the back-EMF, recorded until the motor looks stopped."""
    rng = random.Random(7919 * (seed + 3) + hash_name(conv_name))
    conv, noise = converter_kind(conv_name)
    clock = ArduinoClock(rng)
    c1 = rng.uniform(4.0e-7, 9.0e-7)             # τ = J/c1 = 12.5 .. 28 s
    vmax = min(4.5, 0.93 * conv.vref)          # below the converter's top
    v_supply = rng.uniform(1.6, vmax)
    v0 = v_supply - rng.uniform(0.05, 0.2)
    w0 = v0 / KB_LAB
    tau = J_LAB / c1
    t_on = rng.uniform(1.5, 4.0)
    t_cut = t_on + rng.uniform(3.0, 6.0)
    if conv.bits == 10:
        t_rec = tau * math.log(v0 / (conv.step / 2)) + rng.uniform(5.0, 15.0)
    else:
        t_rec = tau * math.log(v0 / 0.003) + rng.uniform(5.0, 15.0)
    t_end = t_cut + t_rec
    out = [putty_header("2024.10.%02d 09:%02d:%02d" % (rng.randint(1, 28), rng.randint(0, 59), rng.randint(0, 59)))]
    while True:
        T = clock.next()
        t = T / 1000.0
        if t > t_end:
            break
        if t < t_on:
            v = 0.0
        elif t < t_cut:
            v = v_supply
        else:
            v = v0 * math.exp(-(t - t_cut) / tau)
        v += rng.gauss(0.0, noise)
        out.append("%d\t%s\r\n" % (ArduinoClock.millis(T), conv.printed(v)))
    truth = {"kind": "viscous", "converter": conv_name, "seed": seed, "c1": c1, "c4": 0.0, "omega0": w0,
             "tau_s": tau, "t_cut_s": t_cut, "noise_v": noise, "step_v": conv.step, "model": "viscous"}
    return "".join(out).encode("ascii"), truth


def hash_name(s):
    h = 0
    for ch in s:
        h = (h * 131 + ord(ch)) % 1000003
    return h


# ---------------------------------------------------------------------------------------------
# General lab-sketch recordings (healthy motors, other J, other units).
# ---------------------------------------------------------------------------------------------

def sketch_run_samples(rng, clock, J, c3, c4, v_supply, t_on, t_cut, t_after_stop, noise,
                       cw=0.0, ripple=0.004):
    """(T_ms, back-EMF volts) of one run: zeros, powered at the supply, the coast, zeros."""
    v0 = v_supply - rng.uniform(0.05, 0.2)
    w0 = v0 / KB_LAB
    if cw > 0:
        dt = 1e-3
        ts, ws, T_stop = integrate_with_windage(w0, J, c3, c4, cw, dt=dt)
        speed = lambda s: interp(ts, ws, s, dt)
    else:
        T_stop = stop_time(w0, J, c3, c4)
        speed = lambda s: omega_combined(s, w0, J, c3, c4)
    t_end = t_cut + T_stop + t_after_stop
    samples = []
    while True:
        T = clock.next()
        t = T / 1000.0
        if t > t_end:
            break
        if t < t_on:
            v = 0.0
        elif t < t_cut:
            v = v_supply
        else:
            v = KB_LAB * speed(t - t_cut) * (1 + ripple * math.sin(rng.uniform(0, 2 * math.pi)))
        samples.append((T, v + rng.gauss(0.0, noise)))
    truth = {"c3": c3, "c4": c4, "cw": cw, "omega0": w0, "t_cut_s": t_cut, "t_stop_s": t_cut + T_stop, "J": J}
    return samples, truth


def sketch_recording(seed, J=J_LAB, c3=C3_LAB, c4=C4_LAB, cw=0.0, stamp="2024.09.14 14:03:22",
                     scale=1.0, digits=2, noise=None, header=True, ctrl_z=False, t0_ms=None):
    """A PuTTY log of the lab sketch.  scale=1000 makes a sketch that prints millivolts."""
    rng = random.Random(104729 * (seed + 11))
    conv = Converter(10, 5.0, "round", digits=digits)
    clock = ArduinoClock(rng, t0_ms=t0_ms)
    noise = noise if noise is not None else rng.uniform(0.002, 0.004)
    t_on = rng.uniform(1.5, 3.5)
    t_cut = t_on + rng.uniform(2.5, 5.0)
    samples, truth = sketch_run_samples(rng, clock, J, c3, c4, rng.uniform(2.9, 3.4), t_on, t_cut,
                                        rng.uniform(4.0, 8.0), noise, cw=cw)
    out = [putty_header(stamp)] if header else []
    for T, v in samples:
        c = conv.counts(v)
        out.append("%d\t%s\r\n" % (ArduinoClock.millis(T), arduino_float(c * 5.0 / 1023 * scale, digits)))
    data = "".join(out).encode("ascii")
    if ctrl_z:
        data += b"\x1a"
    truth["seed"] = seed
    return data, truth


def speed_recording(seed, header, delim, time_unit, value_unit, c3=C3_LAB, c4=C4_LAB, J=J_LAB,
                    decimals=1):
    """A speed sensor's or a converted recording written by a logger script with a header.

    time_unit: "ms" | "s"; value_unit: "rpm" | "rad/s" | "mV"."""
    rng = random.Random(15485863 * (seed + 5) + hash_name(header))
    clock = ArduinoClock(rng, t0_ms=rng.uniform(0, 5))
    t_on = rng.uniform(0.5, 1.5)
    t_cut = t_on + rng.uniform(2.0, 4.0)
    samples, truth = sketch_run_samples(rng, clock, J, c3, c4, rng.uniform(2.9, 3.4), t_on, t_cut,
                                        rng.uniform(3.0, 6.0), 0.0, ripple=0.0)
    rows = [header]
    for T, v in samples:
        w = v / KB_LAB                        # rad/s, the physical speed
        if value_unit == "rpm":
            x = w * 60.0 / (2 * math.pi) + rng.gauss(0.0, 2.0)      # tachometer: ±2 rpm
            x = max(0.0, x)
            val = "%.*f" % (decimals, x)
        elif value_unit == "rad/s":
            x = max(0.0, w + rng.gauss(0.0, 0.25))
            val = "%.*f" % (decimals, x)
        elif value_unit == "mV":
            x = max(0.0, v * 1000.0 + rng.gauss(0.0, 2.5))
            val = "%.*f" % (decimals, x)
        else:
            raise ValueError(value_unit)
        t = ArduinoClock.millis(T)
        ts = str(t) if time_unit == "ms" else "%.3f" % (t / 1000.0)
        rows.append(ts + delim + val)
    truth["seed"] = seed
    truth["value_unit"] = value_unit
    truth["time_unit"] = time_unit
    return ("\r\n".join(rows) + "\r\n").encode("ascii"), truth


# ---------------------------------------------------------------------------------------------
# Point 5: what Excel writes.
# ---------------------------------------------------------------------------------------------

def excel_csv_german(rows, ncols_used):
    """Excel (German locale) "CSV (Trennzeichen-getrennt) (*.csv)": cp1252, ';', CR LF, every row
    padded with ';' to the sheet's used range, empty rows as ';;;' - no BOM, no quotes unless needed."""
    out = []
    for r in rows:
        cells = list(r) + [""] * (ncols_used - len(r))
        q = []
        for c in cells:
            if ";" in c or '"' in c or "\n" in c:
                c = '"' + c.replace('"', '""') + '"'
            q.append(c)
        out.append(";".join(q))
    return ("\r\n".join(out) + "\r\n").encode("cp1252")


def excel_unicode_text(rows):
    """Excel "Unicode Text (*.txt)": UTF-16 LE with a BOM, TAB, CR LF; a cell holding a comma or a
    quote is written in quotes, as Excel's text export does."""
    def q(c):
        return '"' + c.replace('"', '""') + '"' if ("," in c or '"' in c) else c
    text = "\r\n".join("\t".join(q(c) for c in r) for r in rows) + "\r\n"
    return b"\xff\xfe" + text.encode("utf-16-le")


def xlsx_workbook(rows):
    """A minimal but real .xlsx (Office Open XML zip) holding rows of numbers: what a student who
    pasted the serial monitor into Excel and pressed Ctrl-S hands in."""
    import io
    import zipfile
    def cell(ref, v):
        try:
            float(v)
            return '<c r="%s"><v>%s</v></c>' % (ref, v)
        except ValueError:
            return '<c r="%s" t="inlineStr"><is><t>%s</t></is></c>' % (ref, v)
    sheet_rows = []
    for i, r in enumerate(rows, 1):
        cells = "".join(cell("%s%d" % ("AB"[j], i), v) for j, v in enumerate(r))
        sheet_rows.append('<row r="%d">%s</row>' % (i, cells))
    sheet = ('<?xml version="1.0" encoding="UTF-8" standalone="yes"?>\r\n'
             '<worksheet xmlns="http://schemas.openxmlformats.org/spreadsheetml/2006/main">'
             '<sheetData>%s</sheetData></worksheet>' % "".join(sheet_rows))
    files = {
        "[Content_Types].xml":
            '<?xml version="1.0" encoding="UTF-8" standalone="yes"?>\r\n'
            '<Types xmlns="http://schemas.openxmlformats.org/package/2006/content-types">'
            '<Default Extension="rels" ContentType="application/vnd.openxmlformats-package.relationships+xml"/>'
            '<Default Extension="xml" ContentType="application/xml"/>'
            '<Override PartName="/xl/workbook.xml" ContentType="application/vnd.openxmlformats-officedocument.spreadsheetml.sheet.main+xml"/>'
            '<Override PartName="/xl/worksheets/sheet1.xml" ContentType="application/vnd.openxmlformats-officedocument.spreadsheetml.worksheet+xml"/>'
            '</Types>',
        "_rels/.rels":
            '<?xml version="1.0" encoding="UTF-8" standalone="yes"?>\r\n'
            '<Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships">'
            '<Relationship Id="rId1" Type="http://schemas.openxmlformats.org/officeDocument/2006/relationships/officeDocument" Target="xl/workbook.xml"/>'
            '</Relationships>',
        "xl/workbook.xml":
            '<?xml version="1.0" encoding="UTF-8" standalone="yes"?>\r\n'
            '<workbook xmlns="http://schemas.openxmlformats.org/spreadsheetml/2006/main" '
            'xmlns:r="http://schemas.openxmlformats.org/officeDocument/2006/relationships">'
            '<sheets><sheet name="Tabelle1" sheetId="1" r:id="rId1"/></sheets></workbook>',
        "xl/_rels/workbook.xml.rels":
            '<?xml version="1.0" encoding="UTF-8" standalone="yes"?>\r\n'
            '<Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships">'
            '<Relationship Id="rId1" Type="http://schemas.openxmlformats.org/officeDocument/2006/relationships/worksheet" Target="worksheets/sheet1.xml"/>'
            '</Relationships>',
        "xl/worksheets/sheet1.xml": sheet,
    }
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as z:
        for name, text in files.items():
            zi = zipfile.ZipInfo(name, date_time=(2024, 9, 14, 14, 30, 0))
            zi.compress_type = zipfile.ZIP_DEFLATED
            z.writestr(zi, text)
    return buf.getvalue()
