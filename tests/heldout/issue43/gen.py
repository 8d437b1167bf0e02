#!/usr/bin/env python3
"""Write every case's input files from physics: python3 gen.py SCRATCH_DIR

Each case gets SCRATCH_DIR/<case>/ with its inputs and truth.json (the physics of the run and
what a correct tool must do). CASES.md says what each device or program is and why its bytes
look as they do. Deterministic (fixed seeds)."""
import json
import math
import os
import random
import sys
import unicodedata

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from physics import (Bench, LoopClock, record, truth_dict, avr_adc, arduino_print_float,  # noqa: E402
                     steel_flywheel_J, J_LAB, KB_LAB, CV_LAB, CC_LAB)


def putty_header(stamp):
    return "=~=~=~=~=~=~=~=~=~=~=~= PuTTY log %s =~=~=~=~=~=~=~=~=~=~=~=\r\n" % stamp


def lab_sketch_lines(rows, vref=5.0, digits=2, time_fn=None):
    """The handout's sketch: data = analogRead(A0); data = data*5/1023; print(millis()) '\t'
    println(data) -> CR LF."""
    out = []
    for ms, v, _ in rows:
        c = avr_adc(v, vref=vref)
        t = time_fn(ms) if time_fn else str(int(ms))
        out.append("%s\t%s\r\n" % (t, arduino_print_float(c * 5 / 1023.0, digits)))
    return out


def multi_run(benches, lead_s=3.0, tail_s=3.0, start_ms=1500.0, seed=7, period_ms=20.35):
    """Several spin-downs on one device clock (the student re-powers the motor between them;
    A0 is disconnected while it spins up, so the lead-in of each reads 0)."""
    rows_all, cuts = [], []
    t0 = start_ms
    for i, b in enumerate(benches):
        clk = LoopClock(period_ms=period_ms, start_ms=t0, seed=seed + i)
        rows, cut = record(b, lead_s=lead_s, tail_s=tail_s, clock=clk)
        rows_all.extend(rows)
        cuts.append((cut, cut + b.coast.t_stop * 1000.0))
        t0 = rows[-1][0] + period_ms
    return rows_all, cuts


def write(path, data, mode="w"):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    if isinstance(data, str):
        data = data.encode("utf-8")
    with open(path, "wb") as f:
        f.write(data)


def write_truth(d, truth):
    write(os.path.join(d, "truth.json"), json.dumps(truth, indent=1, ensure_ascii=False))


def reference_file(path, bench_seed, cc=CC_LAB, cv=CV_LAB, runs=3, stamp="2024.09.24 09:05:11"):
    """A motor's good runs for its baseline (the lab sketch, PuTTY log)."""
    benches = [Bench(cv=cv, cc=cc, e_cut=2.8 - 0.05 * i, seed=bench_seed * 10 + i) for i in range(runs)]
    rows, _ = multi_run(benches, seed=bench_seed * 10)
    write(path, putty_header(stamp) + "".join(lab_sketch_lines(rows)))
    return {"c_v": cv, "c_c": cc, "runs": runs}


# ================================================================ formats and readers

