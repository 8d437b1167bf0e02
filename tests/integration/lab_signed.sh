#!/usr/bin/env bash
# A signed lab (issue 31; docs/security.md), in a lab of namespaces (veth to a bridge device,
# ttl=1): one key from `spindown keygen`; the bridge and the logger get it as systemd would hand
# it over (the credential lab-key in $CREDENTIALS_DIRECTORY), the fitter and watch by --key. A
# laptop on the network sends, while bench-1's first run coasts: an unsigned SAMPLE with the
# bridge's own source and sequence 2^40, an unsigned FIT ("health ok") with the fitter's own
# source (host and session copied off the wire: nothing but the signature tells it apart), a FIT
# signed with another key, and every signed message it heard in 2 s sent again (a replay).
# Checks, against the virtual bench's truth:
#   - every run has its live fit, and the refit of the log with the key equals it;
#   - the forged FITs never appear in watch as fits (0 rows of run 99), only counted and named as
#     not shown; the fitter and the logger count the unsigned, wrongly signed and replayed ones;
#   - with the key, `refit --live` lists only the fitter's signed FITs; without it, the forged
#     ones too (so the key is what tells them apart).
source "$(dirname "$0")/lab_common.bash"

lab_netns_up "sdsg$$" 2 || fail "could not build the namespaces"
LAPTOP=${LAB_NS_BENCH[1]}
KEY=$LAB_WORK/lab.key
"$LAB_BIN/spindown" keygen -o "$KEY" >"$LAB_WORK/keygen.out" || fail "spindown keygen"
cat "$LAB_WORK/keygen.out"
[[ $(stat -c %a "$KEY") == 600 && $(stat -c %s "$KEY") == 32 ]] || fail "keygen: not a 32-byte mode-600 file"
"$LAB_BIN/spindown" keygen -o "$KEY" >/dev/null 2>"$LAB_WORK/keygen2.err" && fail "keygen overwrote a key"
head -c 32 /dev/urandom >"$LAB_WORK/other.key"
mkdir -p "$LAB_WORK/credentials"
cp "$KEY" "$LAB_WORK/credentials/lab-key"  # what LoadCredential=lab-key:/etc/spindown/lab.key gives a unit
CRED=(env CREDENTIALS_DIRECTORY="$LAB_WORK/credentials")

lab_start_services -k "$KEY" -c "$LAB_WORK/credentials"
grep -q "messages signed with key 0x.* (systemd credential lab-key)" "$LAB_WORK/logger.err" ||
  fail "the logger did not take the key from the credential"
lab_profile 1 bench-1
lab_start "${LAB_NS_BENCH[0]}" bench-1.bench "$LAB_BIN/spindown-virtual-bench" "${LAB_BENCH_ARGS[@]}" --runs 2 \
  --speed 5 --idle 1.0 --link "$LAB_WORK/bench-1.tty" --truth "$LAB_WORK/bench-1.truth.json" --wait-reader 30 --linger 1
lab_wait "[[ -L '$LAB_WORK/bench-1.tty' ]]" 15 || fail "bench-1 made no pty"
lab_start "${LAB_NS_BENCH[0]}" bench-1.bridge "${CRED[@]}" "$LAB_BIN/spindown-bridge" --device "$LAB_WORK/bench-1.tty" \
  --bench bench-1 --lcm-url "$URL" --config "$LAB_WORK/bench-1.toml"

lab_wait "grep -q 'bench-1 run 1 coasting' '$LAB_WORK/fitter.err'" 90 || fail "run 1 never started coasting"
inject() { ip netns exec "$LAPTOP" "$LAB_BIN/spindown-inject" --lcm-url "$URL" --bench bench-1 "$@"; }
inject --sample --listen 0.5 >"$LAB_WORK/inject.out" 2>&1 || fail "inject --sample"
inject --fit --as-fitter --listen 1.5 >>"$LAB_WORK/inject.out" 2>&1 || fail "inject --fit"
inject --fit --listen 0.5 --new-session --key "$LAB_WORK/other.key" >>"$LAB_WORK/inject.out" 2>&1 || fail "inject --fit --key"
inject --replay --listen 2 >>"$LAB_WORK/inject.out" 2>&1 || fail "inject --replay"
cat "$LAB_WORK/inject.out"
replayed=$(sed -n 's/^sent \([0-9]*\) messages again.*/\1/p' "$LAB_WORK/inject.out")
((${replayed:-0} > 20)) || fail "the replay sent too little ($replayed messages)"

