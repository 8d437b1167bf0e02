#!/bin/bash
# Issue 32 held-out cases: other rigs' short fast coasts, powered steps, start-up transients,
# slow quantized tails, doubts that mean something, files as other rigs write them.
# usage: run.sh BIN_DIR [SCRATCH_DIR]     (BIN_DIR holds the built `spindown`)
# Prints PASS/FAIL per case and SUMMARY; exits 1 if any case failed, 0 otherwise.
# Needs only /usr/bin/python3 (standard library) and coreutils' timeout; no root, no network.
set -u
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
bin="${1:?usage: run.sh BIN_DIR [SCRATCH_DIR]}"
bin="$(cd "$bin" && pwd)" || { echo "FAIL setup: no directory $1"; echo "SUMMARY: 0/1 passed"; exit 1; }
scratch="${2:-$(mktemp -d)}"
mkdir -p "$scratch"
if [ ! -x "$bin/spindown" ]; then
  echo "FAIL setup: $bin/spindown is not an executable"
  echo "SUMMARY: 0/1 passed"
  exit 1
fi
# the whole runner is bounded: 290 s, then killed
timeout -k 5 290 /usr/bin/python3 -B "$here/cases.py" "$bin" "$scratch"
rc=$?
if [ $rc -eq 0 ]; then exit 0; fi
if [ $rc -eq 124 ] || [ $rc -eq 137 ]; then
  echo "FAIL runner: killed after 290 s"
  echo "SUMMARY: runner timed out"
fi
exit 1
