#!/usr/bin/env bash
# spindown-web in a real browser, with the live lab: in a private network namespace, three
# virtual benches -> bridges -> spindown-fitter -> spindown-logger, and spindown-web; Debian's
# Chromium (headless) driven by puppeteer-core (tests/integration/web_browser.js) opens the
# room page and a bench page while the benches run. Checked:
#   - the room page lists every bench (a tile each, data-state one of the six states) and the
#     pages log no console error, exception or failed request;
#   - bench-a's page: data-points of its plot grow while it coasts; its cut and stop are marked,
#     the three models' curves, the residuals and the explain story appear; its CSV has the run's
#     samples;
#   - every FIT message in the logger's log (bench, run, c3, c4: the exact doubles) appears on
#     the room page (every bench) and on bench-a's page with data-si equal to the message's value,
#     at most 1 s after the logger received the FIT;
#   - bench-b, unplugged and plugged back in mid-session, shows "replugged"; bench-c, whose bench
#     ends early, shows silent;
#   - a phone-width viewport (390 px) scrolls no sideways and shows the plot, c3, c4 and the CSV
#     link; the print layout is one A4 page with the plot and the numbers, without the controls.
# The screenshots and the PDF are kept (SPINDOWN_WEB_ARTIFACTS, default build/web-browser/).
# Needs chromium and puppeteer-core (deploy/setup --tests installs both): a failure, not a skip.
set -euo pipefail
if [[ -z ${SPINDOWN_IN_NETNS:-} ]]; then
  export SPINDOWN_IN_NETNS=1
  exec timeout 280 unshare -n bash "$0" "$@"
fi
src=${SPINDOWN_SOURCE_DIR:-$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)}
LAB_BIN=${SPINDOWN_BIN_DIR:?SPINDOWN_BIN_DIR not set}
LAB_WORK=$(mktemp -d /tmp/spindown-web-browser.XXXXXX)
ART=${SPINDOWN_WEB_ARTIFACTS:-$LAB_BIN/../web-browser}
NODE_MODULES=${SPINDOWN_NODE_MODULES:-/opt/spindown-test-node/node_modules}
PY=${SPINDOWN_PYTHON:-/usr/bin/python3}
source "$src/tests/integration/browser_common.bash"

[[ -x $LAB_BIN/spindown-web ]] || fail "$LAB_BIN/spindown-web is missing"

ip link set lo up
ip route add 224.0.0.0/4 dev lo
URL='udpm://239.255.76.67:7667?ttl=0'
PORT=8080
rm -rf "$ART"
mkdir -p "$ART" "$LAB_WORK/log"

lab_start - logger "$LAB_BIN/spindown-logger" --lcm-url "$URL" --dir "$LAB_WORK/log" --prefix lab --flush-interval 0.2
lab_start - fitter "$LAB_BIN/spindown-fitter" --lcm-url "$URL" --status-period 0.5 -v
lab_start - web "$LAB_BIN/spindown-web" --lcm-url "$URL" --listen "127.0.0.1:$PORT" --silent-after 3
lab_wait "grep -q channels '$LAB_WORK/logger.err' && grep -q 'fitting benches' '$LAB_WORK/fitter.err' &&
          grep -q serving '$LAB_WORK/web.err'" 30 || fail "the lab services did not start"

# The browser first (its room page and bench-a's page open before any bench runs, so they see
# every run from its start), then the benches: bench-a 3 runs; bench-b 3 runs, its cable pulled
# for 1.5 s after the first; bench-c 1 run, then its bench ends (silent). At 4x real time a coast
# lasts about 7 s.
NODE_PATH="$NODE_MODULES" timeout 230 node "$src/tests/integration/web_browser.js" \
  --url "http://127.0.0.1:$PORT/" --out "$ART" --chrome "$chrome" --benches bench-a,bench-b,bench-c \
  --coaster bench-a --replugged bench-b --silent bench-c --runs bench-a=3,bench-b=3,bench-c=1 \
  --ready "$LAB_WORK/browser-ready" >"$LAB_WORK/browser.out" 2>"$LAB_WORK/browser.err" &
