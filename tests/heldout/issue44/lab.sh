#!/bin/bash
# Held-out issue 44: the labs and the cases, run INSIDE a private network namespace (run.sh starts it
# with `unshare -n`). Usage: lab.sh BIN_DIR SCRATCH_DIR TEST_DIR DOCS_DIR
# Writes one PASS/FAIL line per case to SCRATCH_DIR/results.txt; every process it starts is listed
# in SCRATCH_DIR/pids and ended by its id when this script ends. Every loop is bounded.
set -u
BIN=$1 SCR=$2 HERE=$3 DOCS=$4
RES=$SCR/results.txt PIDS=$SCR/pids LOGS=$SCR/logs
mkdir -p "$LOGS" "$SCR/a" "$SCR/k" "$SCR/l" "$SCR/dl"
: > "$RES"; : > "$PIDS"
T0=$(date +%s)
say() { echo "[$(( $(date +%s) - T0 ))s] $*" >> "$SCR/timeline.txt"; }
record() { echo "$*" >> "$RES"; say "$*"; }

cleanup() {
  trap - EXIT TERM INT
  local p
  for p in $(tac "$PIDS" 2>/dev/null); do kill -CONT "$p" 2>/dev/null; kill -TERM "$p" 2>/dev/null; done
  sleep 0.5
  for p in $(cat "$PIDS" 2>/dev/null); do kill -KILL "$p" 2>/dev/null; done
}
trap cleanup EXIT
trap 'exit 143' TERM INT

# the namespace's network: loopback with multicast; the lab PC's LAN address lives on loopback too
ip link set lo up && ip route add 224.0.0.0/4 dev lo || { echo "FAIL setup: cannot set up the namespace's loopback and multicast route" >> "$RES"; exit 3; }
ip addr add 10.44.0.5/32 dev lo 2>/dev/null
LAN=10.44.0.5

# start NAME CMD...: in the background, log in $LOGS/NAME.log, pid in PID_NAME and $PIDS
start() {
  local name=$1; shift
  "$@" > "$LOGS/$name.log" 2>&1 &
  local pid=$!
  echo "$pid" >> "$PIDS"
  declare -g "PID_${name//-/_}=$pid"
}
stop() { local p=$1; [ -n "$p" ] && { kill -CONT "$p" 2>/dev/null; kill -TERM "$p" 2>/dev/null; }; }
# wait_api PORT EXPR SECONDS: until the expression over /api/state is true
wait_api() {
  local i n=$(( $3 * 2 ))
  for ((i = 0; i < n; i++)); do
    python3 "$HERE/apiq.py" "$1" "$2" > "$SCR/apiq.out" 2>/dev/null && { cat "$SCR/apiq.out"; return 0; }
    sleep 0.5
  done
  return 1
}
# wait_log FILE REGEX SECONDS
wait_log() {
  local i n=$(( $3 * 4 ))
  for ((i = 0; i < n; i++)); do grep -Eq "$2" "$1" 2>/dev/null && return 0; sleep 0.25; done
  return 1
}
wait_link() { local i; for ((i = 0; i < 40; i++)); do [ -e "$1" ] && return 0; sleep 0.25; done; return 1; }
# browser NAME KIND LIMIT_S JSON: one Chromium check, bounded
browser() {
  local name=$1 kind=$2 lim=$3 args=$4 line
  if [ -n "${H44_ONLY:-}" ] && ! [[ $name =~ $H44_ONLY ]]; then return 0; fi   # debugging: only some cases
  say "start $name"
  args=$(python3 -c 'import json,sys; a=json.loads(sys.argv[1]); a["name"]=sys.argv[2]; a["limit_s"]=int(sys.argv[3]); print(json.dumps(a))' "$args" "$name" "$lim")
  line=$(cd "$SCR" && HOME="$SCR" timeout -k 5 $((lim + 15)) node "$HERE/check.js" "$kind" "$args" 2> "$LOGS/node-$name.log" | grep -E "^(PASS|FAIL) $name:" | head -1)
  [ -n "$line" ] || line="FAIL $name: the browser check gave no verdict (see $LOGS/node-$name.log)"
  record "$line"
}
VB=$BIN/spindown-virtual-bench

