"""spindown_log against spindown export, on a real log (tests/integration/python_reader.sh makes
it with spindown-logger and passes it in the environment):

  SPINDOWN_TEST_LOG   the log (3 benches, one spin-down each, every message type)
  SPINDOWN_TEST_CSV   `spindown export LOG --csv` of it (fits beside it: .fits.csv)
  SPINDOWN_BIN_DIR    spindown and spindown-log-summary, run on damaged copies of the log
  SPINDOWN_TEST_WORK  a directory for those copies
  SPINDOWN_REQUIRE_NUMPY=1  fail (not skip) when NumPy is missing
"""

import csv
import json
import math
import os
import random
import shutil
import struct
import subprocess
import sys
import unittest

import spindown_log
from spindown_log import eventlog, samples as samples_module

LOG = os.environ.get("SPINDOWN_TEST_LOG", "")
CSV = os.environ.get("SPINDOWN_TEST_CSV", "")
BIN = os.environ.get("SPINDOWN_BIN_DIR", "")
WORK = os.environ.get("SPINDOWN_TEST_WORK", "")
HAVE_NUMPY = samples_module.numpy is not None


def export_csv(log, out):
    """spindown export LOG --csv -o OUT (fits too: OUT with .fits.csv)."""
    r = subprocess.run([os.path.join(BIN, "spindown"), "export", log, "--csv", "-o", out],
                       stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True, timeout=120)
    if r.returncode != 0:
        raise AssertionError("spindown export %s failed (%d): %s" % (log, r.returncode, r.stderr))
    return out


def csv_rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def by_bench(rows):
    out = {}
    for r in rows:
        out.setdefault(r["bench"], []).append(r)
    return out


