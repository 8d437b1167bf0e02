#!/bin/bash
# spindown-web under a lab's load: BENCHES benches at RATE Hz (spindown-run-publisher, one sample
# per message as the bridge publishes the lab sketch, RUNS runs each, real time) fitted live by
# spindown-fitter, into one spindown-web with CLIENTS pages connected over Server-Sent Events for
# the whole load (curl -N: most on the room page, one in six on a bench page, and one Python
# client that stamps each event), inside a private network namespace (ttl=0, 127.0.0.1 only).
# Reports the service's CPU (utime+stime from /proc/<pid>/stat over the load), its memory (VmRSS
# at the end, VmHWM the peak), what each page received, and the delay from a FIT on the network
# (its receive time in spindown-logger's log) to the room page's event carrying it.
# Usage: bench/bench_web.sh [BIN_DIR] [BENCHES] [RATE_HZ] [CLIENTS] [RUNS]
if [ -z "${SPINDOWN_IN_NETNS:-}" ]; then exec unshare -n env SPINDOWN_IN_NETNS=1 bash "$0" "$@"; fi
set -euo pipefail
ip link set lo up; ip route add 224.0.0.0/4 dev lo
B=${1:-${SPINDOWN_BIN_DIR:-build/bin}}; N=${2:-30}; RATE=${3:-50}; CLIENTS=${4:-60}; RUNS=${5:-2}
B=$(cd "$B" && pwd)
PYDIR=${SPINDOWN_PYTHON_DIR:-$B/../python}
URL='udpm://239.255.76.67:7667?ttl=0'
PORT=8080
T=$(mktemp -d /tmp/spindown-bench-web.XXXXXX)
PIDS=()
trap 'for p in "${PIDS[@]}"; do kill "$p" 2>/dev/null || true; done; wait 2>/dev/null; rm -rf "$T"' EXIT
mkdir -p "$T/log"
"$B/spindown-logger" --lcm-url "$URL" --dir "$T/log" --prefix bench --channels 'SPINDOWN\..*\.FIT' 2>"$T/logger.err" & PIDS+=($!)
"$B/spindown-fitter" --lcm-url "$URL" 2>"$T/fitter.err" & PIDS+=($!)
"$B/spindown-web" --lcm-url "$URL" --listen "127.0.0.1:$PORT" --max-clients $((CLIENTS + 10)) 2>"$T/web.err" & W=$!
PIDS+=($W)
for _ in $(seq 100); do grep -q serving "$T/web.err" 2>/dev/null && break; sleep 0.1; done
grep -q serving "$T/web.err" || { cat "$T/web.err"; exit 1; }

# The pages: CLIENTS-1 curl streams (every sixth on a bench page) and the stamping client.
for ((i = 1; i < CLIENTS; ++i)); do
  if ((i % 6 == 0)); then path="/events?bench=bench$(printf '%03d' $((i % N)))"; else path="/events"; fi
  curl -sN --max-time 600 "http://127.0.0.1:$PORT$path" -o "$T/client$i.sse" 2>/dev/null & PIDS+=($!)
done
python3 - "$PORT" "$T/stamped.json" <<'PY' & STAMPER=$!
import json, socket, sys, time
s = socket.create_connection(("127.0.0.1", int(sys.argv[1])))
s.sendall(f"GET /events HTTP/1.1\r\nHost: 127.0.0.1:{sys.argv[1]}\r\nAccept: text/event-stream\r\n\r\n".encode())  # the Host it serves
seen, buf, out = {}, b"", open(sys.argv[2], "w")
while True:
    d = s.recv(65536)
    if not d:
        break
    buf += d
    t = time.time() * 1e3
    while b"\n\n" in buf:
        ev, buf = buf.split(b"\n\n", 1)
        if b"event: bench" not in ev and b"event: snapshot" not in ev:
            continue
        data = ev[ev.index(b"data: ") + 6:]
        j = json.loads(data)
        for b in (j["benches"] if "benches" in j else [j]):
            f = b.get("last_fit")
            if f and (b["id"], f["run"]) not in seen:
                seen[(b["id"], f["run"])] = t
                out.write(json.dumps({"bench": b["id"], "run": f["run"], "t_ms": t}) + "\n")
                out.flush()
