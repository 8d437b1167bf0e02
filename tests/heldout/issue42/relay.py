#!/usr/bin/env python3
"""The network between a bench PC and the lab PC, in user space (this kernel has no netem).

Started inside the bench PC's network namespace: it receives every datagram sent to the lab's
multicast group and port there (as any listener on that PC does: multicast loopback), then
switches to the lab PC's namespace (setns) and sends each datagram, byte for byte, to the same
group and port there, after the impairments of the control file:

  {"delay_ms": 0,                       every datagram (a change applies to datagrams received after it)
   "reorder_p": 0, "reorder_ms": 0,     with probability p a datagram is held reorder_ms longer
   "straggle_p": 0, "straggle_ms": 0,   the same, a second class (late stragglers)
   "dup_p": 0, "dup_extra_ms": [0, 0],  with probability p a second copy, uniform extra delay
   "ge_p": 0, "ge_r": 0,                Gilbert-Elliott loss: good->bad with p, bad->good with r; lost in bad
   "drop": false}                       drop everything (a link down)

The control file is re-read when it changes. Counts go to --stats (JSON) every second and at exit.
Bounded: at most --max-seconds of running, at most --max-queue datagrams held.
"""
import argparse, ctypes, heapq, json, os, random, select, signal, socket, struct, sys, time

ap = argparse.ArgumentParser()
ap.add_argument("--group", default="239.255.76.67")
ap.add_argument("--port", type=int, default=7667)
ap.add_argument("--to-netns", required=True, help="path of the lab PC's namespace, /run/netns/NAME")
ap.add_argument("--ctl", required=True)
ap.add_argument("--stats", required=True)
ap.add_argument("--seed", type=int, default=1)
ap.add_argument("--max-seconds", type=float, default=300)
ap.add_argument("--max-queue", type=int, default=200000)
a = ap.parse_args()
rng = random.Random(a.seed)

rx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM, socket.IPPROTO_UDP)
rx.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
try:
    rx.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEPORT, 1)
except OSError:
    pass
rx.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 8 << 20)
rx.bind(("", a.port))
rx.setsockopt(socket.IPPROTO_IP, socket.IP_ADD_MEMBERSHIP,
              struct.pack("4s4s", socket.inet_aton(a.group), socket.inet_aton("0.0.0.0")))
rx.setblocking(False)

libc = ctypes.CDLL(None, use_errno=True)
fd = os.open(a.to_netns, os.O_RDONLY)
if libc.setns(fd, 0x40000000) != 0:  # CLONE_NEWNET
    sys.exit("relay: setns %s: %s" % (a.to_netns, os.strerror(ctypes.get_errno())))
os.close(fd)
tx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM, socket.IPPROTO_UDP)
tx.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_TTL, 0)
tx.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_LOOP, 1)
dest = (a.group, a.port)

ctl = {}
ctl_mtime = None
def read_ctl():
    global ctl, ctl_mtime
    try:
        st = os.stat(a.ctl)
    except OSError:
        return
    if st.st_mtime_ns == ctl_mtime:
        return
    try:
        with open(a.ctl) as f:
            ctl = json.load(f)
        ctl_mtime = st.st_mtime_ns
    except (OSError, ValueError):
        pass  # half-written: next round

stats = {"received": 0, "sent": 0, "lost": 0, "duplicated": 0, "held_extra": 0, "send_errors": 0,
         "max_queue": 0, "ctl_changes": 0}
def write_stats():
    tmp = a.stats + ".tmp"
    with open(tmp, "w") as f:
        json.dump(stats, f)
    os.replace(tmp, a.stats)

stop = False
def on_term(*_):
    global stop
    stop = True
signal.signal(signal.SIGTERM, on_term)
signal.signal(signal.SIGINT, on_term)

heap = []
n = 0
bad = False
t_start = time.monotonic()
last_stats = 0.0
last_ctl = 0.0
read_ctl()
while not stop and time.monotonic() - t_start < a.max_seconds:
    now = time.monotonic()
    if now - last_ctl > 0.02:
        old = ctl_mtime
        read_ctl()
        if ctl_mtime != old:
            stats["ctl_changes"] += 1
        last_ctl = now
    timeout = 0.02
    if heap:
        timeout = max(0.0, min(timeout, heap[0][0] - now))
    r, _, _ = select.select([rx], [], [], timeout)
    if r:
        for _ in range(1000):
            try:
                data = rx.recv(65536)
            except BlockingIOError:
                break
            stats["received"] += 1
            t = time.monotonic()
            # Gilbert-Elliott
            gp, gr = float(ctl.get("ge_p", 0)), float(ctl.get("ge_r", 0))
            if gp > 0 or bad:
                if bad:
                    if rng.random() < gr:
                        bad = False
                elif rng.random() < gp:
                    bad = True
            if bad or ctl.get("drop"):
                stats["lost"] += 1
                continue
            d = float(ctl.get("delay_ms", 0))
            if rng.random() < float(ctl.get("reorder_p", 0)):
                d += float(ctl.get("reorder_ms", 0)); stats["held_extra"] += 1
            if rng.random() < float(ctl.get("straggle_p", 0)):
                d += float(ctl.get("straggle_ms", 0)); stats["held_extra"] += 1
            if len(heap) < a.max_queue:
                heapq.heappush(heap, (t + d / 1000.0, n, data)); n += 1
            if rng.random() < float(ctl.get("dup_p", 0)):
                lo, hi = ctl.get("dup_extra_ms", [0, 0])
                dd = d + rng.uniform(float(lo), float(hi))
                if len(heap) < a.max_queue:
                    heapq.heappush(heap, (t + dd / 1000.0, n, data)); n += 1
                    stats["duplicated"] += 1
    now = time.monotonic()
    while heap and heap[0][0] <= now:
        _, _, data = heapq.heappop(heap)
        try:
            tx.sendto(data, dest)
            stats["sent"] += 1
        except OSError:
            stats["send_errors"] += 1
    stats["max_queue"] = max(stats["max_queue"], len(heap))
    if now - last_stats > 1.0:
        write_stats(); last_stats = now
# what is still held is delivered (a link that comes back), bounded by the queue itself
while heap:
    _, _, data = heapq.heappop(heap)
    try:
        tx.sendto(data, dest); stats["sent"] += 1
    except OSError:
        stats["send_errors"] += 1
write_stats()
