#!/usr/bin/env bash
# Held-out cases of issue 43: bash tests/heldout/issue43/run.sh BIN_DIR [SCRATCH_DIR]
# Generates every input from physics into SCRATCH_DIR (default: mktemp -d), runs each case
# against BIN_DIR's spindown, spindown-bridge and spindown-logger, prints PASS/FAIL per case and
# SUMMARY; exit 1 if any failed. The live cases need root (unshare -n); bounded to 5 minutes.
set -u
export PYTHONDONTWRITEBYTECODE=1
here=$(cd "$(dirname "$0")" && pwd)
bin=${1:?usage: run.sh BIN_DIR [SCRATCH_DIR]}
bin=$(cd "$bin" && pwd) || { echo "FAIL setup: no directory $1"; echo "SUMMARY: 0/14 passed"; exit 1; }
scratch=${2:-$(mktemp -d /tmp/issue43.XXXXXX)}
mkdir -p "$scratch" && scratch=$(cd "$scratch" && pwd)
# a fresh tree each time (only what this script generated: the case folders and its marker)
if [ -f "$scratch/.issue43" ]; then
  for d in "$scratch"/*/; do [ -f "$d/truth.json" ] && rm -rf -- "$d"; done
fi
touch "$scratch/.issue43"
python3 "$here/gen.py" "$scratch" >/dev/null || { echo "FAIL setup: gen.py failed"; echo "SUMMARY: 0/14 passed"; exit 1; }
exec timeout -k 5 290 python3 "$here/judge.py" "$bin" "$scratch"
