#!/usr/bin/env bash
# Held-out cases for issue 43 (part b). usage: bash tests/heldout/issue43b/run.sh BIN_DIR [SCRATCH_DIR]
# Prints PASS/FAIL per case and "SUMMARY: N/M passed"; exit 1 if any failed. At most ~5 minutes.
# The live cases' LCM traffic stays inside a private network namespace (unshare -n, ttl=0).
set -u
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
if [ $# -lt 1 ]; then echo "usage: bash $0 BIN_DIR [SCRATCH_DIR]" >&2; exit 2; fi
BIN="$(cd "$1" && pwd)" || { echo "no such BIN_DIR: $1" >&2; exit 2; }
SCRATCH="${2:-$(mktemp -d /tmp/issue43b.XXXXXX)}"
mkdir -p "$SCRATCH"
SCRATCH="$(cd "$SCRATCH" && pwd)"
PY="${PYTHON:-python3}"

timeout 60 "$PY" "$HERE/gen.py" "$SCRATCH" >&2 || { echo "FAIL gen: gen.py failed"; echo "SUMMARY: 0/1 passed"; exit 1; }

# a private network namespace: loopback only, multicast routed to lo
if unshare -n true 2>/dev/null; then
  timeout --kill-after=5 285 unshare -n bash -c '
    ip link set lo up && ip route add 224.0.0.0/4 dev lo || exit 97
    exec "$0" "$1/judge.py" "$2" "$3"' "$PY" "$HERE" "$BIN" "$SCRATCH"
  rc=$?
  if [ $rc -eq 97 ]; then
    "$PY" "$HERE/judge.py" "$BIN" "$SCRATCH" --no-live "could not set up the private network namespace's loopback route"
    rc=$?
  elif [ $rc -eq 124 ] || [ $rc -eq 137 ]; then
    echo "FAIL run.sh: the judge did not finish within its time limit"
    echo "SUMMARY: 0/1 passed"
    rc=1
  fi
else
  "$PY" "$HERE/judge.py" "$BIN" "$SCRATCH" --no-live "no private network namespace (unshare -n failed): live cases not run"
  rc=$?
fi
echo "scratch: $SCRATCH (judge.log: proposals seen and followed)" >&2
exit $rc
