"""spindown's messages in a log: SPINDOWN.<bench>.<KIND> channels decoded with the types that
lcm-gen -p generates from lcmtypes/*.lcm (the Python package `spindown`, built into
build/python/spindown/ beside this package)."""

import re
import struct

try:
    from spindown import config_t, explain_t, fit_t, run_t, samples_t, status_t
except ImportError as e:  # pragma: no cover - says what to do instead of a bare ImportError
    raise ImportError("spindown_log needs spindown's LCM types (the Python package 'spindown' made by lcm-gen -p): "
                      "build them (cmake --build build --target spindown_python) and use build/python "
                      "(PYTHONPATH=build/python, or pip install build/python)") from e

# The message type of each channel kind, as spindown's services publish them.
TYPES = {
    "SAMPLE": samples_t,
    "CONFIG": config_t,
    "RUN": run_t,
    "FIT": fit_t,
    "EXPLAIN": explain_t,
    "STATUS": status_t,
}

_BENCH = re.compile(r"[A-Za-z0-9_-]{1,32}\Z")


def split_channel(channel):
    """(bench, kind) of a SPINDOWN.<bench>.<KIND> channel, or None for any other channel.

    The bench id is 1 to 32 of [A-Za-z0-9_-]; a service's STATUS channel (SPINDOWN.fitter.STATUS)
    splits the same way, with the service instance in place of the bench."""
    prefix = "SPINDOWN."
    if not channel.startswith(prefix):
        return None
    bench, dot, kind = channel[len(prefix):].partition(".")
    if not dot or not kind or not _BENCH.match(bench):
        return None
    return bench, kind


class DecodeError(ValueError):
    """A message whose bytes are not its channel's type (wrong fingerprint, truncated, damaged)."""


def decode(channel, data):
    """The decoded message of a spindown channel (a samples_t, fit_t, …), or None when the channel
    is not one of spindown's. Raises DecodeError when the bytes are not that type."""
    parts = split_channel(channel)
    if parts is None or parts[1] not in TYPES:
        return None
    cls = TYPES[parts[1]]
    try:
        msg = cls.decode(data)
    except (ValueError, struct.error, UnicodeDecodeError) as e:
        raise DecodeError("%s is not a %s: %s" % (channel, cls.__name__, e or "decode error")) from None
    if cls is samples_t and not (len(msg.device_time_us) == len(msg.host_time_us) == len(msg.value)
                                 == len(msg.raw_adc) == msg.n):
        raise DecodeError("%s: sample arrays do not hold n = %d samples" % (channel, msg.n))
    return msg


class Message:
    """A decoded spindown message: the log event it came in, its bench (or service instance), its
    channel kind ("SAMPLE", "FIT", …) and the message itself."""

    __slots__ = ("event", "bench", "kind", "message")

    def __init__(self, event, bench, kind, message):
        self.event = event
        self.bench = bench
        self.kind = kind
        self.message = message

    @property
    def channel(self):
        return self.event.channel

    @property
    def timestamp(self):
        return self.event.timestamp

    def __repr__(self):
        return "Message(%s, event %d, %s)" % (self.event.channel, self.event.number, type(self.message).__name__)
