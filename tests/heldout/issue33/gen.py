#!/usr/bin/python3
"""Generator for issue 33's held-out cases (standard library only, deterministic).

A lab spin-down as the handout's Arduino sketch records it and PuTTY saves it:
  motor: J = 1.12687602e-5 kg*m^2 (aluminium flywheel + rotor), K_b = 1/123.569311 V*s/rad,
         friction T = c3*w + c4 (viscous + Coulomb), the lab group's values c3 = 1.822e-7 N*m*s/rad,
         c4 = 1.1389e-4 N*m, w0 = 350 rad/s at the power cut;
  sketch: analogRead(A0) (10 bit, 0..5 V), data*5/1023 printed with Serial.println(float): 2
         decimals; millis() TAB value CR LF; delay(20) so millis advances 20 ms, sometimes 21;
  lab procedure (handout steps 5-6): A0 is connected when the supply is cut, so the recording
         reads 0.00 before the cut (lead-in of zeros), then the back-EMF coast, then 0.00 at rest;
  loose connector: single samples that read 0 ("dropouts") or half the value ("glitches")
         inside the coast;
  serial damage: a cut first line (PuTTY opened mid-line), three garbled lines (line noise bytes,
         bit errors turning digits into letters, a value lost), each in place of one sample.

Usage:
  gen.py lab OUT_DIR           -> OUT_DIR/lab-run.txt (PuTTY log), OUT_DIR/lab-run.serial (the bytes
                                  on the serial line: the same, less PuTTY's header line),
                                  OUT_DIR/lab-run.truth.json
  gen.py many OUT_DIR N        -> N clean PuTTY logs OUT_DIR/many/run-NN.txt (one run each, seeds
                                  and friction varied) for the JSON-size case
"""
import json
import math
import os
import random
import sys

J = 1.12687602e-5
KB = 1.0 / 123.569311
C3 = 1.822e-7
C4 = 1.1389e-4
W0 = 350.0
NOISE_V = 0.003            # white noise on A0 before the converter (0.6 LSB)
LSB = 5.0 / 1023.0
PUTTY_HEADER = "=~=~=~=~=~=~=~=~=~=~=~= PuTTY log 2024.03.14 10:22:31 =~=~=~=~=~=~=~=~=~=~=~=\r\n"


def omega(tau, w0, c3, c4):
    """Speed tau seconds after the cut: J dw/dt = -(c3 w + c4), clamped at the stop."""
    if tau <= 0:
        return w0
    w = (w0 + c4 / c3) * math.exp(-c3 * tau / J) - c4 / c3
    return max(w, 0.0)


def t_stop_after_cut(w0, c3, c4):
    return (J / c3) * math.log(1.0 + c3 * w0 / c4)


def adc_print(v_true, rng, noise=NOISE_V):
    """What the sketch prints for a true A0 voltage: 10-bit count, *5/1023, 2 decimals."""
    count = int(math.floor((v_true + rng.gauss(0.0, noise)) / LSB + 0.5))
    count = min(max(count, 0), 1023)
    return "%.2f" % (count * LSB), count


