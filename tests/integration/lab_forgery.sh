#!/usr/bin/env bash
# A student's laptop on an unsigned lab network (issue 31, case 2), in a lab of namespaces (veth
# to a bridge device, ttl=1): while bench-1's first run coasts, the laptop sends one SAMPLE on
# SPINDOWN.bench-1.SAMPLE with the bridge's own source (copied off the wire), sequence number 2^40
# and a device time years ahead; then a FIT on SPINDOWN.bench-1.FIT ("health ok"). Checks, against
# the virtual bench's truth:
#   - every run has its live fit (cut within 0.2 s of the truth), and the forged datagram changes
#     no fit: the refit of the log equals the refit of the same log without that datagram, and the
#     live fits;
#   - it is named ("forged or damaged", seq_jumps 1) and nothing is "repeated" (before issue 31:
#     every later sample of the session was, and 1 of 2 runs was fitted);
#   - spindown watch marks the forged FIT "NOT VERIFIED" (no fitter heard on STATUS has its
#     session): without a key that is all that can be said (docs/security.md).
source "$(dirname "$0")/lab_common.bash"

lab_netns_up "sdfg$$" 2 || fail "could not build the namespaces"
LAPTOP=${LAB_NS_BENCH[1]}
lab_start_services
lab_start_bench "${LAB_NS_BENCH[0]}" bench-1 1 "$URL" 2 5 || fail "bench-1 did not start"

# Mid-coast of run 1: one forged SAMPLE, then a forged FIT, from the laptop.
lab_wait "grep -q 'bench-1 run 1 coasting' '$LAB_WORK/fitter.err'" 90 || fail "run 1 never started coasting"
sleep 1
ip netns exec "$LAPTOP" "$LAB_BIN/spindown-inject" --lcm-url "$URL" --bench bench-1 --sample --listen 1 \
  >"$LAB_WORK/inject-sample.out" 2>&1 || fail "spindown-inject --sample: $(cat "$LAB_WORK/inject-sample.out")"
cat "$LAB_WORK/inject-sample.out"
grep -q 'seq 1099511627776 as host .* (session ' "$LAB_WORK/inject-sample.out" ||
  fail "the forger did not copy the bridge's source"
ip netns exec "$LAPTOP" "$LAB_BIN/spindown-inject" --lcm-url "$URL" --bench bench-1 --fit --listen 0.5 \
  >"$LAB_WORK/inject-fit.out" 2>&1 || fail "spindown-inject --fit"
cat "$LAB_WORK/inject-fit.out"

rc=0
lab_wait_exit bench-1.bench 150 || rc=$?
((rc == 0)) || fail "virtual bench bench-1 ended with code $rc"
lab_end_session "$LAB_WORK/bench-1.truth.json" -- bench-1.bridge

# 1. Every run fitted live, against the truth.
"$LAB_BIN/spindown" refit "$LOG" --live --json >"$LAB_WORK/live.json" 2>/dev/null || fail "refit --live"
python3 "$src/deploy/lab/lab_fits.py" check-runs "$LAB_WORK/live.json" "bench-1=$LAB_WORK/bench-1.truth.json" ||
  fail "a run has no live fit"

# 2. The forged datagram changes no fit: the log without it refits the same.
"${SPINDOWN_PYTHON:-python3}" - "$LOG" "$LAB_WORK/clean.lcm" <<'PY' || fail "could not write the log without the forged datagram"
import os, struct, sys
sys.path.insert(0, os.environ["SPINDOWN_PYTHON_DIR"])
import spindown_log
dropped = 0
with open(sys.argv[2], "wb") as out:
    n = 0
    for ev in spindown_log.SpindownLog(sys.argv[1]).events():
        m = spindown_log.decode(ev.channel, ev.data) if ev.channel.endswith(".SAMPLE") else None
        if m is not None and m.seq >= 2 ** 40:
            dropped += 1
            continue
        ch = ev.channel.encode()
        out.write(struct.pack(">IqqII", 0xEDA1DA01, n, ev.timestamp, len(ch), len(ev.data)) + ch + ev.data)
        n += 1
print(f"the log without the forged datagram: {dropped} event dropped")
sys.exit(0 if dropped == 1 else 1)
PY
"$LAB_BIN/spindown" refit "$LOG" --json >"$LAB_WORK/refit.json" 2>/dev/null || fail "refit"
"$LAB_BIN/spindown" refit "$LAB_WORK/clean.lcm" --json >"$LAB_WORK/refit-clean.json" 2>/dev/null || fail "refit clean"
python3 "$src/deploy/lab/lab_fits.py" compare "$LAB_WORK/refit.json" "$LAB_WORK/refit-clean.json" \
  "bench-1=$LAB_WORK/bench-1.truth.json" || fail "the forged datagram changed a fit"
"$LAB_BIN/spindown" refit "$LOG" --compare >"$LAB_WORK/compare.out" 2>/dev/null ||
  { cat "$LAB_WORK/compare.out"; fail "refit --compare: the live fits differ from the refit"; }
tail -1 "$LAB_WORK/compare.out"

# 3. Named, counted; nothing "repeated".
grep -q 'stopped: .* 0 duplicates' "$LAB_WORK/fitter.err" || fail "samples were taken as repeated"
grep -q 'sources: 0 new sources, 0 two sources at once (0 samples refused), 1 far jumps dropped (1 samples)' \
  "$LAB_WORK/fitter.err" || fail "the fitter did not count one dropped far jump"
grep -q 'SPINDOWN.bench-1.SAMPLE: 1 sample(s) from seq 1099511627776 .* forged or damaged; not used' \
  "$LAB_WORK/fitter.err" || fail "the fitter did not name the forged datagram"

# 4. The forged FIT is marked in watch (run 99, health ok: not from a fitter).
grep -q 'bench-1: run 99 fit: best combined.*\[NOT VERIFIED: from host .* no fitter heard on STATUS: forged?\]' \
  "$LAB_WORK/watch.out" || fail "watch showed the forged FIT without marking it"
echo "watch: $(grep 'run 99 fit' "$LAB_WORK/watch.out" | head -1 | cut -c1-160)"
echo "PASS lab_forgery: $EXPECTED of $EXPECTED runs fitted, the forged datagram dropped and named, no fit changed; the forged FIT marked"
