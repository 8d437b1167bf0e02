#!/bin/sh
# Held-out cases of issue 41 (run finding on real-like recordings): see CASES.md.
# usage: run.sh BIN_DIR [SCRATCH_DIR]    BIN_DIR holds the built `spindown`
# Prints PASS name / FAIL name: why, then SUMMARY: N/M passed; exit 1 if any failed.
set -u
HERE=$(cd "$(dirname "$0")" && pwd)
if [ $# -lt 1 ]; then
    echo "usage: $0 BIN_DIR [SCRATCH_DIR]" >&2
    exit 2
fi
BIN=$(cd "$1" && pwd) || { echo "usage: $0 BIN_DIR [SCRATCH_DIR]: no directory $1" >&2; exit 2; }
SCRATCH=${2:-}
if [ -z "$SCRATCH" ]; then
    SCRATCH=$(mktemp -d "${TMPDIR:-/tmp}/issue41.XXXXXX")
fi
mkdir -p "$SCRATCH"
timeout -k 5 290 python3 "$HERE/issue41.py" run "$BIN" "$SCRATCH"
rc=$?
if [ $rc -eq 124 ] || [ $rc -eq 137 ]; then
    echo "FAIL timeout: the cases did not finish in 290 s"
    echo "SUMMARY: timed out"
    exit 1
fi
exit $rc