URL_A='udpm://239.255.76.67:7701?ttl=0'  LAB=phys-2b
URL_K='udpm://239.255.76.67:7702?ttl=0'
URL_L='udpm://239.255.76.67:7703?ttl=0'
URL_R1='udpm://239.255.76.67:7704?ttl=0'
URL_R2='udpm://239.255.76.67:7705?ttl=0'
URL_W='udpm://239.255.76.67:7706?ttl=0'
P_A=18080 P_R1=18081 P_R2=18082 P_W=18083 P_WLAN=18084 P_K=18085 P_L=18086

# ---------------------------------------------------------------- lab A: three benches, no key, lab "phys-2b"
cat > "$SCR/a/bench-a.toml" <<EOF
bench_id = "bench-a"
[serial]
device = "$SCR/a/tty-a"
baud = 9600
[bench]
inertia_kg_m2 = 1.35e-5
kb_v_s_per_rad = 0.00845
quantity = "V"
[adc]
bits = 10
ref_v = 5.0
[lab]
period_s = 0.020
EOF
start vb-a "$VB" --runs 4 --speed 1 --inertia 1.35e-5 --kb 0.00845 --seed 21 --link "$SCR/a/tty-a" --truth "$SCR/a/truth-a.json" --wait-reader 30 --linger 400
start vb-r "$VB" --runs 2 --speed 2 --reset-at 48 --seed 22 --link "$SCR/a/tty-r" --truth "$SCR/a/truth-r.json" --wait-reader 30 --linger 400
start vb-s "$VB" --runs 40 --speed 2 --seed 23 --link "$SCR/a/tty-s" --truth "$SCR/a/truth-s.json" --wait-reader 30 --linger 400
# lab K: one bench, every service with the lab key
"$BIN/spindown" keygen -o "$SCR/k/lab.key" > /dev/null 2>&1
"$BIN/spindown" keygen -o "$SCR/k/wrong.key" > /dev/null 2>&1
start vb-k "$VB" --runs 1 --speed 4 --seed 31 --link "$SCR/k/tty-k" --truth "$SCR/k/truth-k.json" --wait-reader 30 --linger 400
wait_link "$SCR/a/tty-a"; wait_link "$SCR/a/tty-r"; wait_link "$SCR/a/tty-s"; wait_link "$SCR/k/tty-k"
start fit-a "$BIN/spindown-fitter" --lcm-url "$URL_A" --lab "$LAB" -v
start web-a "$BIN/spindown-web" --lcm-url "$URL_A" --lab "$LAB" --listen 127.0.0.1:$P_A
start br-a "$BIN/spindown-bridge" --device "$SCR/a/tty-a" --bench bench-a --config "$SCR/a/bench-a.toml" --lcm-url "$URL_A" --lab "$LAB"
start br-r "$BIN/spindown-bridge" --device "$SCR/a/tty-r" --bench bench-r --lcm-url "$URL_A" --lab "$LAB"
start br-s "$BIN/spindown-bridge" --device "$SCR/a/tty-s" --bench bench-s --lcm-url "$URL_A" --lab "$LAB" --retry-interval 0.2
start fit-k "$BIN/spindown-fitter" --lcm-url "$URL_K" --lab "$LAB" --key "$SCR/k/lab.key" -v
start web-k "$BIN/spindown-web" --lcm-url "$URL_K" --lab "$LAB" --key "$SCR/k/lab.key" --listen 127.0.0.1:$P_K
start br-k "$BIN/spindown-bridge" --device "$SCR/k/tty-k" --bench bench-k --lcm-url "$URL_K" --lab "$LAB" --key "$SCR/k/lab.key"
say "labs A and K started"
# bench-r's first (whole) run as the web reported it, before the reset cuts run 2 short
(
  for ((i = 0; i < 240; i++)); do
    python3 "$HERE/apiq.py" $P_A "(lambda f: f if f and f.get('run') == 1 and f.get('end') == 'stopped' and f.get('c3') else None)(b('bench-r').get('last_fit'))" > "$SCR/a/r-run1.tmp" 2>/dev/null \
      && { mv "$SCR/a/r-run1.tmp" "$SCR/a/r-run1.json"; break; }
    sleep 0.5
  done
) &
echo $! >> "$PIDS"