def case_fmt_tek_tbs_csv(root):
    """A Tektronix TBS1052B's 'Save All' spreadsheet file (F0000CH1.CSV): 2500 points, six
    columns per row; the settings sit in columns 1-3 of the first 18 rows, the time (s, from the
    trigger) and the value (V) in columns 4 and 5 of every row, each row ending in a comma."""
    d = os.path.join(root, "fmt_tek_tbs_csv")
    b = Bench(seed=431)
    n, dt, trig = 2500, 0.02, 500          # 5 s/div, trigger point 500: 10 s before the cut
    step = 0.5 / 25.0                      # 500 mV/div, 25 levels a division (8-bit)
    rows = []
    for i in range(n):
        t = (i - trig) * dt
        v = b.terminal_volts(t, noise=0.004, ripple=0.01)
        q = round(v / step) * step
        rows.append((t, q))
    meta = [
        ("Record Length", "2.500000e+03"), ("Sample Interval", "2.000000e-02"),
        ("Trigger Point", "5.000000000000e+02"), ("", ""), ("", ""), ("", ""),
        ("Source", "CH1"), ("Vertical Units", "V"), ("Vertical Scale", "5.000000e-01"),
        ("Vertical Offset", "-1.500000e+00"), ("Horizontal Units", "s"),
        ("Horizontal Scale", "5.000000e+00"), ("Pt Fmt", "Y"), ("Yzero", "0.000000e+00"),
        ("Probe Atten", "1.000000e+01"), ("Model Number", "TBS1052B"),
        ("Serial Number", "C041337"), ("Firmware Version", "FV:v4.2.0"),
    ]
    out = []
    for i, (t, q) in enumerate(rows):
        k, v = meta[i] if i < len(meta) else ("", "")
        out.append("%s,%s,,%.12f,%.5f,\r\n" % (k, v, t, q))
    write(os.path.join(d, "F0000CH1.CSV"), "".join(out))
    write_truth(d, truth_dict(b, 0.0, kind="reader", file="F0000CH1.CSV",
                              time_column=4, time_unit="s", value_column=5, value_unit="V",
                              name_re=r"(?i)sample interval|tektronix|TBS|column 4|column 5"))


def case_fmt_raw_adc_counts(root):
    """The handout's sketch with the conversion line deleted: data is still a float, so
    Serial.println(data) prints the count with two decimals ("574.00")."""
    d = os.path.join(root, "fmt_raw_adc_counts")
    b = Bench(seed=432)
    rows, cut = record(b, lead_s=3.5, tail_s=3.0, clock=LoopClock(start_ms=2311.0, seed=4321))
    lines = ["%d\t%s\r\n" % (int(ms), arduino_print_float(float(avr_adc(v)), 2)) for ms, v, _ in rows]
    write(os.path.join(d, "putty.log"), putty_header("2024.10.08 14:02:13") + "".join(lines))
    write_truth(d, truth_dict(b, cut, kind="reader", file="putty.log", counts_to_volts=5 / 1023.0,
                              name_re=r"(?i)\bADC\b|raw (?:ADC )?counts?|analogRead|\b1023\b"))


