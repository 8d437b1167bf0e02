"""LCM event logs, the format lcm-logger and spindown-logger write, read without LCM.

A log is a sequence of events. Each event is a 28-byte header followed by the channel name and
the message bytes, all integers big-endian:

    sync word    uint32   0xEDA1DA01
    event number int64    counts from 0 in the file
    timestamp    int64    µs since the Unix epoch when the logger received the message
    channel len  int32    bytes of the channel name (LCM: 1..999)
    data len     int32    bytes of the message
    channel      UTF-8
    data         the LCM-encoded message

Damage is handled as spindown's own reader handles it (spindown export, refit): bytes that are
not an event are skipped up to the next sync word, a header with impossible lengths is skipped
byte by byte, and an event that runs past the end of the file (a logger stopped mid-write) is
dropped. Each of these is reported in LogReader.problems, never raised.
"""

import mmap
import os
import struct

SYNC = 0xEDA1DA01
SYNC_BYTES = struct.pack(">I", SYNC)
HEADER = struct.Struct(">Iqqii")
HEADER_BYTES = HEADER.size  # 28
MAX_CHANNEL_BYTES = 1000  # LCM's own limit: a channel name is shorter


class Event:
    """One event: number and timestamp from its header, channel, data (bytes), file offset."""

    __slots__ = ("number", "timestamp", "channel", "data", "offset")

    def __init__(self, number, timestamp, channel, data, offset):
        self.number = number
        self.timestamp = timestamp
        self.channel = channel
        self.data = data
        self.offset = offset

    def __repr__(self):
        return "Event(number=%d, timestamp=%d, channel=%r, %d bytes at offset %d)" % (
            self.number, self.timestamp, self.channel, len(self.data), self.offset)


class Problem:
    """Damage found in the log: where (file offset) and what, in words."""

    __slots__ = ("offset", "text")

    def __init__(self, offset, text):
        self.offset = offset
        self.text = text

    def __repr__(self):
        return "Problem(offset=%d, %r)" % (self.offset, self.text)

    def __str__(self):
        return self.text


class LogReader:
    """Iterates over the events of an LCM log file; problems collects the damage met so far.

        with LogReader("lab.lcm") as log:
            for ev in log:
                print(ev.timestamp, ev.channel, len(ev.data))
            print(log.problems)
    """

    def __init__(self, path):
        self.path = os.fspath(path)
        self.problems = []
        self.events = 0
        self._file = open(self.path, "rb")
        size = os.fstat(self._file.fileno()).st_size
        # A memory map reads a large log without loading it; an empty file cannot be mapped.
        self._data = mmap.mmap(self._file.fileno(), 0, access=mmap.ACCESS_READ) if size else b""

    def close(self):
        if isinstance(self._data, mmap.mmap):
            self._data.close()
        self._data = b""
        self._file.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def _problem(self, offset, text):
        self.problems.append(Problem(offset, text))

    def __iter__(self):
        data = self._data
        size = len(data)
        pos = 0
        while pos < size:
            if size - pos < 4 or data[pos:pos + 4] != SYNC_BYTES:
                at = data.find(SYNC_BYTES, pos)
                if at < 0:
                    self._problem(pos, "%d bytes at offset %d (after event %d) are not an LCM event and no event "
                                  "follows; ignored" % (size - pos, pos, self.events))
                    return
                self._problem(pos, "%d bytes at offset %d (after event %d) are not an LCM event; skipped to the "
                              "next event at offset %d" % (at - pos, pos, self.events, at))
                pos = at
            if size - pos < HEADER_BYTES:
                self._problem(pos, "the log ends inside an event header at offset %d (%d of %d bytes; truncated "
                              "after event %d)" % (pos, size - pos, HEADER_BYTES, self.events))
                return
            _, number, timestamp, channel_len, data_len = HEADER.unpack_from(data, pos)
            if channel_len <= 0 or channel_len >= MAX_CHANNEL_BYTES or data_len < 0:
                self._problem(pos, "damaged event header at offset %d (channel length %d, data length %d) after "
                              "event %d; looking for the next event" % (pos, channel_len, data_len, self.events))
                pos += 1
                continue
            start = pos + HEADER_BYTES
            end = start + channel_len + data_len
            if end > size:
                channel = bytes(data[start:min(start + channel_len, size)]).decode("utf-8", "replace")
                resume = data.find(SYNC_BYTES, pos + 1)
                self._problem(pos, "event %d at offset %d (channel %r) needs %d bytes but the log has %d left: "
                              "truncated or damaged; %s" % (
                                  self.events + 1, pos, channel, channel_len + data_len, size - start,
                                  "skipped to the next event at offset %d" % resume if resume >= 0
                                  else "it is the last one and is lost"))
                if resume < 0:
                    return
                pos = resume
                continue
            self.events += 1
            channel = bytes(data[start:start + channel_len]).decode("utf-8", "replace")
            yield Event(number, timestamp, channel, bytes(data[start + channel_len:end]), pos)
            pos = end


def read_events(path):
    """Every sound event of the log at path, in file order (a list of Event)."""
    with LogReader(path) as log:
        return list(log)
