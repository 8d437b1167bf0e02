#!/bin/bash
# issue 34 held-out: the live lab, run INSIDE `unshare -n` by run.sh (never on the host network).
# lab.sh BIN SCRATCH HERE
# virtual benches -> bridges -> fitter, logger, spindown-web (and two dead /events clients);
# the browser driver (browser.js) watches the pages; everything is killed by the trap.
set -u
BIN=$1; S=$2; HERE=$3
PORT=8734
WEB="http://127.0.0.1:$PORT"
URL='udpm://239.255.76.67:7667?ttl=0'
export LCM_DEFAULT_URL=$URL
PIDS=$S/pids            # run.sh's trap kills these too
: > "$PIDS"
STATUS=$S/lab-status    # key=value lines for judge.py
: > "$STATUS"
st() { echo "$1=$2" >> "$STATUS"; }

cleanup() {
    trap - EXIT INT TERM
    # the logger last and with SIGTERM, so it drains its queue into the log
    while read -r p; do
        case $p in
            pgid:*) kill -KILL -- "-${p#pgid:}" 2>/dev/null ;;
            logger:*) ;;
            *) kill -TERM "$p" 2>/dev/null ;;
        esac
    done < "$PIDS"
    sleep 0.5
    while read -r p; do
        case $p in
            logger:*) kill -TERM "${p#logger:}" 2>/dev/null ;;
            pgid:*) ;;
            *) kill -KILL "$p" 2>/dev/null ;;
        esac
    done < "$PIDS"
    for i in $(seq 1 50); do
        alive=0
        while read -r p; do case $p in logger:*) kill -0 "${p#logger:}" 2>/dev/null && alive=1 ;; esac; done < "$PIDS"
        [ $alive = 0 ] && break; sleep 0.1
    done
    while read -r p; do case $p in logger:*) kill -KILL "${p#logger:}" 2>/dev/null ;; esac; done < "$PIDS"
    wait 2>/dev/null
}
trap cleanup EXIT
trap 'exit 1' INT TERM

ip link set lo up || { st lab_error "ip link set lo up failed"; exit 1; }
ip route add 224.0.0.0/4 dev lo || { st lab_error "ip route add 224.0.0.0/4 dev lo failed"; exit 1; }
mkdir -p "$S/log"

python3 "$HERE/benches.py" "$S/benches.json" || { st lab_error "benches.py failed"; exit 1; }

"$BIN/spindown-logger" --lcm-url "$URL" --dir "$S/log" --flush-interval 0.1 -q > "$S/logger.out" 2> "$S/logger.err" &
echo "logger:$!" >> "$PIDS"
"$BIN/spindown-fitter" --lcm-url "$URL" -v > "$S/fitter.out" 2> "$S/fitter.err" &
echo $! >> "$PIDS"
"$BIN/spindown-web" --lcm-url "$URL" --listen "127.0.0.1:$PORT" > "$S/web.out" 2> "$S/web.err" &
WEBPID=$!
echo $WEBPID >> "$PIDS"
st web_pid $WEBPID

# The web serves its room page within 15 s.
ok=0
for i in $(seq 1 150); do
    if python3 - "$WEB/" <<'PY' 2>/dev/null
import sys, urllib.request
r = urllib.request.urlopen(sys.argv[1], timeout=1)
sys.exit(0 if r.status == 200 else 1)
PY
    then ok=1; break; fi
    kill -0 $WEBPID 2>/dev/null || break
    sleep 0.1
done
if [ $ok = 0 ]; then
    st lab_error "spindown-web did not serve GET / with 200 within 15 s (alive: $(kill -0 $WEBPID 2>/dev/null && echo yes || echo no)); stderr: $(head -c 300 "$S/web.err" | tr '\n' ' ')"
    exit 1
fi
st web_up_ms "$(date +%s%3N)"

# Two dead browsers: connected to /events, never read a byte (tiny receive buffer).
for k in 1 2; do
    python3 - "$PORT" "$S/stalled-$k.txt" <<'PY' &
import socket, sys, time
s = socket.socket(); s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 2048)
s.settimeout(5); s.connect(('127.0.0.1', int(sys.argv[1])))
s.sendall(b'GET /events HTTP/1.1\r\nHost: 127.0.0.1\r\nAccept: text/event-stream\r\n\r\n')
open(sys.argv[2], 'w').write('connected %d\n' % int(time.time() * 1000))
time.sleep(600)   # never reads; killed by the trap
PY
    echo $! >> "$PIDS"
done