def make_run(seed, w0=W0, c3=C3, c4=C4, lead_s=3.5, rest_s=6.0, m0=48213, damage=True):
    rng = random.Random(seed)
    T = t_stop_after_cut(w0, c3, c4)
    # millis() of each loop iteration
    times = []
    m = m0
    t_cut_ms = m0 + lead_s * 1000.0 + rng.uniform(0.0, 20.0)  # supply cut (and A0 connected)
    end_ms = t_cut_ms + T * 1000.0 + rest_s * 1000.0
    while m <= end_ms:
        times.append(m)
        m += 21 if rng.random() < 0.15 else 20
    samples = []  # (millis, printed, kind) kind: lead, coast, rest
    for ms in times:
        tau = (ms - t_cut_ms) / 1000.0
        if tau < 0:
            samples.append([ms, "0.00", "lead", 0.0])
        else:
            v = KB * omega(tau, w0, c3, c4)
            txt, _ = adc_print(v, rng)
            samples.append([ms, txt, "coast" if tau < T else "rest", v])
    coast_idx = [i for i, s in enumerate(samples) if s[2] == "coast"]
    first_coast = coast_idx[0]
    outliers = []
    garbled = []
    if damage:
        # candidate positions: 2 s after the cut .. 8 s before the stop (reading > ~0.5 V)
        cand = [i for i in coast_idx
                if 2.0 <= (samples[i][0] - t_cut_ms) / 1000.0 <= T - 8.0]
        chosen = []
        tries = 0
        while len(chosen) < 10 and tries < 10000:
            tries += 1
            i = rng.choice(cand)
            if all(abs(i - j) >= 40 for j in chosen):
                chosen.append(i)
        chosen.sort()
        kinds = ["zero", "half", "zero", "garble-bytes", "half", "zero", "garble-letters",
                 "half", "zero", "garble-cut"]
        rng.shuffle(kinds)
        for i, k in zip(chosen, kinds):
            ms, txt, _, v = samples[i]
            if k == "zero":
                samples[i] = [ms, "0.00", "dropout-zero", v]
                outliers.append({"t_s": ms / 1000.0, "kind": "dropout reading 0", "true_v": v})
            elif k == "half":
                t2, _ = adc_print(v / 2.0, rng)
                samples[i] = [ms, t2, "glitch-half", v]
                outliers.append({"t_s": ms / 1000.0, "kind": "glitch reading half", "true_v": v,
                                 "printed": t2})
            else:
                garbled.append({"t_s": ms / 1000.0, "kind": k})
                samples[i] = [ms, None, k, v]
    lines = []
    for ms, txt, kind, v in samples:
        if kind == "garble-bytes":
            lines.append(b"\xff\xfe?\xfc\xe0?\r\n")
        elif kind == "garble-letters":
            m_s, v_s = str(ms), adc_print(v, rng)[0]
            s = m_s[0] + "O" + m_s[2:] + "\t" + v_s[:-1] + "l"   # bit errors: 0->O, digit->l
            lines.append((s + "\r\n").encode("ascii"))
        elif kind == "garble-cut":
            lines.append(("%d\t\r\n" % ms).encode("ascii"))
        else:
            lines.append(("%d\t%s\r\n" % (ms, txt)).encode("ascii"))
    # PuTTY was opened mid-line: the first line is the tail of one
    if damage:
        lines[0] = lines[0][lines[0].index(b"\t") + 2:]  # e.g. b".00\r\n"
    valid = []
    for (ms, txt, kind, v), ln in zip(samples, lines):
        if txt is None or (damage and ln is lines[0]):
            continue
        valid.append({"t_s": ms / 1000.0, "printed": float(txt),
                      "outlier": kind in ("dropout-zero", "glitch-half")})
    periods = [b - a for a, b in zip(times, times[1:])]
    # physics of what the print can resolve near the stop
    slope_v = KB * (c4 / J)                                   # |dV/dt| at the stop, V/s
    t_unresolved = (1.5 * LSB + 2 * NOISE_V) / slope_v        # reading prints 0.00 below 1.5 counts
    truth = {
        "J": J, "Kb": KB, "c3": c3, "c4": c4, "omega0": w0, "noise_v": NOISE_V,
        "t_cut_s": t_cut_ms / 1000.0,
        "t_first_coast_sample_s": samples[first_coast][0] / 1000.0,
        "t_stop_s": (t_cut_ms + T * 1000.0) / 1000.0,
        "coast_s": T,
        "period_s": sum(periods) / len(periods) / 1000.0,
        "max_period_s": max(periods) / 1000.0,
        "t_unresolved_at_stop_s": t_unresolved,
        "outliers": outliers,
        "garbled": garbled,
        "valid_samples": valid,
        "lines": len(lines),
    }
    return lines, truth


def main():
    what = sys.argv[1]
    out = sys.argv[2]
    os.makedirs(out, exist_ok=True)
    if what == "lab":
        lines, truth = make_run(seed=3301)
        serial = b"".join(lines)
        with open(os.path.join(out, "lab-run.txt"), "wb") as f:
            f.write(PUTTY_HEADER.encode("ascii") + serial)
        with open(os.path.join(out, "lab-run.serial"), "wb") as f:
            f.write(serial)
        # the feeder needs each line's millis for the timing
        with open(os.path.join(out, "lab-run.lines.json"), "w") as f:
            json.dump([ln.decode("latin-1") for ln in lines], f)
        with open(os.path.join(out, "lab-run.truth.json"), "w") as f:
            json.dump(truth, f, indent=1)
    elif what == "many":
        n = int(sys.argv[3])
        d = os.path.join(out, "many")
        os.makedirs(d, exist_ok=True)
        rng = random.Random(3302)
        for k in range(n):
            w0 = rng.uniform(300.0, 420.0)
            c3 = C3 * rng.uniform(0.7, 1.4)
            c4 = C4 * rng.uniform(0.8, 1.25)
            lines, _ = make_run(seed=4000 + k, w0=w0, c3=c3, c4=c4, lead_s=rng.uniform(1, 4),
                                rest_s=3.0, m0=rng.randint(1000, 90000), damage=False)
            with open(os.path.join(d, "run-%02d.txt" % k), "wb") as f:
                f.write(PUTTY_HEADER.encode("ascii") + b"".join(lines))
    else:
        sys.exit("usage: gen.py lab|many OUT_DIR [N]")


if __name__ == "__main__":
    main()
