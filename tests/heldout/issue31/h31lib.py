"""Helpers for the issue-31 held-out cases (standard library only).

- LCM event logs: read and write (the public LCM log format: sync word 0xEDA1DA01,
  event number, timestamp in us, channel length, data length, channel, data; big-endian).
- MCAP: a small reader of uncompressed MCAP files (`spindown export LOG --mcap`), which
  hold the live RUN and FIT messages as JSON (docs/cli.md, "spindown export").
- Judging helpers: match published runs to the virtual bench's truth.
"""
import json
import struct

LCM_SYNC = 0xEDA1DA01


def read_lcm_log(path):
    """Return [(eventnum, utime_us, channel, data_bytes)]; stops at the first damaged event."""
    out = []
    with open(path, "rb") as f:
        buf = f.read()
    i = 0
    n = len(buf)
    while i + 28 <= n:
        sync, evn, ut, clen, dlen = struct.unpack(">IqqiI", buf[i:i + 28])
        if sync != LCM_SYNC or clen < 0 or i + 28 + clen + dlen > n:
            break
        ch = buf[i + 28:i + 28 + clen].decode("utf-8", "replace")
        data = buf[i + 28 + clen:i + 28 + clen + dlen]
        out.append((evn, ut, ch, data))
        i += 28 + clen + dlen
    return out


def write_lcm_log(path, events):
    """events: [(utime_us, channel, data)]; event numbers are rewritten 0.."""
    with open(path, "wb") as f:
        for k, (ut, ch, data) in enumerate(events):
            cb = ch.encode()
            f.write(struct.pack(">IqqiI", LCM_SYNC, k, int(ut), len(cb), len(data)))
            f.write(cb)
            f.write(data)


# ---------------------------------------------------------------- MCAP
MCAP_MAGIC = b"\x89MCAP0\r\n"


def _str(b, i):
    (ln,) = struct.unpack_from("<I", b, i)
    return b[i + 4:i + 4 + ln].decode("utf-8", "replace"), i + 4 + ln


def _records(b, start, end, channels, out):
    i = start
    while i + 9 <= end:
        op = b[i]
        (ln,) = struct.unpack_from("<Q", b, i + 1)
        body = b[i + 9:i + 9 + ln]
        i += 9 + ln
        if op == 0x04:  # Channel
            cid, _sid = struct.unpack_from("<HH", body, 0)
            topic, _ = _str(body, 4)
            channels[cid] = topic
        elif op == 0x05:  # Message
            cid, _seq, log_t, pub_t = struct.unpack_from("<HIQQ", body, 0)
            data = body[22:]
            out.append((channels.get(cid, "?"), log_t, pub_t, data))
        elif op == 0x06:  # Chunk
            _s, _e, _usize, _crc = struct.unpack_from("<QQQI", body, 0)
            comp, j = _str(body, 28)
            (rlen,) = struct.unpack_from("<Q", body, j)
            if comp not in ("", "none"):
                raise ValueError("compressed MCAP chunk (%s) not supported" % comp)
            inner = body[j + 8:j + 8 + rlen]
            _records(inner, 0, len(inner), channels, out)
        elif op == 0x02:  # Footer
            break


def read_mcap(path):
    """Return [(topic, log_time_ns, publish_time_ns, obj_or_None)] of every message."""
    with open(path, "rb") as f:
        b = f.read()
    if not b.startswith(MCAP_MAGIC):
        raise ValueError("not an MCAP file: %s" % path)
    raw = []
    _records(b, len(MCAP_MAGIC), len(b) - len(MCAP_MAGIC), {}, raw)
    out = []
    seen = set()
    for topic, lt, pt, data in raw:
        key = (topic, lt, pt, data)
        if key in seen:  # a message could appear twice only through a reader bug
            continue
        seen.add(key)
        try:
            obj = json.loads(data.decode("utf-8"))
        except Exception:
            obj = None
        out.append((topic, lt, pt, obj))
    out.sort(key=lambda r: r[1])
    return out


# ---------------------------------------------------------------- fits
def model_param(fit, model, name):
    """(value, stderr) of a parameter of a model in a fit --json-like run object."""
    for m in fit.get("models") or []:
        if m.get("name") == model:
            p = (m.get("params") or {}).get(name)
            if isinstance(p, dict):
                v = p.get("value")
                se = p.get("stderr")
                return (v, se)
    return (None, None)


def is_partial(fit):
    """A run whose cut was not seen: lead_in 'none' (docs/faults.md), or a partial flag."""
    if fit.get("partial") is True:
        return True
    li = fit.get("lead_in")
    if isinstance(li, str) and li.strip().lower() in ("none", "partial", "unknown"):
        return True
    note = str(fit.get("note") or "")
    if "not seen" in note.lower() or "partial" in note.lower():
        return True
    if fit.get("t_cut_s") is None:
        return True
    return False


def bench_of(topic, obj):
    parts = topic.split(".")
    if len(parts) >= 3:
        return parts[1]
    b = (obj or {}).get("bench")
    if isinstance(b, dict):
        return b.get("id")
    return b


def fits_from_mcap(path):
    """[(bench, log_time_ns, fit_obj)] of every live FIT in the log."""
    res = []
    for topic, lt, _pt, obj in read_mcap(path):
        if topic.endswith(".FIT") and isinstance(obj, dict):
            res.append((bench_of(topic, obj), lt, obj))
    return res


def runs_from_mcap(path):
    res = []
    for topic, lt, _pt, obj in read_mcap(path):
        if topic.endswith(".RUN") and isinstance(obj, dict):
            res.append((bench_of(topic, obj), lt, obj))
    return res


def friction_ok(fit, truth_cv, truth_cc, whole=True):
    """Combined-model c4 (and, for a whole coast, c3) against the motor's truth.

    A whole coast: c4 within max(3 % of the truth, 4 standard errors capped at 25 % of the
    truth), c3 within max(15 %, 4 se capped at 50 %): a whole coast resolves both, and a fit of
    it 25 % off the motor's dry friction is never right, whatever error it states.
    A coast a fault cut short (whole=False): c4 within max(3 %, 4 se) (a short window trades c4
    against c3; its stated error must cover the truth); c3 is not judged.
    """
    c4, s4 = model_param(fit, "combined", "c4")
    c3, s3 = model_param(fit, "combined", "c3")
    if c4 is None:
        return False, "no combined c4"
    if whole:
        tol4 = max(0.03 * truth_cc, min(4.0 * (s4 or 0.0), 0.25 * truth_cc))
    else:
        tol4 = max(0.03 * truth_cc, 4.0 * (s4 or 0.0))
    ok = abs(c4 - truth_cc) <= tol4
    txt = "c4 %.4g (truth %.4g, tol %.2g)" % (c4, truth_cc, tol4)
    if whole:
        if c3 is None:
            return False, txt + " no c3"
        tol3 = max(0.15 * truth_cv, min(4.0 * (s3 or 0.0), 0.5 * truth_cv))
        ok = ok and abs(c3 - truth_cv) <= tol3
        txt += " c3 %.4g (truth %.4g, tol %.2g)" % (c3, truth_cv, tol3)
    return ok, txt


def load_truth(path):
    with open(path) as f:
        return json.load(f)