# ---------------------------------------------------------------- who-may-see (no browser)
say "start who-may-see"
start web-w "$BIN/spindown-web" --lcm-url "$URL_W" --lab "$LAB" --listen 127.0.0.1:$P_W
start web-wlan "$BIN/spindown-web" --lcm-url "$URL_W" --lab "$LAB" --listen $LAN:$P_WLAN
start pub-w "$BIN/spindown-lcm-publish" --lcm-url "$URL_W" --bench bench-1 --count 0 --rate 10 --duration 25 --all-types
if wait_api $P_W "b('bench-1').get('last_fit')" 15 > /dev/null; then
  line=$(timeout -k 5 60 python3 "$HERE/who.py" $P_W $LAN $P_WLAN "$PID_web_w" "$DOCS" bench-1 | grep -E '^(PASS|FAIL) who-may-see:' | head -1)
  record "${line:-FAIL who-may-see: the check gave no verdict}"
else
  record "FAIL who-may-see: precondition: spindown-web on 127.0.0.1:$P_W never showed bench-1's published FIT (/api/state)"
fi
stop "$PID_pub_w"; stop "$PID_web_w"; stop "$PID_web_wlan"

# ---------------------------------------------------------------- room-1366x768-30
start web-r1 "$BIN/spindown-web" --lcm-url "$URL_R1" --lab "$LAB" --listen 127.0.0.1:$P_R1
start pub-r1 "$BIN/spindown-lcm-publish" --lcm-url "$URL_R1" --benches 30 --count 0 --rate 5 --duration 60 --all-types
IDS30=$(python3 -c 'import json; print(json.dumps(["bench-%d" % i for i in range(1, 31)]))')
if wait_api $P_R1 "len([x for x in s['benches'] if x.get('last_fit')]) >= 30" 20 > /dev/null; then
  browser room-1366x768-30 room 40 "{\"url\":\"http://127.0.0.1:$P_R1/\",\"w\":1366,\"h\":768,\"min_font\":14,\"ids\":$IDS30}"
else
  record "FAIL room-1366x768-30: precondition: 30 benches with a FIT never reached /api/state within 20 s"
fi
stop "$PID_pub_r1"; stop "$PID_web_r1"

# ---------------------------------------------------------------- room-grows-1280x720
start web-r2 "$BIN/spindown-web" --lcm-url "$URL_R2" --lab "$LAB" --listen 127.0.0.1:$P_R2
start pub-r2a "$BIN/spindown-lcm-publish" --lcm-url "$URL_R2" --bench bench-A --bench bench-B --bench teaching-lab-row-C-b17 --bench optics-corner-bench-22 --count 0 --rate 5 --duration 90 --all-types
FIRST='["bench-A","bench-B","teaching-lab-row-C-b17","optics-corner-bench-22"]'
MORE=$(python3 -c 'import json; print(json.dumps(["bench-%d" % i for i in range(1, 19)]))')
MORE_CMD="echo \$\$ >> '$PIDS'; exec '$BIN/spindown-lcm-publish' --lcm-url '$URL_R2' --benches 18 --count 0 --rate 5 --duration 60 --all-types > '$LOGS/pub-r2b.log' 2>&1"
if wait_api $P_R2 "len([x for x in s['benches'] if x.get('last_fit')]) >= 4" 20 > /dev/null; then
  browser room-grows-1280x720 grow 55 "{\"url\":\"http://127.0.0.1:$P_R2/\",\"w\":1280,\"h\":720,\"min_font\":14,\"min_cover\":0.30,\"first\":$FIRST,\"more\":$MORE,\"more_cmd\":$(python3 -c 'import json,sys; print(json.dumps(sys.argv[1]))' "$MORE_CMD")}"
else
  record "FAIL room-grows-1280x720: precondition: the first 4 benches never reached /api/state"
fi
stop "$PID_pub_r2a"; stop "$PID_web_r2"

