#!/bin/bash
# Held-out cases for issue 30.  usage: run.sh BIN_DIR [SCRATCH_DIR]
# Needs root for the live part (unshare -n: a private network namespace for LCM, ttl=0).
set -u
BIN=${1:?usage: run.sh BIN_DIR [SCRATCH_DIR]}
SCR=${2:-$(mktemp -d /tmp/issue30.XXXXXX)}
HERE=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$SCR"
# the whole runner is bounded: 290 s, then everything it started is ended
timeout -k 5 290 /usr/bin/python3 "$HERE/cases.py" "$BIN" "$SCR"
rc=$?
if [ $rc -eq 0 ]; then exit 0; fi
if [ $rc -eq 124 ] || [ $rc -eq 137 ]; then echo "FAIL runner-timeout: the runner passed its 290 s bound"; echo "SUMMARY: 0/1 passed"; fi
exit 1
