#!/usr/bin/env bash
# `spindown fit` on garbage: each file gives a clear message on stderr naming the file and a
# defined exit code, never a crash (also run under ASan/UBSan by deploy/run-tests --sanitize).
# Several files where one is bad: the others are still reported, exit 1.
set -euo pipefail
bin="${SPINDOWN_BIN_DIR:?}/spindown"
data="${SPINDOWN_SHARED_DATA:?}"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cd "$tmp"

# A clean coast (lab-like combined friction, 20 ms loop), printed as the sketch does.
python3 - <<'PY'
import math
def coast(gain=1.0):
    rows = []
    for i in range(1500):
        t = 5000 + 20 * i
        tau = (i - 150) * 0.02
        w = 0.0 if i < 150 else max(0.0, (346 + 1011) * math.exp(-0.0162 * tau) - 1011)
        rows.append((t, gain * w / 123.569311))
    return rows
def write(name, rows):
    with open(name, "w") as f:
        for t, v in rows:
            f.write(f"{t}\t{v}\r\n" if isinstance(v, str) else f"{t}\t{v:.2f}\r\n")
rows = coast()
write("nan_inf.tsv", [(t, {300: "nan", 400: "NaN", 500: "inf", 600: "-inf"}.get(k, f"{v:.2f}"))
                      for k, (t, v) in enumerate(rows)])
write("backwards.tsv", [(t - 300 if 700 <= k < 710 else t, v) for k, (t, v) in enumerate(rows)])
# Back-EMF above the converter's 5 V: the reading sits at 5.00 V until the motor slows.
write("clipped.tsv", [(t, min(v, 5.0)) for t, v in coast(gain=2.2)])
write("zeros.tsv", [(t, 0.0) for t, _ in rows])
write("three.tsv", [(1000, 2.5), (1020, 2.4), (1040, 2.3)])
write("good.tsv", rows)
PY
: >empty.tsv
head -c 4096 /dev/urandom >binary.bin

fail=0
# run_case FILE EXPECTED_EXIT STDERR_REGEX
run_case() {
  local file=$1 want=$2 pattern=$3 rc=0
  timeout 60 "$bin" fit "$file" >out.txt 2>err.txt || rc=$?
  if ((rc >= 128 || rc == 124)); then
    echo "FAIL $file: crashed or hung (exit $rc)"; cat err.txt; fail=1; return
  fi
  if ((rc != want)); then echo "FAIL $file: exit $rc, want $want"; cat err.txt; fail=1; fi
  if ! grep -qF -- "$file" err.txt; then echo "FAIL $file: stderr does not name the file"; cat err.txt; fail=1; fi
  if ! grep -qiE -- "$pattern" err.txt; then echo "FAIL $file: stderr lacks /$pattern/"; cat err.txt; fail=1; fi
  if grep -qE "AddressSanitizer|runtime error|LeakSanitizer" err.txt; then echo "FAIL $file: sanitizer report"; fail=1; fi
  # JSON mode: the same exit code and still one valid JSON object on stdout.
  rc=0
  timeout 60 "$bin" fit --json "$file" >out.json 2>/dev/null || rc=$?
  if ((rc != want)) || ! python3 -c 'import json,sys; json.load(open(sys.argv[1]))["files"][0]["runs"]' out.json; then
    echo "FAIL $file: --json exit $rc or invalid JSON"; fail=1
  fi
  echo "ok $file (exit $want): $(head -n 1 err.txt)"
}

run_case empty.tsv 1 "empty"
run_case binary.bin 1 "binary"
run_case zeros.tsv 1 "no spin-down"
run_case three.tsv 1 "no spin-down"
run_case nan_inf.tsv 0 "NaN or infinite"
run_case backwards.tsv 0 "time goes back"
run_case clipped.tsv 0 "pinned|clip|saturat"
run_case missing-file.tsv 1 "No such file"

# Several files, one bad: the good ones are still reported, the exit code says one was not used.
rc=0
timeout 60 "$bin" fit good.tsv empty.tsv "$data/seed-3v-run1.tsv" >out.txt 2>err.txt || rc=$?
if ((rc != 1)); then echo "FAIL mixed files: exit $rc, want 1"; fail=1; fi
if (($(grep -c "best: " out.txt) != 2)); then echo "FAIL mixed files: want two fitted files"; cat out.txt; fail=1; fi
grep -qF "empty.tsv: error: not used" err.txt || { echo "FAIL mixed files: no reason for empty.tsv"; fail=1; }
rc=0
timeout 60 "$bin" fit --json good.tsv empty.tsv "$data/seed-3v-run1.tsv" >out.json 2>/dev/null || rc=$?
if ((rc != 1)) || ! python3 - out.json <<'PY'
import json, sys
files = json.load(open(sys.argv[1]))["files"]
assert [len(f["runs"]) for f in files] == [1, 0, 1], [len(f["runs"]) for f in files]
assert files[1]["failures"] and not files[0]["failures"]
PY
then echo "FAIL mixed files --json: exit $rc"; fail=1; fi
echo "ok mixed files (exit 1)"
exit $fail
