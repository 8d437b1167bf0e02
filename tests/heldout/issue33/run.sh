#!/usr/bin/env bash
# Issue 33 held-out cases. Usage: run.sh BIN_DIR [SCRATCH_DIR]
#   BIN_DIR: the built programs (e.g. /work/main/build/bin); the Python log reader is taken
#            from BIN_DIR/../python (build/python, built with the programs).
# Needs: /usr/bin/python3 (standard library), unshare and ip (util-linux, iproute2), root (or
# unprivileged user namespaces) for the private network namespace of the live lab.
# Prints PASS/FAIL per case and SUMMARY; exit 1 if any case failed, else 0. Under 5 minutes.
set -u
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
bin=${1:?usage: run.sh BIN_DIR [SCRATCH_DIR]}
scratch=${2:-$(mktemp -d /tmp/issue33.XXXXXX)}
mkdir -p "$scratch"
for p in spindown spindown-fitter spindown-logger spindown-bridge; do
  if [[ ! -x $bin/$p ]]; then
    echo "FAIL setup: $bin/$p is missing"; echo "SUMMARY: 0/1 passed"; exit 1
  fi
done
timeout -k 10 280 /usr/bin/python3 "$here/cases.py" "$bin" "$scratch"
rc=$?
if ((rc != 0 && rc != 1)); then
  echo "FAIL runner: cases.py ended with code $rc (timeout or crash); scratch $scratch"
  echo "SUMMARY: 0/1 passed"
  exit 1
fi
exit $rc