node_pid=$!
LAB_PID[browser]=$node_pid
LAB_ORDER+=(browser)
lab_wait "[[ -e '$LAB_WORK/browser-ready' ]] || ! kill -0 $node_pid 2>/dev/null" 90 ||
  fail "the browser did not open the pages within 90 s: $(tail -3 "$LAB_WORK/browser.err")"
speed=4
lab_start_bench - bench-a 1 "$URL" 3 "$speed" || fail "bench-a did not start"
lab_start_bench - bench-b 2 "$URL" 3 "$speed" --unplug-at 36 --unplug-for 1.5 || fail "bench-b did not start"
lab_start_bench - bench-c 3 "$URL" 1 "$speed" || fail "bench-c did not start"
rc=0
wait "$node_pid" || rc=$?
unset "LAB_PID[browser]"
cat "$LAB_WORK/browser.out"
[[ -s $LAB_WORK/browser.err ]] && { echo "--- the browser driver's stderr:"; tail -20 "$LAB_WORK/browser.err"; }

for b in bench-a bench-b bench-c; do lab_wait_exit "$b.bench" 60 >/dev/null || true; done
sleep 1
for b in bench-a bench-b bench-c; do lab_stop "$b.bridge" 5 || true; done
lab_stop web 10 || fail "spindown-web: exit code $? on SIGTERM (want 0)"
lab_stop fitter 10 || true
lab_stop logger 15 || true
((rc == 0)) || fail "the browser checks failed (artifacts in $ART)"

# Every FIT of the log on the pages: the exact numbers, at most 1 s after the logger had it.
LOG=$(lab_only_log "$LAB_WORK/log")
[[ -n $LOG ]] || fail "no log written"
PYTHONPATH=${SPINDOWN_PYTHON_DIR:-$LAB_BIN/../python} "$PY" - "$LOG" "$ART/observed.json" <<'PY' || fail "FIT messages against the pages"
import json, sys
from spindown_log import SpindownLog

def param(m, model, name):
    i = list(m.model).index(model)
    for k in range(m.nparams):
        if m.param_model[k] == i and m.param_name[k] == name:
            return m.param_value[k]
    return None

fits = []
for x in SpindownLog(sys.argv[1]).messages(kinds={"FIT"}):
    m = x.message
    fits.append(dict(bench=x.bench, run=m.run, t_ms=x.timestamp / 1000.0,
                     c3=param(m, "combined", "c3"), c4=param(m, "combined", "c4")))
observed = json.load(open(sys.argv[2]))
bad = 0
for f in fits:
    pages = ["room"] + (["bench"] if f["bench"] == "bench-a" else [])
    for page in pages:
        seen = [o for o in observed if o["page"] == page and o["bench"] == f["bench"] and o["run"] == f["run"]
                and o["c3"] is not None and float(o["c3"]) == f["c3"] and float(o["c4"]) == f["c4"]
                and (page == "room" or o["curves"] >= 3)]
        if not seen:
            print(f"FAIL {page} page never showed {f['bench']} run {f['run']} with c3 {f['c3']!r}, c4 {f['c4']!r}"); bad += 1
            continue
        delay = min(o["t_ms"] for o in seen) - f["t_ms"]
        ok = delay <= 1000
        bad += not ok
        print(f"{'ok' if ok else 'FAIL'} {page} page: {f['bench']} run {f['run']}: c3 {f['c3']!r} c4 {f['c4']!r}"
              f"{' and the three curves' if page == 'bench' else ''} {delay:.0f} ms after the FIT")
print(f"{len(fits)} FIT messages in the log")
sys.exit(1 if bad or len(fits) < 7 else 0)
PY
echo "artifacts: $ART ($(ls "$ART" | tr '\n' ' '))"
echo "PASS"