# ---------------------------------------------------------------- lab-record-next-run (bench-a: run N printed while run N+1 coasts)
COND="(lambda x: x.get('run') and x['run'].get('state') == 'coasting' and x.get('last_fit') and x['last_fit'].get('end') == 'stopped' and x['last_fit'].get('run') == x['run'].get('number') - 1 and {'run': x['last_fit']['run'], 'c3': x['last_fit']['c3']['text'].split(' ')[0]})(b('bench-a'))"
if R=$(wait_api $P_A "$COND" 100); then
  RUN=$(python3 -c 'import json,sys; print(json.loads(sys.argv[1])["run"])' "$R")
  C3=$(python3 -c 'import json,sys; print(json.loads(sys.argv[1])["c3"])' "$R")
  ARGS=$(python3 - "$P_A" "$RUN" "$C3" "$LAB" "$SCR/dl" <<'EOF'
import json, sys
port, run, c3, lab, dl = sys.argv[1:6]
print(json.dumps({
    "bench_url": f"http://127.0.0.1:{port}/bench/bench-a", "port": int(port), "bench": "bench-a",
    "run": int(run), "c3_digits": c3, "lab": lab, "download_dir": dl,
    # J = 1.35e-5 kg·m² = 135 g·cm²; K_b = 0.00845 V·s/rad (= 1130 rpm/V)
    "j_re": r"1\.350?\s*(e-0?5|[×x·]\s*10)|\b135(\.0+)?\s*g\s*[·.]?\s*cm", "j_text": "1.35e-5 kg·m² (135 g·cm²)",
    "kb_re": r"0\.00845|8\.45\s*(e-0?3|[×x·]\s*10|mV)|\b113[01](\.\d+)?\s*rpm", "kb_text": "0.00845 V·s/rad (1130 rpm/V)",
}))
EOF
)
  browser lab-record-next-run record 45 "$ARGS"
else
  record "FAIL lab-record-next-run: precondition: bench-a never showed a whole run's FIT while its next run coasted (/api/state, 100 s)"
fi

# ---------------------------------------------------------------- phone-bench-page
if wait_api $P_A "b('bench-a').get('last_fit')" 30 > /dev/null; then
  browser phone-bench-page phone 40 "{\"bench_url\":\"http://127.0.0.1:$P_A/bench/bench-a\",\"room_url\":\"http://127.0.0.1:$P_A/\"}"
else
  record "FAIL phone-bench-page: precondition: bench-a has no FIT"
fi

# ---------------------------------------------------------------- ghost-bench-keyless
INJ_G="'$BIN/spindown-inject' --lcm-url '$URL_A' --bench bench-7 --fit --new-session --host laptop-17 --lab '$LAB' --listen 1"
if wait_api $P_A "b('bench-a').get('last_fit')" 20 > /dev/null; then
  browser ghost-bench-keyless ghost 45 "{\"room_url\":\"http://127.0.0.1:$P_A/\",\"bench_url\":\"http://127.0.0.1:$P_A/bench/bench-7\",\"ghost\":\"bench-7\",\"real\":[\"bench-a\",\"bench-r\",\"bench-s\"],\"inject_cmd\":$(python3 -c 'import json,sys; print(json.dumps(sys.argv[1]))' "$INJ_G")}"
else
  record "FAIL ghost-bench-keyless: precondition: lab A never showed bench-a's FIT (/api/state)"
fi

# ---------------------------------------------------------------- reset-run-not-headline (bench-r: Arduino reset mid-coast of run 2)
if wait_log "$LOGS/fit-a.log" 'bench-r run 2 (abandoned|fitted)' 60 && sleep 2 && [ -s "$SCR/a/r-run1.json" ]; then
  GOOD=$(python3 -c 'import json; f=json.load(open("'"$SCR/a/r-run1.json"'")); print(json.dumps({"good_run": f["run"], "good_c3": f["c3"]["value"]}))')
  browser reset-run-not-headline reset 40 "$(python3 -c 'import json,sys; a=json.loads(sys.argv[1]); a.update(room_url=sys.argv[2], bench_url=sys.argv[3], bench="bench-r", cut_run=2); print(json.dumps(a))' "$GOOD" "http://127.0.0.1:$P_A/" "http://127.0.0.1:$P_A/bench/bench-r")"
else
  record "FAIL reset-run-not-headline: precondition: the fitter never closed bench-r's run 2 at the reset, or run 1's whole FIT never reached /api/state"
fi

# ---------------------------------------------------------------- dim-room-dark
browser dim-room-dark dark 50 "{\"room_url\":\"http://127.0.0.1:$P_A/\",\"bench_url\":\"http://127.0.0.1:$P_A/bench/bench-a\",\"ids\":[\"bench-a\",\"bench-r\",\"bench-s\"]}"