PY
PIDS+=($STAMPER)
sleep 1
ticks() { awk '{print $14 + $15}' /proc/$W/stat; }
t0=$(date +%s.%N); c0=$(ticks)
"$B/spindown-run-publisher" --lcm-url "$URL" --benches "$N" --runs "$RUNS" --period "$(echo "1/$RATE" | bc -l)" \
  --speed 1 --wait-fits 30 --report "$T/report.json" >"$T/summary.json" 2>"$T/publisher.err"
t1=$(date +%s.%N); c1=$(ticks)
rss=$(awk '/VmRSS/ {print $2}' /proc/$W/status); hwm=$(awk '/VmHWM/ {print $2}' /proc/$W/status)
curl -s "http://127.0.0.1:$PORT/api/state" >"$T/state.json"
sleep 0.5
kill -INT "${PIDS[1]}" 2>/dev/null; kill -TERM "${PIDS[0]}" 2>/dev/null; sleep 1
bytes=$(cat "$T"/client*.sse | wc -c)
PYTHONPATH=$PYDIR python3 - "$T/summary.json" "$t0" "$t1" "$c0" "$c1" "$(getconf CLK_TCK)" "$N" "$RATE" "$CLIENTS" \
  "$rss" "$hwm" "$T/state.json" "$T/stamped.json" "$(ls "$T"/log/*.lcm | head -1)" "$bytes" <<'PY'
import json, sys
from spindown_log import SpindownLog
s = json.load(open(sys.argv[1]))
t0, t1, c0, c1, hz = map(float, sys.argv[2:7])
n, rate, clients, rss, hwm = sys.argv[7], sys.argv[8], int(sys.argv[9]), int(sys.argv[10]), int(sys.argv[11])
state = json.load(open(sys.argv[12]))
stamped = {(j["bench"], j["run"]): j["t_ms"] for j in map(json.loads, open(sys.argv[13]))}
fits = {(m.bench, m.message.run): m.timestamp / 1e3 for m in SpindownLog(sys.argv[14]).messages(kinds={"FIT"})}
dt = t1 - t0
print(f"benches {n} at {rate} Hz, {s['messages']} messages in {dt:.1f} s; fits {s['fits']}/{s['expected_fits']}; {clients} pages connected")
print(f"spindown-web CPU: {100 * (c1 - c0) / hz / dt:.1f} % of one core")
print(f"spindown-web memory: {rss / 1024:.1f} MB resident at the end, peak {hwm / 1024:.1f} MB")
c = state["clients"]
print(f"pages: {c['connected']} connected, {c['refused']} refused, {c['resyncs']} resynced, {c['dropped_events']} events dropped")
print(f"received by the curl pages: {int(sys.argv[15]) / (clients - 1) / dt / 1e3:.1f} kB/s each on average")
delays = sorted(stamped[k] - fits[k] for k in fits if k in stamped)
missing = [k for k in fits if k not in stamped]
if delays:
    q = lambda p: delays[min(len(delays) - 1, int(p * len(delays)))]
    print(f"FIT on the network -> its event at a page: {len(delays)} fits, p50 {q(0.5):.0f} ms, p95 {q(0.95):.0f} ms, max {delays[-1]:.0f} ms"
          + (f"; {len(missing)} not seen" if missing else ""))
else:  # the main figure missing is a failed measurement, not a quiet one
    print(f"FIT on the network -> its event at a page: none of {len(fits)} FITs reached the stamping page (refused? see web.err)")
    sys.exit(1)
PY
tail -1 "$T/web.err" || true