class LogTestCase(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        for name, value in (("SPINDOWN_TEST_LOG", LOG), ("SPINDOWN_TEST_CSV", CSV), ("SPINDOWN_BIN_DIR", BIN),
                            ("SPINDOWN_TEST_WORK", WORK)):
            if not value:
                raise AssertionError("%s is not set: run tests/integration/python_reader.sh (ctest -R python_reader)" % name)
        if os.environ.get("SPINDOWN_REQUIRE_NUMPY") == "1" and not HAVE_NUMPY:
            raise AssertionError("NumPy is missing for %s (Debian: python3-numpy; deploy/setup --tests)" % sys.executable)

    def assertSamplesEqualCsv(self, samples, rows, label):
        """Every sample of every bench equals the CSV's row, to the digits export prints."""
        want = by_bench(rows)
        self.assertEqual(list(samples), list(want), "%s: benches (in order of first appearance)" % label)
        for bench, s in samples.items():
            r = want[bench]
            self.assertEqual(len(s), len(r), "%s: bench %s sample count" % (label, bench))
            for i, row in enumerate(r):
                where = "%s: bench %s sample %d (%s)" % (label, bench, i, row)
                self.assertEqual(int(s.seq[i]), int(row["seq"]), where)
                self.assertEqual(int(s.device_time_us[i]), round(float(row["device_time_s"]) * 1e6), where)
                self.assertEqual(int(s.host_time_us[i]), round(float(row["host_time_s"]) * 1e6), where)
                value = float(s.value[i])
                self.assertEqual("NaN" if math.isnan(value) else "%.10g" % value, row["value"], where)
                self.assertEqual(spindown_log.unit_of(int(s.quantity[i])), row["unit"], where)
                self.assertEqual(int(s.raw_adc[i]), int(row["raw_adc"]) if row["raw_adc"] else -1, where)
                self.assertEqual(int(s.clock_epoch[i]), int(row["clock_epoch"]), where)


class RealLog(LogTestCase):
    """The log as the logger wrote it."""

    def test_events_match_spindown_log_summary(self):
        """Event count per channel equals spindown-log-summary's (spindown's C++ reader)."""
        log = spindown_log.SpindownLog(LOG)
        counts = log.channels()
        out = subprocess.run([os.path.join(BIN, "spindown-log-summary"), LOG], stdout=subprocess.PIPE, check=True,
                             timeout=60).stdout
        summary = {}
        for f in json.loads(out)["files"]:
            for ch, n in f["channels"].items():
                summary[ch] = summary.get(ch, 0) + n
        self.assertEqual(counts, summary)
        self.assertEqual(log.problems, [])
        events = spindown_log.read_events(LOG)
        self.assertEqual([e.number for e in events], list(range(len(events))), "event numbers count from 0")
        # Timestamps are LCM's receive times: nearly in order (spindown-logger has been seen to write one
        # 0.16 ms earlier than the event before it), so only their range is checked.
        self.assertLess(events[-1].timestamp - events[0].timestamp, 600 * 10**6)
        self.assertGreater(events[0].timestamp, 10**15)

    def test_every_spindown_type_decodes(self):
        log = spindown_log.SpindownLog(LOG)
        kinds = {}
        for m in log.messages():
            kinds[m.kind] = kinds.get(m.kind, 0) + 1
            self.assertIsInstance(m.message, spindown_log.TYPES[m.kind])
            if m.kind == "STATUS":  # SPINDOWN.<bench>.STATUS from a bridge, SPINDOWN.<service>.STATUS otherwise
                self.assertIn(m.bench, (m.message.instance, m.message.service), m)
            else:
                self.assertEqual(m.message.bench, m.bench, m)
        self.assertEqual(log.problems, [])
        self.assertEqual(set(kinds), {"SAMPLE", "CONFIG", "RUN", "FIT", "EXPLAIN", "STATUS"}, kinds)

    def test_samples_equal_spindown_export(self):
        samples = spindown_log.read_samples(LOG)
        self.assertGreaterEqual(len(samples), 3, "several benches")
        self.assertSamplesEqualCsv(samples, csv_rows(CSV), "lab log")

    @unittest.skipUnless(HAVE_NUMPY, "NumPy not installed")
    def test_numpy_arrays(self):
        import numpy
        s = next(iter(spindown_log.read_samples(LOG, numpy=True).values()))
        self.assertIsInstance(s.value, numpy.ndarray)
        self.assertEqual(s.value.dtype, numpy.float64)
        self.assertEqual(s.seq.dtype, numpy.int64)
        numpy.testing.assert_allclose(s.device_time_s, s.device_time_us * 1e-6)
        # The bridge's sequence numbers are consecutive in this log: no sample lost or repeated.
        self.assertTrue((numpy.diff(s.seq) == 1).all())

    def test_lists_without_numpy(self):
        lists = spindown_log.read_samples(LOG, numpy=False)
        for s in lists.values():
            self.assertIsInstance(s.value, list)
            self.assertIsInstance(s.device_time_s, list)
        self.assertSamplesEqualCsv(lists, csv_rows(CSV), "lab log, lists")

    def test_bench_filter(self):
        rows = csv_rows(CSV)
        first = rows[0]["bench"]
        only = spindown_log.read_samples(LOG, bench=first)
        self.assertEqual(list(only), [first])
        self.assertEqual(len(only[first]), sum(1 for r in rows if r["bench"] == first))

    def test_csv_identical_to_export(self):
        """python3 -m spindown_log LOG --csv writes export's samples CSV byte for byte."""
        r = subprocess.run([sys.executable, "-m", "spindown_log", LOG, "--csv"], stdout=subprocess.PIPE,
                           stderr=subprocess.PIPE, check=True, timeout=120)
        with open(CSV, "rb") as f:
            self.assertEqual(r.stdout.decode().splitlines(), f.read().decode().splitlines())

    def test_recorded_fits_equal_refit(self):
        """The fitter's FIT messages, decoded here, name the same best model and c1 as export's refit."""
        fits = csv_rows(os.path.splitext(CSV)[0] + ".fits.csv")
        recorded = [m for m in spindown_log.SpindownLog(LOG).messages(kinds={"FIT"})]
        self.assertEqual(len(recorded), 3, "one FIT per run")
        for m in recorded:
            f = m.message
            rows = [r for r in fits if r["bench"] == m.bench and int(r["run"]) == f.run]
            best = [r["model"] for r in rows if r["best"] == "1"]
            self.assertEqual(best, [f.best], m)
            c1 = [f.param_value[k] for k in range(f.nparams)
                  if f.param_name[k] == "c1" and f.model[f.param_model[k]] == "viscous"]
            refit = [float(r["c1"]) for r in rows if r["model"] == "viscous"]
            self.assertEqual(len(c1), 1)
            self.assertEqual(len(refit), 1)
            self.assertAlmostEqual(c1[0] / refit[0], 1.0, delta=1e-8)


def event_end(ev):
    """The file offset just after an event."""
    return ev.offset + eventlog.HEADER_BYTES + len(ev.channel.encode()) + len(ev.data)


class DamagedLog(LogTestCase):
    """Damaged copies of the real log: spindown_log and spindown export still agree."""

    def copy(self, name, data):
        path = os.path.join(WORK, name)
        with open(path, "wb") as f:
            f.write(data)
        return path

    def test_truncated_last_event(self):
        """The logger stopped in the middle of writing a SAMPLE message: that message is lost, no other."""
        with open(LOG, "rb") as f:
            data = f.read()
        events = spindown_log.read_events(LOG)
        last = [ev for ev in events if ev.channel.endswith(".SAMPLE")][-1]
        cut = event_end(last) - len(last.data) // 2
        path = self.copy("truncated.lcm", data[:cut])
        log = spindown_log.SpindownLog(path)
        samples = log.samples()
        self.assertEqual(len(log.problems), 1, log.problems)
        self.assertIn("it is the last one and is lost", log.problems[0].text)
        self.assertEqual(log.problems[0].offset, last.offset)
        rows = csv_rows(export_csv(path, os.path.join(WORK, "truncated.csv")))
        self.assertSamplesEqualCsv(samples, rows, "truncated log")
        full = csv_rows(CSV)
        self.assertEqual(len(rows), len(full) - spindown_log.decode(last.channel, last.data).n)
        self.assertEqual(rows, full[:len(rows)])

    def test_truncated_header(self):
        """A log that ends inside an event's 28-byte header."""
        with open(LOG, "rb") as f:
            data = f.read()
        start = spindown_log.read_events(LOG)[-1].offset
        path = self.copy("header.lcm", data[:start + 13])
        log = spindown_log.SpindownLog(path)
        samples = log.samples()
        self.assertEqual(len(log.problems), 1, log.problems)
        self.assertIn("ends inside an event header", log.problems[0].text)
        self.assertSamplesEqualCsv(samples, csv_rows(export_csv(path, os.path.join(WORK, "header.csv"))), "header")

    def test_garbage_between_events(self):
        with open(LOG, "rb") as f:
            data = f.read()
        events = spindown_log.read_events(LOG)
        rnd = random.Random(7)
        noise = bytes(rnd.randrange(256) for _ in range(301)).replace(b"\xed", b"\xee")  # no sync word in it
        sync = eventlog.SYNC_BYTES
        garbage = [
            noise,                                                    # bytes that are no event at all
            sync + struct.pack(">qqii", 0, 0, 0, 5) + noise[:40],     # a sync word with a zero channel length
            sync + struct.pack(">qqii", 0, 0, 20, -1) + noise[:40],   # a negative data length
            sync + struct.pack(">qqii", 0, 0, 10, 1 << 30) + noise[:20],  # an event larger than the file
            sync[:3],                                                 # a sync word cut short
            b"SPINDOWN.bench000.SAMPLE" + noise[:17],                 # a channel name without its header
        ]
        # Between events spread over the log (the SAMPLE events of every bench are among them).
        at = sorted(rnd.sample(range(1, len(events)), len(garbage)))
        out, prev = bytearray(), 0
        for g, i in zip(garbage, at):
            out += data[prev:events[i].offset] + g
            prev = events[i].offset
        out += data[prev:]
        path = self.copy("garbage.lcm", bytes(out))
        log = spindown_log.SpindownLog(path)
        samples = log.samples()
        self.assertGreaterEqual(len(log.problems), len(garbage), log.problems)
        self.assertTrue(all("skipped" in p.text or "looking for the next event" in p.text for p in log.problems),
                        log.problems)
        rows = csv_rows(export_csv(path, os.path.join(WORK, "garbage.csv")))
        self.assertSamplesEqualCsv(samples, rows, "log with garbage")
        # Nothing of the log was lost to the garbage.
        self.assertSamplesEqualCsv(samples, csv_rows(CSV), "log with garbage vs the clean log")
        self.assertEqual(sum(1 for _ in log.events()), len(events))

    def test_not_a_log(self):
        path = self.copy("text.lcm", b"millis\tvolts\n0\t4.2\n")
        log = spindown_log.SpindownLog(path)
        self.assertEqual(log.samples(), {})
        self.assertEqual(len(log.problems), 1)
        self.assertIn("no event follows", log.problems[0].text)


class Install(LogTestCase):
    """pip installs build/python without network into a virtual environment, and it runs there."""

    @unittest.skipUnless(os.environ.get("SPINDOWN_PYTHON_DIR"), "SPINDOWN_PYTHON_DIR not set")
    def test_pip_install_offline(self):
        venv = os.path.join(WORK, "venv")
        shutil.rmtree(venv, ignore_errors=True)
        subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", venv], check=True, timeout=120)
        py = os.path.join(venv, "bin", "python")
        src = os.path.join(WORK, "src")  # pip builds in the folder: a copy keeps build/python clean
        shutil.rmtree(src, ignore_errors=True)
        shutil.copytree(os.environ["SPINDOWN_PYTHON_DIR"], src, ignore=shutil.ignore_patterns("__pycache__"))
        r = subprocess.run([py, "-m", "pip", "install", "--no-build-isolation", "--no-index", "--no-cache-dir", src], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                           universal_newlines=True, timeout=300)
        self.assertEqual(r.returncode, 0, r.stdout)
        env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
        r = subprocess.run([os.path.join(venv, "bin", "spindown-log"), LOG], stdout=subprocess.PIPE,
                           stderr=subprocess.PIPE, universal_newlines=True, env=env, cwd=WORK, timeout=120)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("bench bench000:", r.stdout)
        r = subprocess.run([py, "-c", "import spindown_log, spindown; print(spindown_log.__file__, spindown.fit_t)"],
                           stdout=subprocess.PIPE, universal_newlines=True, env=env, cwd=WORK, check=True, timeout=60)
        self.assertIn(venv, r.stdout)



class LegacyEncodingTest(unittest.TestCase):
    """A log written before the source and signature fields: each type's older encoding reads as
    the current type with those fields empty (as spindown's own reader reads it)."""

    def test_every_type_reads(self):
        from spindown import samples_t, run_t, status_t
        from spindown_log import messages
        m = samples_t()
        m.utime, m.bench, m.seq, m.clock_epoch, m.quantity, m.n = 7, "bench-1", 40, 1, 0, 2
        m.device_time_us, m.host_time_us, m.value, m.raw_adc = [1000, 21000], [5, 6], [1.5, 1.25], [-1, -1]
        m.auth = bytes(32)  # lcm-gen's Python default for byte[32] ("") does not encode
        current = m.encode()
        old = struct.pack(">Q", messages._LEGACY[samples_t][0]) + current[8:-len(messages._LEGACY[samples_t][1])]
        back = spindown_log.decode("SPINDOWN.bench-1.SAMPLE", old)
        self.assertEqual((back.seq, back.n, list(back.value), back.lab, back.source_session), (40, 2, [1.5, 1.25], "", 0))
        for cls, kind in ((run_t, "RUN"), (status_t, "STATUS")):
            r = cls()
            r.auth = bytes(32)
            current = r.encode()
            old = struct.pack(">Q", messages._LEGACY[cls][0]) + current[8:-len(messages._LEGACY[cls][1])]
            self.assertIsInstance(spindown_log.decode("SPINDOWN.x." + kind, old), cls)
        with self.assertRaises(spindown_log.DecodeError):
            spindown_log.decode("SPINDOWN.bench-1.SAMPLE", old)  # a status_t's bytes on a SAMPLE channel


if __name__ == "__main__":
    unittest.main()
