# Shared by the bridge_*.sh integration tests (sourced; not a test itself).
# Re-runs the calling script inside a private network namespace with multicast on loopback, so
# LCM traffic never leaves this test (design §7). Every wait is bounded.
set -euo pipefail

if [[ -z "${SPINDOWN_IN_NETNS:-}" ]]; then
  if ! unshare -n true 2>/dev/null; then
    if unshare -rn true 2>/dev/null; then NETNS=(unshare -rn); else
      echo "SKIP: cannot create a network namespace (unshare -n)"; exit 0; fi
  else NETNS=(unshare -n); fi
  export SPINDOWN_IN_NETNS=1
  exec timeout 280 "${NETNS[@]}" bash "$0" "$@"
fi
ip link set lo up
ip route add 224.0.0.0/4 dev lo
export LCM_URL='udpm://239.255.76.67:7667?ttl=0'
# The tap may be starved of CPU on a busy machine: give its socket room (capped by rmem_max).
TAP_URL="$LCM_URL&recv_buf_size=4194304"

BIN=${SPINDOWN_BIN_DIR:?SPINDOWN_BIN_DIR not set}
WORK=$(mktemp -d /tmp/spindown-bridge-test.XXXXXX)
PIDS=()
cleanup() {
  for p in "${PIDS[@]}"; do kill -TERM "$p" 2>/dev/null || true; done
  sleep 0.2
  for p in "${PIDS[@]}"; do kill -KILL "$p" 2>/dev/null || true; done
  if [[ -z "${KEEP_WORK:-}" ]]; then rm -rf "$WORK"; else echo "work dir kept: $WORK"; fi
}
trap cleanup EXIT

fail() { echo "FAIL: $*" >&2; exit 1; }

# wait_for CONDITION-COMMAND SECONDS WHAT
wait_for() {
  local deadline=$((SECONDS + $2))
  until eval "$1"; do
    ((SECONDS < deadline)) || fail "timed out after $2 s waiting for $3"
    sleep 0.05
  done
}

# wait_samples PREFIX N SECONDS: waits until the tap holds N samples (no failure: the comparison
# that follows says what is missing).
wait_samples() {
  local deadline=$((SECONDS + $3))
  while (( $(wc -l < "$WORK/$1.samples.tsv") < $2 && SECONDS < deadline )); do sleep 0.05; done
}

# wait_pid PID SECONDS: waits for a child to exit, returns its exit code.
wait_pid() {
  local pid=$1 deadline=$((SECONDS + $2))
  while kill -0 "$pid" 2>/dev/null; do
    ((SECONDS < deadline)) || fail "process $pid still running after $2 s"
    sleep 0.05
  done
  local rc=0
  wait "$pid" || rc=$?
  return $rc
}

start_tap() {  # start_tap BENCH PREFIX
  "$BIN/spindown-bridge-tap" --bench "$1" --lcm-url "$TAP_URL" --samples "$WORK/$2.samples.tsv" \
    --status "$WORK/$2.status.jsonl" --config "$WORK/$2.config.jsonl" --ready "$WORK/$2.ready" \
    --timeout 250 2>"$WORK/$2.tap.log" &
  PIDS+=($!)
  TAP_PID=$!
  wait_for "[[ -e '$WORK/$2.ready' ]]" 10 "the tap to subscribe"
}

# compare_samples PREFIX: every sample the bench sent was published, in order, exactly.
compare_samples() {
  python3 - "$WORK/$1.sent.tsv" "$WORK/$1.samples.tsv" <<'PY'
import sys
sent = [l.split('\t') for l in open(sys.argv[1]).read().splitlines()[1:]]
got = [l.split('\t') for l in open(sys.argv[2]).read().splitlines()]
errors = []
if len(got) != len(sent):
    errors.append(f"published {len(got)} samples, the bench sent {len(sent)}")
for i, g in enumerate(got):
    if int(g[0]) != i:
        errors.append(f"sample {i}: seq {g[0]} (gap or reorder)"); break
for i, (s, g) in enumerate(zip(sent, got)):
    epoch, dev_us, value, adc = int(s[0]), int(s[1]), float(s[2]), int(s[3])
    if int(g[1]) != epoch or int(g[2]) != dev_us or abs(float(g[4]) - value) > 1e-9 or int(g[5]) != adc:
        errors.append(f"sample {i}: sent epoch={epoch} t={dev_us} v={value} adc={adc}, "
                      f"published epoch={g[1]} t={g[2]} v={g[4]} adc={g[5]}")
        if len(errors) > 5: break
if errors:
    print("\n".join(errors)); sys.exit(1)
print(f"all {len(sent)} samples match (values, device times, epochs, seq 0..{len(sent)-1})")
PY
}

# last_status PREFIX KEY: a counter or gauge from the last status message ("state" and
# "last_error" for those fields).
last_status() {
  python3 - "$WORK/$1.status.jsonl" "$2" <<'PY'
import json, sys
lines = [json.loads(l) for l in open(sys.argv[1]) if l.strip()]
last = lines[-1]
k = sys.argv[2]
if k in ("state", "last_error"): print(last[k])
elif k in last["counters"]: print(last["counters"][k])
else: print(last["gauges"][k])
PY
}

truth() {  # truth PREFIX PYTHON-EXPR-ON-t
  python3 -c "import json,sys; t=json.load(open('$WORK/$1.truth.json')); print($2)"
}
