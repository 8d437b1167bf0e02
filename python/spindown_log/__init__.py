"""Read spindown's LCM event logs (spindown-logger, lcm-logger) in plain Python.

    import spindown_log
    log = spindown_log.SpindownLog("lab-2024-05-01.lcm")
    for ev in log.events():                 # every event: number, timestamp (µs), channel, data
        ...
    for m in log.messages(kinds={"FIT"}):   # decoded spindown messages (lcm-gen -p types)
        print(m.bench, m.message.best)
    samples = log.samples()                 # {bench: BenchSamples}, NumPy arrays when NumPy is there
    s = samples["bench000"]
    s.device_time_s, s.value, s.units       # seconds, readings, ["V"]
    log.problems                            # damage skipped in the last pass (truncation, garbage)

Only the standard library is needed; NumPy is used when it is installed (numpy=False: lists).
The reader skips damage as spindown export does, so both give the same samples.
"""

import re

from .eventlog import Event, LogReader, Problem, read_events
from .messages import TYPES, DecodeError, Message, decode, split_channel
from .samples import BenchSamples, SampleCollector, unit_of

__all__ = [
    "BenchSamples", "DecodeError", "Event", "LogReader", "Message", "Problem", "SpindownLog", "TYPES",
    "decode", "read_events", "read_samples", "split_channel", "unit_of",
]


class SpindownLog:
    """A spindown LCM log. Each method reads the file again (a log may be larger than memory);
    problems holds the damage found by the last pass."""

    def __init__(self, path):
        self.path = path
        self.problems = []

    def events(self):
        """Every sound event in file order (Event: number, timestamp, channel, data, offset)."""
        with LogReader(self.path) as reader:
            self.problems = reader.problems
            for ev in reader:
                yield ev

    def messages(self, kinds=None, bench=None):
        """Decoded messages (Message: event, bench, kind, message) of the SPINDOWN.<bench>.<KIND>
        channels, kinds a set such as {"SAMPLE", "FIT"} (default all), bench a regular expression
        the whole bench id must match (default all). A message that does not decode is skipped
        and reported in problems."""
        wanted = re.compile(bench) if bench is not None else None
        for ev in self.events():
            parts = split_channel(ev.channel)
            if parts is None or parts[1] not in TYPES:
                continue
            b, kind = parts
            if (kinds is not None and kind not in kinds) or (wanted is not None and not wanted.fullmatch(b)):
                continue
            try:
                msg = decode(ev.channel, ev.data)
            except DecodeError as e:
                self.problems.append(Problem(ev.offset, "event %d on %s: %s; skipped" % (ev.number, ev.channel, e)))
                continue
            yield Message(ev, b, kind, msg)

    def samples(self, bench=None, numpy=None):
        """{bench: BenchSamples} of every SAMPLE message, benches in order of first appearance.
        numpy: True for NumPy arrays, False for lists, None (default) arrays when NumPy is there."""
        collect = SampleCollector()
        for m in self.messages(kinds={"SAMPLE"}, bench=bench):
            collect.add(m.bench, m.message, m.event.timestamp)
        return collect.arrays(numpy)

    def channels(self):
        """{channel: number of events}, in order of first appearance."""
        counts = {}
        for ev in self.events():
            counts[ev.channel] = counts.get(ev.channel, 0) + 1
        return counts


def read_samples(path, bench=None, numpy=None):
    """{bench: BenchSamples} of the log at path (see SpindownLog.samples)."""
    return SpindownLog(path).samples(bench=bench, numpy=numpy)
