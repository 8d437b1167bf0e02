#!/usr/bin/env bash
# The bridge reads a virtual bench over a real pty and publishes over real LCM: every sample
# the bench sent arrives once, in order, with its value, device time and a gap-free seq.
# Both protocols: the lab sketch's millis<TAB>volts and spindown-v1; the config says which.
source "$(dirname "$0")/bridge_common.bash"

run_case() {  # run_case NAME BRIDGE-ARGS -- BENCH-ARGS
  local name=$1; shift
  local bridge_args=() bench_args=()
  while [[ $1 != -- ]]; do bridge_args+=("$1"); shift; done; shift
  bench_args=("$@")
  start_tap "$name" "$name"
  "$BIN/spindown-virtual-bench" --link "$WORK/$name.tty" --sent "$WORK/$name.sent.tsv" \
    --truth "$WORK/$name.truth.json" --wait-reader 20 --linger 1 "${bench_args[@]}" \
    >"$WORK/$name.bench.out" 2>"$WORK/$name.bench.log" &
  local bench=$!; PIDS+=($bench)
  wait_for "[[ -L '$WORK/$name.tty' ]]" 10 "the virtual bench's pty"
  "$BIN/spindown-bridge" --device "$WORK/$name.tty" --bench "$name" --lcm-url "$LCM_URL" "${bridge_args[@]}" \
    2>"$WORK/$name.bridge.log" &
  local bridge=$!; PIDS+=($bridge)
  wait_pid "$bench" 120 || fail "$name: virtual bench failed: $(cat "$WORK/$name.bench.log")"
  local n; n=$(truth "$name" "t['samples']")
  wait_samples "$name" "$n" 10
  sleep 1.2  # one more heartbeat
  kill -TERM "$bridge"
  wait_pid "$bridge" 5 || fail "$name: bridge exited with $? on SIGTERM (want 0)"
  compare_samples "$name" || fail "$name: published samples differ from what the bench sent"
  [[ $(last_status "$name" lines_bad) == 0 ]] || fail "$name: lines_bad should be 0"
  [[ $(last_status "$name" samples) == "$n" ]] || fail "$name: status samples != $n"
  [[ $(last_status "$name" state) == stopping ]] || fail "$name: last status is not 'stopping'"
  # The bridge's own line->publish latency over real LCM UDP multicast (reported, not asserted).
  echo "$name: line->publish latency p50 $(last_status "$name" latency_p50_us) us," \
       "p99 $(last_status "$name" latency_p99_us) us, max $(last_status "$name" latency_max_us) us"
}

run_case lab --baud 9600 -- --protocol lab --speed 25 --runs 2 --lead-in supply --seed 3
grep -q '"protocol":"lab-tsv"' "$WORK/lab.config.jsonl" || fail "lab: config does not say lab-tsv"
grep -q '"firmware":"lab sketch"' "$WORK/lab.config.jsonl" || fail "lab: config does not say lab sketch"

cat >"$WORK/bench.toml" <<'TOML'
[bench]
inertia_kg_m2 = 2.5e-5
inertia_source = "bigger flywheel"
speed_constant_rpm_per_v = 1000
[serial]
baud = 115200
TOML
run_case v1 --config "$WORK/bench.toml" -- --protocol spindown-v1 --period-ms 5 --jitter-ms 0 --speed 10 --runs 1 --e0 2.0
grep -q '"protocol":"spindown-v1"' "$WORK/v1.config.jsonl" || fail "v1: config does not say spindown-v1"
grep -q '"firmware":"spindown-coast 1.0.0"' "$WORK/v1.config.jsonl" || fail "v1: config lacks the banner's firmware"
grep -q '"inertia_kg_m2":2.5e-05' "$WORK/v1.config.jsonl" || fail "v1: J from the config file not published"
grep -q '"kb_source":"speed constant 1000 rpm/V"' "$WORK/v1.config.jsonl" || fail "v1: K_b source not published"
grep -q '"sample_period_s":0.005' "$WORK/v1.config.jsonl" || fail "v1: period from the banner not published"
echo "PASS bridge_match"