rc=0
lab_wait_exit bench-1.bench 150 || rc=$?
((rc == 0)) || fail "virtual bench bench-1 ended with code $rc"
lab_end_session "$LAB_WORK/bench-1.truth.json" -- bench-1.bridge

# 1. Every run fitted live (signed FITs only, with the key), and the refit with the key equals it.
"$LAB_BIN/spindown" refit "$LOG" --live --json --key "$KEY" >"$LAB_WORK/live.json" 2>/dev/null || fail "refit --live --key"
python3 "$src/deploy/lab/lab_fits.py" check-runs "$LAB_WORK/live.json" "bench-1=$LAB_WORK/bench-1.truth.json" ||
  fail "a run has no live fit (or a forged FIT passed the key)"
"$LAB_BIN/spindown" refit "$LOG" --compare --key "$KEY" >"$LAB_WORK/compare.out" 2>/dev/null ||
  { cat "$LAB_WORK/compare.out"; fail "refit --compare --key found differences"; }
grep -q "$EXPECTED runs refitted, $EXPECTED live FIT messages: $EXPECTED identical, 0 different" "$LAB_WORK/compare.out" ||
  { cat "$LAB_WORK/compare.out"; fail "refit --compare --key counts"; }
# Without the key the FIT forged with the fitter's own source is among the "live" ones: only the
# signature tells it apart.
"$LAB_BIN/spindown" refit "$LOG" --live --json >"$LAB_WORK/live-nokey.json" 2>/dev/null || fail "refit --live"
python3 - "$LAB_WORK/live.json" "$LAB_WORK/live-nokey.json" <<'PY' || fail "refit --live: the key did not exclude the forged FIT"
import json, sys
runs = [[r["run"] for f in json.load(open(p))["files"] for r in f["runs"]] for p in sys.argv[1:]]
print(f"refit --live: runs {runs[0]} with the key, {runs[1]} without")
sys.exit(0 if 99 not in runs[0] and 99 in runs[1] else 1)
PY

# 2. watch: never a row or event of the forged run 99; the refused messages counted as not shown.
! grep -q 'run 99' "$LAB_WORK/watch.out" || fail "watch showed a forged FIT"
grep -q 'not shown: SPINDOWN.bench-1.FIT: fit_t from host .*: not signed, and this lab signs its messages' \
  "$LAB_WORK/watch.out" || fail "watch did not name the unsigned FIT"
grep -q 'not shown: SPINDOWN.bench-1.FIT: fit_t from host .*: signed with key 0x' "$LAB_WORK/watch.out" ||
  fail "watch did not name the FIT signed with another key"
watch_last_table | grep -Eq 'messages not shown \(.*not signed.*\)' || fail "watch's table does not count what it did not show"

# 3. The fitter and the logger counted the unsigned and replayed messages (the logger kept them all).
grep -Eq 'not used: 0 of another lab, [1-9][0-9]* unsigned, [0-9]+ badly signed, [1-9][0-9]* replayed' \
  "$LAB_WORK/fitter.err" || fail "the fitter did not count the unsigned and replayed samples"
grep -q 'SPINDOWN.bench-1.SAMPLE: samples_t from host .*: not signed, and this lab signs its messages' \
  "$LAB_WORK/fitter.err" || fail "the fitter did not name the unsigned SAMPLE"
grep -q 'stopped: .* 0 duplicates' "$LAB_WORK/fitter.err" || fail "samples were taken as repeated"
"${SPINDOWN_PYTHON:-python3}" - "$LOG" <<'PY' || fail "the logger did not count them"
import os, sys
sys.path.insert(0, os.environ["SPINDOWN_PYTHON_DIR"])
import spindown_log
most = {}
for m in spindown_log.SpindownLog(sys.argv[1]).messages(kinds={"STATUS"}):
    if m.message.service != "logger":
        continue
    for name, value in zip(m.message.counter_name, m.message.counter_value):
        most[name] = max(most.get(name, 0), value)
c = {k: most.get(k, 0) for k in ("unsigned_messages", "bad_signatures", "replays", "other_lab")}
print("logger heartbeat:", c)
sys.exit(0 if c["unsigned_messages"] >= 2 and c["bad_signatures"] >= 1 and c["replays"] >= 20 else 1)
PY
echo "PASS lab_signed: $EXPECTED of $EXPECTED runs fitted; forged FITs never shown; unsigned, wrongly signed, replayed counted"
