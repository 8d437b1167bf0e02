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


# Logs written before issue 31 appended the source and signature fields to every type hold each
# type under an older fingerprint. Such a message is the current encoding without the appended
# fields: it is read as the current type with those fields empty (lab "", session 0, not signed),
# as spindown's own reader does.
_EMPTY_STRING = b"\x00\x00\x00\x01\x00"
_SOURCE_FIELDS = _EMPTY_STRING * 3 + bytes(8 + 8 + 4 + 32)  # lab, sent_to, source_host, session, seq, key id, auth
_BRIDGE_FIELDS = _EMPTY_STRING + bytes(8)                   # run_t, fit_t: bridge_host, bridge_session
_LEGACY = {
    samples_t: (0x6366464c24ab26e1, _SOURCE_FIELDS),
    config_t: (0xf33bcecf4e9c80bd, _SOURCE_FIELDS),
    run_t: (0x52fa3d633257d3ef, _BRIDGE_FIELDS + _SOURCE_FIELDS),
    fit_t: (0x9a6ae2b7c7c8e61c, _BRIDGE_FIELDS + _SOURCE_FIELDS),
    explain_t: (0x8e7064d4b8398716, _SOURCE_FIELDS),
    status_t: (0x056ac82d6252dc21, bytes(8) + _SOURCE_FIELDS),  # start_utime
}


def _current_encoding(cls, data):
    """data itself, or a legacy encoding of cls rewritten as the current one."""
    legacy = _LEGACY.get(cls)
    if legacy is None or len(data) < 8 or struct.unpack(">Q", data[:8])[0] != legacy[0]:
        return data
    return cls._get_packed_fingerprint() + bytes(data[8:]) + legacy[1]


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
        msg = cls.decode(_current_encoding(cls, data))
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