# ---------------------------------------------------------------- keyed-refusal-on-tile (lab K)
if K=$(wait_api $P_K "(lambda f: f and f.get('end') == 'stopped' and f['c3']['value'])(b('bench-k').get('last_fit'))" 40); then
  INJ_K1="'$BIN/spindown-inject' --lcm-url '$URL_K' --bench bench-k --fit --new-session --host laptop-17 --lab '$LAB' --listen 1"
  INJ_K2="'$BIN/spindown-inject' --lcm-url '$URL_K' --bench bench-k --fit --as-fitter --key '$SCR/k/wrong.key' --lab '$LAB' --listen 2"
  browser keyed-refusal-on-tile keyed 50 "$(python3 -c 'import json,sys; print(json.dumps({"room_url": sys.argv[1], "bench_url": sys.argv[2], "bench": "bench-k", "real_c3": float(sys.argv[3]), "inject_cmds": [sys.argv[4], sys.argv[5]]}))' "http://127.0.0.1:$P_K/" "http://127.0.0.1:$P_K/bench/bench-k" "$K" "$INJ_K1" "$INJ_K2")"
else
  record "FAIL keyed-refusal-on-tile: precondition: the signed lab's bench-k never showed a whole run's FIT"
fi

# ---------------------------------------------------------------- unplug-replug-bench (bench-s)
UNPLUG="kill -9 $PID_vb_s; rm -f '$SCR/a/tty-s'"
REPLUG="'$BIN/spindown-virtual-bench' --runs 4 --speed 2 --seed 24 --link '$SCR/a/tty-s' --wait-reader 30 --linger 400 > '$LOGS/vb-s2.log' 2>&1 & echo \$! >> '$PIDS'"
browser unplug-replug-bench unplug 70 "$(python3 -c 'import json,sys; print(json.dumps({"room_url": sys.argv[1], "bench_url": sys.argv[2], "bench": "bench-s", "port": int(sys.argv[3]), "unplug_cmd": sys.argv[4], "replug_cmd": sys.argv[5]}))' "http://127.0.0.1:$P_A/" "http://127.0.0.1:$P_A/bench/bench-s" $P_A "$UNPLUG" "$REPLUG")"

# ---------------------------------------------------------------- long-coast-3min (lab L)
SPEED_L=6
start vb-l "$VB" --runs 1 --speed $SPEED_L --coulomb 1.5e-5 --viscous 5e-8 --max-coast-s 600 --seed 41 --link "$SCR/l/tty-l" --truth "$SCR/l/truth-l.json" --wait-reader 30 --linger 400
wait_link "$SCR/l/tty-l"
start fit-l "$BIN/spindown-fitter" --lcm-url "$URL_L" --lab "$LAB" --max-coast 60 -v
start web-l "$BIN/spindown-web" --lcm-url "$URL_L" --lab "$LAB" --listen 127.0.0.1:$P_L --max-run-samples 2500
start br-l "$BIN/spindown-bridge" --device "$SCR/l/tty-l" --bench bench-long --lcm-url "$URL_L" --lab "$LAB"
if wait_log "$LOGS/fit-l.log" 'bench-long run 1 coasting' 30; then
  TCUT=$(date +%s.%N)
  TSTOP=$(python3 -c 'import json; t=json.load(open("'"$SCR/l/truth-l.json"'")); r=t["runs"][0]; print(r["t_stop_s"] if r.get("stopped") else 1e9)')
  UNTIL=$(python3 -c "print($TCUT + $TSTOP / $SPEED_L - 2.0)")
  if wait_log "$LOGS/fit-l.log" 'bench-long run 1 (abandoned|fitted)' 30; then
    sleep 1
    browser long-coast-3min long 50 "{\"room_url\":\"http://127.0.0.1:$P_L/\",\"bench_url\":\"http://127.0.0.1:$P_L/bench/bench-long\",\"bench\":\"bench-long\",\"port\":$P_L,\"coast_until_epoch\":$UNTIL}"
  else
    record "FAIL long-coast-3min: precondition: the fitter never closed the long coast at --max-coast 60"
  fi
else
  record "FAIL long-coast-3min: precondition: the fitter never saw the long coast's cut"
fi
stop "$PID_vb_l"; stop "$PID_br_l"; stop "$PID_fit_l"; stop "$PID_web_l"

# ---------------------------------------------------------------- server-frozen-stale (lab A's web hangs 12 s at most)
browser server-frozen-stale stale 45 "{\"room_url\":\"http://127.0.0.1:$P_A/\",\"web_pid\":$PID_web_a,\"on_timeout\":\"kill -CONT $PID_web_a\"}"
kill -CONT "$PID_web_a" 2>/dev/null
say "done"
exit 0
