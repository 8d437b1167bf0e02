#!/bin/bash
# issue 34 held-out cases: the lab in a browser (spindown-web), judged in Debian's Chromium.
# run.sh BIN [SCRATCH]     BIN: the built programs (build/bin); SCRATCH: artifacts (default mktemp -d)
# Needs root (a private network namespace: unshare -n), /usr/bin/chromium, node, and puppeteer-core
# in $SPINDOWN_NODE_MODULES (default /opt/spindown-test-node/node_modules; deploy/setup --tests).
# Prints PASS/FAIL per case and SUMMARY; exit 1 if any case failed, else 0. About 2 minutes.
set -u
HERE=$(cd "$(dirname "$0")" && pwd)
BIN=$(cd "${1:?usage: run.sh BIN [SCRATCH]}" 2>/dev/null && pwd || echo "$1")
S=${2:-$(mktemp -d /tmp/issue34.XXXXXX)}
mkdir -p "$S" && S=$(cd "$S" && pwd)
NM=${SPINDOWN_NODE_MODULES:-/opt/spindown-test-node/node_modules}
export SPINDOWN_NODE_MODULES=$NM
echo "issue34: scratch (artifacts: screenshots, PDF, CSV, obs.json, log) in $S" >&2

allfail() { python3 "$HERE/judge.py" --all-fail "$1"; exit 1; }

[ "$(id -u)" = 0 ] || allfail "needs root: the lab runs in a private network namespace (unshare -n)"
[ -x "$BIN/spindown-web" ] || allfail "spindown-web not found in $BIN"
for p in spindown spindown-bridge spindown-fitter spindown-logger spindown-virtual-bench; do
    [ -x "$BIN/$p" ] || allfail "$p not found in $BIN"
done
[ -x /usr/bin/chromium ] || allfail "/usr/bin/chromium not installed (deploy/setup --tests)"
command -v node >/dev/null || allfail "node not installed (deploy/setup --tests)"
[ -d "$NM/puppeteer-core" ] || allfail "puppeteer-core not in $NM (deploy/setup --tests installs it; SPINDOWN_NODE_MODULES)"
command -v unshare >/dev/null && command -v ip >/dev/null || allfail "unshare/ip missing (util-linux, iproute2)"

killall_ours() {
    [ -f "$S/pids" ] || return 0
    while read -r p; do
        case $p in
            pgid:*) kill -KILL -- "-${p#pgid:}" 2>/dev/null ;;
            logger:*) kill -KILL "${p#logger:}" 2>/dev/null ;;
            *) kill -KILL "$p" 2>/dev/null ;;
        esac
    done < "$S/pids"
}
LABPID=
on_exit() { [ -n "$LABPID" ] && kill -TERM "$LABPID" 2>/dev/null; sleep 0.2; killall_ours; }
trap on_exit EXIT
trap 'exit 1' INT TERM

start=$(date +%s)
timeout -k 10 260 unshare -n bash "$HERE/lab.sh" "$BIN" "$S" "$HERE" > "$S/lab.out" 2> "$S/lab.err" &
LABPID=$!
wait $LABPID
rc=$?
LABPID=
[ $rc = 124 ] || [ $rc = 137 ] && echo "lab_error=the lab exceeded its 260 s budget" >> "$S/lab-status"
killall_ours
python3 "$HERE/judge.py" "$S" "$BIN"
jrc=$?
echo "issue34: $(( $(date +%s) - start )) s; artifacts in $S" >&2
exit $jrc
