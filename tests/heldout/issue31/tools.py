#!/usr/bin/python3
"""Small tools for the issue-31 runner (standard library only).

ptyflush PATH
    Discard what waits unread in a serial port's input queue (tcflush TCIFLUSH): an Uno that
    resets when its port is opened gives the new reader nothing from before the reset.
trimlog IN OUT T_FROM_UNIX_S REGEX
    Write the events of IN whose channel matches REGEX and whose log time (utime) is at least
    T_FROM_UNIX_S: "yesterday's log from where the attacker seeks to".
hosttime CSV BENCH DEVICE_S
    From `spindown export --csv` samples: the host time of BENCH's first sample at or after
    device time DEVICE_S.
lastdev LOG BENCH
    (debug) number of events on SPINDOWN.<BENCH>.SAMPLE in a log.
"""
import os
import re
import sys
import termios

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import h31lib  # noqa: E402


def ptyflush(path):
    fd = os.open(path, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
    try:
        termios.tcflush(fd, termios.TCIFLUSH)
    finally:
        os.close(fd)


def trimlog(src, dst, t_from, regex):
    ev = h31lib.read_lcm_log(src)
    if not ev:
        raise SystemExit("trimlog: %s has no events" % src)
    rx = re.compile(regex)
    keep = [(ut, ch, data) for (_n, ut, ch, data) in ev
            if ut >= t_from * 1e6 and rx.fullmatch(ch)]
    h31lib.write_lcm_log(dst, keep)
    print(len(keep))


def main():
    cmd = sys.argv[1]
    if cmd == "ptyflush":
        ptyflush(sys.argv[2])
    elif cmd == "trimlog":
        trimlog(sys.argv[2], sys.argv[3], float(sys.argv[4]), sys.argv[5])
    elif cmd == "hosttime":
        import csv
        with open(sys.argv[2], newline="") as f:
            for row in csv.DictReader(f):
                if row["bench"] == sys.argv[3] and float(row["device_time_s"]) >= float(sys.argv[4]):
                    print(row["host_time_s"])
                    return
        raise SystemExit("hosttime: no sample")
    elif cmd == "lastdev":
        ev = h31lib.read_lcm_log(sys.argv[2])
        print(len([e for e in ev if e[2] == "SPINDOWN.%s.SAMPLE" % sys.argv[3]]))
    else:
        raise SystemExit("tools.py: unknown command " + cmd)


if __name__ == "__main__":
    main()
