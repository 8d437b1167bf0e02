#!/usr/bin/env bash
# Python's route: python/spindown_log (with the types lcm-gen -p generates into build/python)
# reads a real spindown-logger log of 3 benches and gives the same events as spindown-log-summary
# and the same samples as `spindown export --csv`, also on damaged copies (a truncated last event,
# a log cut inside a header, garbage between events); pip installs build/python offline into a
# venv. Runs on Debian's python3 with NumPy (python3-numpy from deploy/setup --tests) and checks
# the list form too (python/tests/test_spindown_log.py).
source "$(dirname "$0")/lab_log_common.bash"
PY=${SPINDOWN_PYTHON:-/usr/bin/python3}
PYDIR=${SPINDOWN_PYTHON_DIR:-}
[[ -x $PY ]] || fail "no python3 at $PY (deploy/setup: python3)"
"$PY" -c 'import numpy' 2>/dev/null || fail "$PY has no NumPy (deploy/setup --tests: python3-numpy)"
"$PY" -c 'import venv, ensurepip' 2>/dev/null || fail "$PY has no venv/ensurepip (deploy/setup --tests: python3-venv)"
[[ -n $PYDIR && -f $PYDIR/spindown/samples_t.py ]] ||
  fail "no generated Python types in '${PYDIR}' (cmake --build build --target spindown_python)"
# build/python holds a copy of python/spindown_log: the test runs what is built, so it must be current.
diff -r -x __pycache__ "$SRC/python/spindown_log" "$PYDIR/spindown_log" >/dev/null ||
  fail "$PYDIR/spindown_log differs from python/spindown_log: rebuild (cmake --build build --target spindown_python)"

make_lab_log "$WORK/lab"
mkdir "$WORK/py"
rc=0
env PYTHONPATH="$PYDIR" PYTHONDONTWRITEBYTECODE=1 SPINDOWN_TEST_LOG="$LAB_LOG" SPINDOWN_TEST_CSV="$LAB_CSV" \
  SPINDOWN_TEST_WORK="$WORK/py" SPINDOWN_REQUIRE_NUMPY=1 SPINDOWN_PYTHON_DIR="$PYDIR" \
  timeout 250 "$PY" -m unittest discover -s "$SRC/python/tests" -t "$SRC/python/tests" -v >"$WORK/unittest.out" 2>&1 || rc=$?
cat "$WORK/unittest.out"
(( rc == 0 )) || fail "python3 -m unittest: exit $rc"
grep -q '^OK' "$WORK/unittest.out" || fail "unittest did not say OK"
grep -qE '(skipped=|\.\.\. skipped)' "$WORK/unittest.out" && fail "a Python test skipped"
echo "PASS: spindown_log reads the log as spindown export does (NumPy and lists), damaged copies too, and pip installs offline"
