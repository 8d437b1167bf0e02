"""python3 -m spindown_log LOG [--csv [--bench RE]]: what a spindown log holds, or its samples as
the CSV `spindown export --csv --no-fits` writes."""

import argparse
import math
import sys

from . import SpindownLog, split_channel, unit_of


def _number(x):
    if math.isnan(x):
        return "NaN"
    if math.isinf(x):
        return "Inf" if x > 0 else "-Inf"
    return "%.10g" % x


def _field(s):
    if any(c in s for c in ',"\r\n'):
        return '"' + s.replace('"', '""') + '"'
    return s


def write_csv(log, out, bench=None):
    """The samples as spindown export's CSV (bench,seq,device_time_s,host_time_s,value,unit,raw_adc,clock_epoch)."""
    out.write("bench,seq,device_time_s,host_time_s,value,unit,raw_adc,clock_epoch\n")
    rows = 0
    for m in log.messages(kinds={"SAMPLE"}, bench=bench):
        s = m.message
        unit = _field(unit_of(s.quantity))
        for i in range(s.n):
            adc = s.raw_adc[i]
            out.write("%s,%d,%.6f,%.6f,%s,%s,%s,%d\n" % (
                _field(m.bench), s.seq + i, 1e-6 * s.device_time_us[i], 1e-6 * s.host_time_us[i],
                _number(s.value[i]), unit, str(adc) if adc >= 0 else "", s.clock_epoch))
            rows += 1
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python3 -m spindown_log", description=__doc__)
    ap.add_argument("log", help="LCM event log (spindown-logger, lcm-logger)")
    ap.add_argument("--csv", action="store_true", help="write the samples as CSV on stdout")
    ap.add_argument("--bench", help="only benches whose whole id matches this regular expression")
    a = ap.parse_args(argv)
    log = SpindownLog(a.log)
    try:
        if a.csv:
            rows = write_csv(log, sys.stdout, a.bench)
            print("%d samples" % rows, file=sys.stderr)
        else:
            channels = log.channels()
            print("%s: %d events on %d channels" % (a.log, sum(channels.values()), len(channels)))
            for ch, n in channels.items():
                print("  %8d  %s%s" % (n, ch, "" if split_channel(ch) else "  (not spindown's)"))
            for bench, s in log.samples(bench=a.bench).items():
                if not len(s):
                    continue
                print("bench %s: %d samples (%s), device time %.3f..%.3f s" % (
                    bench, len(s), ", ".join(s.units), min(s.device_time_s), max(s.device_time_s)))
    except OSError as e:
        print("spindown_log: %s" % e, file=sys.stderr)
        return 1
    for p in log.problems:
        print("%s: warning: %s" % (a.log, p), file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