# Virtual benches: each waits (60 s at most) for its bridge to open the pty.
python3 - "$S/benches.json" > "$S/bench-args" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
for b in d['benches']:
    print(b['id'], b['runs'], b['idle_s'], b['lead_in_s'], b['tail_s'], b['viscous'], b['coulomb'], b['e0'], b['noise'], b['seed'], b['period_ms'])
PY
while read -r id runs idle lead tail visc coul e0 noise seed period; do
    "$BIN/spindown-virtual-bench" --runs "$runs" --idle "$idle" --lead-in zeros --lead-in-s "$lead" --tail-s "$tail" \
        --viscous "$visc" --coulomb "$coul" --e0 "$e0" --noise "$noise" --seed "$seed" --period-ms "$period" \
        --link "$S/tty-$id" --truth "$S/truth-$id.json" --sent "$S/sent-$id.tsv" --wait-reader 60 \
        > "$S/vb-$id.out" 2> "$S/vb-$id.err" &
    echo $! >> "$PIDS"
done < "$S/bench-args"
for i in $(seq 1 100); do
    n=0; for id in bench-a bench-b bench-c; do [ -e "$S/tty-$id" ] && [ -s "$S/truth-$id.json" ] && n=$((n+1)); done
    [ $n = 3 ] && break; sleep 0.1
done

# The browser: pages open before the benches start, so they see every run from its beginning.
export NODE_PATH=${SPINDOWN_NODE_MODULES:-/opt/spindown-test-node/node_modules}
BRIDGE_C_CMD="[\"$BIN/spindown-bridge\",\"--device\",\"$S/tty-bench-c\",\"--bench\",\"bench-c\",\"--lcm-url\",\"$URL\"]"
WEB=$WEB OUT=$S BENCHES=bench-a,bench-b,bench-c LIVE_BENCH_PAGES=bench-a,bench-b KILL_BENCH=bench-c \
BRIDGE_PIDFILE=$S/bridge-bench-c.pid RESTART_CMD="$BRIDGE_C_CMD" PIDS=$PIDS SCHEDULE=$S/schedule.json \
READY=$S/browser-ready NODE_BUDGET_MS=200000 \
    timeout -k 5 210 node "$HERE/browser.js" > "$S/browser.out" 2> "$S/browser.err" &
NODEPID=$!
echo $NODEPID >> "$PIDS"
for i in $(seq 1 900); do [ -e "$S/browser-ready" ] && break; kill -0 $NODEPID 2>/dev/null || break; sleep 0.1; done
if [ ! -e "$S/browser-ready" ]; then
    st lab_error "the browser driver did not open the pages within 90 s (the pages did not load?): $(tail -c 400 "$S/browser.err" | tr '\n' ' ')"
    exit 1
fi

# The bridges: T0. The schedule follows the benches' truth (bench seconds from T0).
T0=$(date +%s%3N)
for id in bench-a bench-b bench-c; do
    "$BIN/spindown-bridge" --device "$S/tty-$id" --bench "$id" --lcm-url "$URL" > "$S/bridge-$id.out" 2> "$S/bridge-$id.err" &
    echo $! >> "$PIDS"
    echo $! > "$S/bridge-$id.pid"
done
st t0_ms "$T0"
python3 - "$S" "$T0" <<'PY'
import json, sys
S, T0 = sys.argv[1], int(sys.argv[2])
tr = {b: json.load(open('%s/truth-%s.json' % (S, b))) for b in ('bench-a', 'bench-b', 'bench-c')}
c2 = tr['bench-c']['runs'][1]
kill = T0 + int(1000 * (c2['cut_bench_s'] + 4.0))            # 4 s into bench-c's second coast
a = tr['bench-a']['runs']
end = T0 + int(1000 * (a[1]['cut_bench_s'] + a[1]['t_stop_s'] + 4.0))   # bench-a's 2nd FIT (stop + ~2 s) + 2 s
b2 = tr['bench-b']['runs'][1]
end = max(end, T0 + int(1000 * (b2['cut_bench_s'] + b2['t_stop_s'] + 4.0)))
json.dump(dict(t0_ms=T0, kill_at_ms=kill, end_at_ms=end, a_cut3_ms=T0 + int(1000 * a[2]['cut_bench_s'])), open(S + '/schedule.json.tmp', 'w'))
PY
mv "$S/schedule.json.tmp" "$S/schedule.json"

wait $NODEPID
st browser_rc $?
st web_alive_at_end "$(kill -0 $WEBPID 2>/dev/null && echo yes || echo no)"
exit 0
