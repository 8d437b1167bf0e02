#!/bin/bash
# run.sh BIN_DIR [SCRATCH_DIR]: the issue-42 held-out cases against the built programs in BIN_DIR.
# One line per case, "PASS name" or "FAIL name: why", then "SUMMARY: N/M passed"; exit 1 if any failed.
# Each case runs under timeout -k 5 120; the whole run stops starting cases past 14 minutes.
# Needs root (network namespaces), iproute2, python3, lcm-logplayer, libfaketime (Debian's
# "faketime", from deploy/setup --tests). CASES="a b" runs only those cases.
set -u
export PYTHONDONTWRITEBYTECODE=1     # the judge imports build/python: write nothing there
HERE=$(cd "$(dirname "$0")" && pwd)
BIN=$(cd "${1:?usage: run.sh BIN_DIR [SCRATCH_DIR]}" && pwd) || exit 2
SCRATCH=${2:-$(mktemp -d /tmp/issue42-heldout.XXXXXX)}
mkdir -p "$SCRATCH"; SCRATCH=$(cd "$SCRATCH" && pwd)
ALL="dup-reorder late-block burst-loss lab-clock-forward bench-clock-forward-signed fitter-joins-late logger-restart replay-fast concat-days cable-swap bridge-stall"
CASES=${CASES:-$ALL}
START=$(date +%s)
BUDGET=840            # seconds after which no case is started (each may take up to 125 s more)

pre=""
[ "$(id -u)" = 0 ] || pre="needs root (network namespaces)"
for t in ip python3 lcm-logplayer timeout; do command -v $t > /dev/null || pre="${pre:+$pre; }missing $t"; done
for p in spindown spindown-fitter spindown-logger spindown-bridge spindown-virtual-bench; do
    [ -x "$BIN/$p" ] || pre="${pre:+$pre; }missing $BIN/$p"
done
[ -d "$BIN/../python/spindown_log" ] || pre="${pre:+$pre; }missing the Python log reader $BIN/../python (docs/using-the-data.md)"
# libfaketime comes with deploy/setup --tests (Debian's faketime); never installed while testing.
ls /usr/lib/*/faketime/libfaketime.so.1 > /dev/null 2>&1 ||
    pre="${pre:+$pre; }missing libfaketime (deploy/setup --tests installs Debian's faketime)"

# a safety net: namespaces (and their processes) a case left behind
sweep() {
    local n p
    for n in $(ip netns list 2>/dev/null | awk '{print $1}' | grep '^i42-'); do
        grep -qx "$n" "$SCRATCH/.netns-before" 2>/dev/null && continue
        for p in $(ip netns pids "$n" 2>/dev/null); do kill -KILL "$p" 2>/dev/null; done
        ip netns del "$n" 2>/dev/null
    done
}
ip netns list 2>/dev/null | awk '{print $1}' > "$SCRATCH/.netns-before"
trap sweep EXIT

pass=0; total=0; failed=0
for c in $CASES; do
    total=$((total + 1))
    if [ -n "$pre" ]; then echo "FAIL $c: harness: $pre"; failed=1; continue; fi
    if [ $(( $(date +%s) - START )) -gt $BUDGET ]; then
        echo "FAIL $c: harness: not started, the run's 15-minute budget is spent"; failed=1; continue
    fi
    d="$SCRATCH/$c"; rm -rf "$d"; mkdir -p "$d"
    t0=$(date +%s)
    timeout -k 5 120 bash "$HERE/case.sh" "$c" "$BIN" "$d" > "$d/case.out" 2> "$d/case.err"
    rc=$?
    sweep
    v=$(head -c 2000 "$d/verdict" 2>/dev/null)
    [ $rc = 124 ] || [ $rc = 137 ] && v="HARNESS: the case did not finish within 120 s (last: $(tail -1 "$d/harness.log" 2>/dev/null))"
    dt=$(( $(date +%s) - t0 ))
    case $v in
        PASS) echo "PASS $c"; pass=$((pass + 1)) ;;
        FAIL:*) echo "FAIL $c: ${v#FAIL: } [${dt}s, $d]"; failed=1 ;;
        *) echo "FAIL $c: harness: ${v#HARNESS: } [${dt}s, $d]"; failed=1 ;;
    esac
done
echo "SUMMARY: $pass/$total passed"
[ $failed = 0 ]