def case_fmt_micros_clock(root):
    """The lab sketch with Serial.print(micros()) in place of millis(): the time column is in
    microseconds (multiples of 4 µs on a 16 MHz Uno), stepping ~20350 a line. The bench has a
    baseline from the same motor's good runs (lab sketch, millis)."""
    d = os.path.join(root, "fmt_micros_clock")
    ref = reference_file(os.path.join(d, "ref", "bench-m_good.log"), 33)
    b = Bench(seed=433)
    rows, cut = record(b, lead_s=4.0, tail_s=3.0, clock=LoopClock(start_ms=13456.789, seed=4331))
    lines = lab_sketch_lines(rows, time_fn=lambda ms: str(int(ms * 1000.0) // 4 * 4))
    write(os.path.join(d, "week.log"), putty_header("2024.10.08 15:40:02") + "".join(lines))
    write_truth(d, truth_dict(b, cut, kind="reader", file="week.log", bench="bench-m",
                              time_unit="us", reference=ref,
                              name_re=r"(?i)micros|µs|\bus\b|microsecond|--time-unit|time unit"))


def case_fmt_pyserial_bytes_repr(root):
    """A student's pyserial logger on Windows, `print(ser.readline())` redirected to a file:
    each line is Python's repr of the bytes, b'12345\\t2.64\\r\\n', and print adds CR LF.
    The script was started mid-line, so the first repr holds a cut line."""
    d = os.path.join(root, "fmt_pyserial_bytes_repr")
    b = Bench(seed=434)
    rows, cut = record(b, lead_s=3.0, tail_s=3.0, clock=LoopClock(start_ms=48211.0, seed=4341))
    raw = lab_sketch_lines(rows)
    out = []
    for i, line in enumerate(raw):
        if i == 0:
            line = line[3:]
        out.append(repr(line.encode("ascii")) + "\r\n")
    write(os.path.join(d, "log.txt"), "".join(out))
    write_truth(d, truth_dict(b, cut, kind="reader", file="log.txt",
                              name_re=r"(?i)b'|\brepr\b|decode|python|pyserial"))


# ================================================================ the same bytes live and offline

def case_live_pico_micropython_space(root):
    """A Raspberry Pi Pico running MicroPython:
        print(time.ticks_ms(), adc.read_u16() * 3.3 / 65535); time.sleep_ms(20)
    print separates with a space; the USB REPL turns \\n into \\r\\n; floats are single
    precision, printed with up to 7 significant digits; read_u16 is the 12-bit count scaled
    to 16 bits."""
    d = os.path.join(root, "live_pico_micropython_space")
    b = Bench(seed=435)
    rows, cut = record(b, lead_s=3.0, tail_s=3.0, clock=LoopClock(period_ms=20.6, start_ms=9137.0, seed=4351))
    out = []
    for ms, v, _ in rows:
        c12 = min(max(int(math.floor(v * 4096 / 3.3)), 0), 4095)
        u16 = (c12 << 4) | (c12 >> 8)
        x = u16 * 3.3 / 65535
        s = "%.7g" % x
        if "." not in s and "e" not in s:
            s += ".0"
        out.append("%d %s\r\n" % (int(ms), s))
    write(os.path.join(d, "capture.txt"), "".join(out))
    write_truth(d, truth_dict(b, cut, kind="live", file="capture.txt", samples=len(rows)))


def case_live_uno_header_three_columns(root):
    """An Uno whose sketch prints a header in setup() and the raw count beside the volts:
        Serial.println("ms\\traw\\tvolts");  ...  millis '\\t' raw '\\t' println(raw*5.0/1023)
    Opening the port resets the Uno (DTR), so the header is the first line the port gives."""
    d = os.path.join(root, "live_uno_header_three_columns")
    b = Bench(seed=436)
    rows, cut = record(b, lead_s=3.0, tail_s=3.0, clock=LoopClock(period_ms=20.45, start_ms=0.0, seed=4361))
    out = ["ms\traw\tvolts\r\n"]
    for ms, v, _ in rows:
        c = avr_adc(v)
        out.append("%d\t%d\t%s\r\n" % (int(ms), c, arduino_print_float(c * 5.0 / 1023, 2)))
    write(os.path.join(d, "capture.txt"), "".join(out))
    write_truth(d, truth_dict(b, cut, kind="live", file="capture.txt", samples=len(rows)))


def case_live_esp32_boot_rom(root):
    """An ESP32 DevKit: opening the port pulses EN through RTS, the ROM bootloader prints its
    banner at 115200 (label:value pairs and commas), then the sketch prints
    millis '\\t' println(analogReadMilliVolts(34)/1000.0, 3). The ADC (11 dB) reads 0 below
    about 0.1 V and is noisier than the Uno's."""
    d = os.path.join(root, "live_esp32_boot_rom")
    b = Bench(seed=437)
    rows, cut = record(b, lead_s=3.0, tail_s=3.0, noise=0.008,
                       clock=LoopClock(period_ms=20.08, start_ms=312.0, seed=4371))
    boot = ("\x00\xff\x00"
            "ets Jun  8 2016 00:22:57\r\n\r\n"
            "rst:0x1 (POWERON_RESET),boot:0x13 (SPI_FAST_FLASH_BOOT)\r\n"
            "configsip: 0, SPIWP:0xee\r\n"
            "clk_drv:0x00,q_drv:0x00,d_drv:0x00,cs0_drv:0x00,hd_drv:0x00,wp_drv:0x00\r\n"
            "mode:DIO, clock div:1\r\n"
            "load:0x3fff0030,len:1184\r\n"
            "load:0x40078000,len:13260\r\n"
            "load:0x40080400,len:3028\r\n"
            "entry 0x400805e4\r\n")
    out = []
    rng = random.Random(4372)
    for ms, v, _ in rows:
        mv = 0 if v < 0.1 else int(round(v * 1000 + rng.gauss(0, 2)))
        out.append("%d\t%s\r\n" % (int(ms), arduino_print_float(mv / 1000.0, 3)))
    data = boot.encode("latin-1") + "".join(out).encode("ascii")
    write(os.path.join(d, "capture.txt"), data)
    write_truth(d, truth_dict(b, cut, kind="live", file="capture.txt", samples=len(rows),
                              physics_checked=False))


# ================================================================ a class through an LMS

def nfd(s):
    return unicodedata.normalize("NFD", s)


def nfc(s):
    return unicodedata.normalize("NFC", s)


def case_class_finder_nfd_roster(root):
    """A Teams/Google-Classroom download unpacked on Linux: one folder per student (NFC names),
    each holding PuTTY's default log name putty.log. The instructor built roster.csv on a Mac
    by pasting each file's path from Finder (NFD) and typing the names (NFC)."""
    d = os.path.join(root, "class_finder_nfd_roster")
    motors = {"bench1": (CV_LAB, 1.10e-4), "bench2": (CV_LAB, 1.14e-4),
              "bench3": (CV_LAB, 1.18e-4), "bench4": (CV_LAB, 1.12e-4)}
    refs = {}
    for i, (bench, (cv, cc)) in enumerate(sorted(motors.items())):
        refs[bench] = reference_file(os.path.join(d, "ref", bench + ".log"), 50 + i, cc=cc, cv=cv)
    students = [("Jürgen Schäfer", "bench3"), ("Zoë Lefèvre", "bench3"), ("Ana Núñez", "bench1"),
                ("Björn Åström", "bench2"), ("Chloé Dubois", "bench4"), ("Sören Kähler", "bench4")]
    worn = {"bench3": (1.5, 2.2)}          # this week bench 3's bearing is dry: c_v ×1.5, c_c ×2.2
    files = []
    for k, (name, bench) in enumerate(students):
        cv, cc = motors[bench]
        fv, fc = worn.get(bench, (1.0, 1.0))
        b = Bench(cv=cv * fv, cc=cc * fc, e_cut=2.78 + 0.01 * k, seed=600 + k)
        rows, _ = record(b, lead_s=3.0, tail_s=3.0, clock=LoopClock(start_ms=1800.0 + 97 * k, seed=610 + k))
        rel = os.path.join(nfc(name), "putty.log")
        write(os.path.join(d, "class", rel),
              putty_header("2024.10.15 1%d:%02d:07" % (k % 6, 10 + k)) + "".join(lab_sketch_lines(rows)))
        files.append({"file": rel, "bench": bench, "student": nfc(name),
                      "health": "not ok" if bench in worn else "ok", "c_v": cv * fv, "c_c": cc * fc})
    roster = "file,bench,student\r\n" + "".join(
        "%s,%s,%s\r\n" % (nfd(f["file"]), f["bench"], f["student"]) for f in files)
    write(os.path.join(d, "class", "roster.csv"), roster)
    write_truth(d, {"kind": "class", "files": files, "references": refs})


MACROMAN_NAMES = [("zoe.txt", "bench1", "Zoë Brontë"), ("francois.txt", "bench2", "François Mäder"),
                  ("jurgen.txt", "bench3", "Jürgen Groß")]


def case_class_excel_mac_roster(root):
    """The roster saved by Excel for Mac as 'Comma Separated Values (.csv)': Mac OS Roman bytes
    (ë 0x91, ç 0x8D, ä 0x8A, ü 0x9F, ß 0xA7) and CR line ends."""
    d = os.path.join(root, "class_excel_mac_roster")
    for k, (fname, bench, _) in enumerate(MACROMAN_NAMES):
        b = Bench(seed=700 + k)
        rows, _ = record(b, lead_s=3.0, tail_s=3.0, clock=LoopClock(start_ms=2200.0 + 31 * k, seed=710 + k))
        write(os.path.join(d, fname), putty_header("2024.10.22 10:1%d:44" % k) + "".join(lab_sketch_lines(rows)))
    text = "file,bench,student\r" + "".join("%s,%s,%s\r" % r for r in MACROMAN_NAMES)
    write(os.path.join(d, "roster.csv"), text.encode("mac_roman"))
    write_truth(d, {"kind": "class", "files": [{"file": f, "bench": b, "student": s}
                                                for f, b, s in MACROMAN_NAMES],
                    "roster_encoding": "mac_roman", "line_end": "CR"})


# ================================================================ verdicts that name the cause

def verdict_case(root, name, bench_id, seed, this_week, truth_extra, reference_cc=CC_LAB,
                 recorder=None):
    d = os.path.join(root, name)
    ref = reference_file(os.path.join(d, "ref", bench_id + "_good.log"), seed, cc=reference_cc)
    rows, cut = record(this_week, lead_s=3.0, tail_s=3.0, clock=LoopClock(start_ms=3100.0, seed=seed + 1))
    lines = recorder(rows) if recorder else lab_sketch_lines(rows)
    write(os.path.join(d, "week.log"), putty_header("2024.11.05 11:12:13") + "".join(lines))
    t = truth_dict(this_week, cut, kind="verdict", file="week.log", bench=bench_id, reference=ref)
    t.update(truth_extra)
    write_truth(d, t)


def case_verdict_dmm_across_leads(root):
    """A student meant to watch the voltage with a multimeter but left its probes in the mA jack
    (400 mA range: shunt and fuse ≈ 10 Ω) across the motor leads. The armature current brakes
    the shaft (viscous K²/(R_a+R) = 3.3e-6 N·m·s, ×19) and A0 reads the divider R/(R_a+R) = 0.5
    of the back-EMF, so the apparent dry friction halves."""
    b = Bench(r_load=10.0, seed=441)
    verdict_case(root, "verdict_dmm_across_leads", "bench-d", 44, b, {
        "expected_ratios": {"c3": b.cv / CV_LAB, "c4": b.term_scale},
        "cause": "electrical braking: a load across the motor leads",
        "cause_re": r"(?i)\blead|electric|brak|\bshort|across the (?:motor|terminal|lead)|\bmeter|multimeter|ammeter|disconnect|\bload\b",
        "wrong_first_re": r"(?i)lubric|grease|bearing|alignment"})


def case_verdict_steel_flywheel(root):
    """The bench's aluminium cylinder swapped for a steel one of the same size (the workshop
    made a spare): J is 2.72× the bench file's. The motor is unchanged; every c from the file's J
    is 0.367× (both alike), and the coast lasts 2.7× longer."""
    J = steel_flywheel_J()
    b = Bench(J=J, seed=442)
    r = J_LAB / J
    verdict_case(root, "verdict_steel_flywheel", "bench-s", 45, b, {
        "expected_ratios": {"c3": r, "c4": r},
        "cause": "J (the flywheel) is not the bench file's",
        "cause_re": r"(?i)\bJ\b|inertia|flywheel",
        "wrong_first_re": r"(?i)lubric|grease|bearing|alignment|wear"})


def case_verdict_3v3_board(root):
    """The bench's Uno replaced by an Arduino Nano 33 IoT (SAMD21): analogRead is 10-bit by
    default but on a 3.3 V reference, and the handout's sketch still multiplies by 5/1023, so
    every reading is 5/3.3 = 1.515× the back-EMF. c3 (a rate) is unchanged; c4 and ω0 read
    1.515×."""
    b = Bench(seed=443)

    def rec(rows):
        return lab_sketch_lines(rows, vref=3.3)
    verdict_case(root, "verdict_3v3_board", "bench-n", 46, b, {
        "expected_ratios": {"c3": 1.0, "c4": 5.0 / 3.3},
        "cause": "the reading's scale (ADC reference), not friction",
        "cause_re": r"(?i)scale|\bK_?b\b|reference|divider|\bADC\b|converter|calibrat|3\.3 ?V|speed constant|back-EMF constant",
        "wrong_first_re": r"(?i)lubric|grease|bearing|alignment|wear"}, recorder=rec)


def case_verdict_step_up_semester(root):
    """Eight weekly sessions on one bench (PuTTY logs dated by their headers). In week 5 the
    flywheel was dropped and the bearing shield dented: dry friction steps from 1.14e-4 to
    1.94e-4 N·m and stays there (weeks 1-4 and 5-8 scatter 2 % about their levels)."""
    d = os.path.join(root, "verdict_step_up_semester")
    ref = reference_file(os.path.join(d, "ref", "bench-w_good.log"), 47, stamp="2024.09.24 10:00:05")
    rng = random.Random(4747)
    weeks = []
    dates = ["2024.10.01", "2024.10.08", "2024.10.15", "2024.10.22",
             "2024.10.29", "2024.11.05", "2024.11.12", "2024.11.19"]
    for w, date in enumerate(dates, start=1):
        cc = (CC_LAB if w <= 4 else 1.94e-4) * (1 + rng.gauss(0, 0.02))
        cv = CV_LAB * (1 + rng.gauss(0, 0.02))
        benches = [Bench(cv=cv, cc=cc, e_cut=2.8 - 0.04 * k, seed=4700 + 10 * w + k) for k in range(2)]
        rows, _ = multi_run(benches, seed=4800 + 10 * w)
        fn = "week%d.log" % w
        write(os.path.join(d, fn), putty_header(date + " 10:%02d:31" % (10 + w)) + "".join(lab_sketch_lines(rows)))
        weeks.append({"file": fn, "date": date, "c_c": cc, "c_v": cv})
    write_truth(d, {"kind": "verdict", "bench": "bench-w", "weeks": weeks, "reference": ref,
                    "step": {"after": "2024-10-22", "before": "2024-10-29", "c_c_ratio": 1.94e-4 / CC_LAB},
                    "cause": "a step up between week 4 and week 5, not a drift"})


def case_verdict_one_decimal_print(root):
    """A motor with viscous friction alone (the damping exercise's eddy-current brake: c_v =
    1.2e-6 N·m·s/rad, no dry friction; it never stops, the back-EMF decays as e^(−t/9.4 s)),
    read by the lab's Uno and printed with Serial.println(data, 1): one decimal, 0.1 V steps
    (a student 'tidied' the plot). Below 0.05 V the print shows 0.0, 37 s after the cut."""
    d = os.path.join(root, "verdict_one_decimal_print")
    b = Bench(cv=1.2e-6, cc=0.0, seed=444)
    # the coast never stops: record 70 s of it (the reading is 0.0 from ~37 s)
    b.coast.t_stop = 70.0
    rows, cut = record(b, lead_s=3.0, tail_s=0.0, clock=LoopClock(start_ms=2650.0, seed=4441))
    b.coast.t_stop = math.inf
    write(os.path.join(d, "putty.log"), putty_header("2024.11.05 09:31:12") + "".join(lab_sketch_lines(rows, digits=1)))
    t = truth_dict(b, cut, kind="verdict", file="putty.log",
                   allowed_effects=["viscous"],
                   cause="the print's 0.1 V rounding near zero, not friction")
    t["stop_device_s"] = None
    t["coast_s"] = None
    write_truth(d, t)


CASES = [
    case_fmt_tek_tbs_csv, case_fmt_raw_adc_counts, case_fmt_micros_clock, case_fmt_pyserial_bytes_repr,
    case_live_pico_micropython_space, case_live_uno_header_three_columns, case_live_esp32_boot_rom,
    case_class_finder_nfd_roster, case_class_excel_mac_roster,
    case_verdict_dmm_across_leads, case_verdict_steel_flywheel, case_verdict_3v3_board,
    case_verdict_step_up_semester, case_verdict_one_decimal_print,
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
