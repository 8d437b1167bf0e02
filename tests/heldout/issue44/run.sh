#!/bin/bash
# Held-out tests of issue 44 (spindown-web: the room on the projector and a page a student can trust).
#   run.sh BIN_DIR [SCRATCH_DIR]
# Sets up live labs (virtual benches -> bridges -> fitter -> spindown-web, and spindown-inject /
# spindown-lcm-publish for crafted messages) inside a private network namespace (unshare -n,
# loopback only, ttl=0), checks each case in a real Chromium (puppeteer-core) or over raw HTTP,
# prints one "PASS name: ..." / "FAIL name: why" per case and "SUMMARY: N/M passed".
# Exit 1 when any case failed. A missing prerequisite fails every case with its reason.
# The whole run is bounded (the labs' part by a 320 s timeout); one browser at a time.
set -u
HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
DOCS=$(cd "$HERE/../../../docs" 2>/dev/null && pwd)
BIN=${1:-}
SCR=${2:-}
CASES=(who-may-see room-1366x768-30 room-grows-1280x720 lab-record-next-run phone-bench-page ghost-bench-keyless
       reset-run-not-headline dim-room-dark keyed-refusal-on-tile unplug-replug-bench long-coast-3min server-frozen-stale)

fail_all() {
  local c
  for c in "${CASES[@]}"; do echo "FAIL $c: $1"; done
  echo "SUMMARY: 0/${#CASES[@]} passed"
  exit 1
}

[ -n "$BIN" ] || fail_all "usage: run.sh BIN_DIR [SCRATCH_DIR]"
BIN=$(cd "$BIN" 2>/dev/null && pwd) || fail_all "BIN_DIR $1 does not exist"
[ "$(id -u)" = 0 ] || fail_all "not root: the labs run in a private network namespace (unshare -n), which needs root"
for b in spindown spindown-web spindown-fitter spindown-bridge spindown-virtual-bench spindown-inject spindown-lcm-publish; do
  [ -x "$BIN/$b" ] || fail_all "missing program $BIN/$b"
done
for t in unshare ip python3 node timeout; do command -v "$t" > /dev/null || fail_all "missing tool: $t"; done
CHROME=${CHROME:-/usr/bin/chromium}
[ -x "$CHROME" ] || fail_all "no Chromium at $CHROME"
NM=${SPINDOWN_NODE_MODULES:-/opt/spindown-test-node/node_modules}
node -e "require('$NM/puppeteer-core')" > /dev/null 2>&1 || fail_all "puppeteer-core cannot be loaded from $NM (set SPINDOWN_NODE_MODULES)"
[ -n "$DOCS" ] && [ -f "$DOCS/security.md" ] || fail_all "the project's docs/ (for docs/security.md) not found beside tests/"
unshare -n true 2> /dev/null || fail_all "unshare -n fails here: no private network namespace"

if [ -z "$SCR" ]; then SCR=$(mktemp -d /tmp/h44.XXXXXX); fi
rm -rf "$SCR" && mkdir -p "$SCR" || fail_all "cannot make the scratch directory $SCR"
SCR=$(cd "$SCR" && pwd)
export CHROME SPINDOWN_NODE_MODULES=$NM

timeout -k 10 320 unshare -n bash "$HERE/lab.sh" "$BIN" "$SCR" "$HERE" "$DOCS" 2> "$SCR/lab.stderr"
rc=$?
# anything lab.sh started that is still alive (a timeout): end it by its id
if [ -s "$SCR/pids" ]; then
  for p in $(cat "$SCR/pids"); do
    if grep -qsa -e "$BIN" -e spindown "/proc/$p/cmdline"; then kill -CONT "$p" 2>/dev/null; kill -KILL "$p" 2>/dev/null; fi
  done
fi

pass=0
for c in "${CASES[@]}"; do
  line=$(grep -E "^(PASS|FAIL) $c:" "$SCR/results.txt" 2>/dev/null | head -1)
  if [ -z "$line" ]; then
    if [ $rc = 124 ] || [ $rc = 137 ]; then line="FAIL $c: no verdict: the run hit its 320 s bound before this case"
    else line="FAIL $c: no verdict (lab.sh exit $rc; see $SCR/logs, $SCR/timeline.txt)"; fi
  fi
  echo "$line"
  case $line in PASS*) pass=$((pass + 1)) ;; esac
done
echo "SUMMARY: $pass/${#CASES[@]} passed"
[ $pass = ${#CASES[@]} ]
