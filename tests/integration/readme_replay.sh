#!/bin/bash
# README's replay recipe, run as README writes it (issue 42.2): a log recorded from the real chain
# (the virtual bench on a pseudo-terminal -> spindown-bridge -> spindown-logger, on the lab's
# default group and port) is replayed with the two commands of README's "Replaying a log" block,
# taken from README.md itself, with only LOG replaced by the log's path. Every run of the bench's
# truth must come out of the replay-fed fitter whole (its cut within 1.5 sample periods), and
# nothing may reach the lab's own URL. Everything in a private network namespace, ttl=0.
source "$(dirname "${BASH_SOURCE[0]}")/netns_common.bash"
SRC=${SPINDOWN_SOURCE_DIR:?}

# ---- a log of the lab, from the real bridge ------------------------------------------------
mkdir -p "$T/lab" "$T/replayed" "$T/spy"
"$B/spindown-logger" --lcm-url "$URL" --dir "$T/lab" --prefix lab --flush-interval 0.2 >"$T/logger.out" 2>"$T/logger.err" &
LOGGER=$!; PIDS+=($LOGGER)
sleep 0.3
"$B/spindown-virtual-bench" --link "$T/bench.tty" --truth "$T/truth.json" --wait-reader 20 --linger 1 \
  --speed 4 --lead-in-s 2 --tail-s 3 --coulomb 4e-4 --seed 42 --runs 3 >"$T/bench.out" 2>"$T/bench.err" &
BENCH=$!; PIDS+=($BENCH)
for _ in $(seq 100); do [ -L "$T/bench.tty" ] && break; sleep 0.1; done
"$B/spindown-bridge" --device "$T/bench.tty" --bench bench-a --lcm-url "$URL" --retry --baud 9600 2>"$T/bridge.err" &
BRIDGE=$!; PIDS+=($BRIDGE)
for _ in $(seq 900); do kill -0 "$BENCH" 2>/dev/null || break; sleep 0.1; done
kill -0 "$BENCH" 2>/dev/null && fail "the virtual bench did not finish within 90 s"
sleep 1
stop "$BRIDGE"; stop "$LOGGER"
LOG=$(ls "$T"/lab/*.lcm | head -1)

# ---- README's recipe, verbatim ---------------------------------------------------------------
# The fenced block after "Replaying a log", LOG replaced by the log's path; the programs found on
# PATH as a user's shell finds them. A logger on the replay URL records what the fitter publishes.
awk '/^Replaying a log/ {on = 1} on && /^```sh/ {inside = 1; next} inside && /^```/ {exit} inside' "$SRC/README.md" \
  >"$T/recipe.sh"
[ "$(wc -l <"$T/recipe.sh")" -eq 2 ] || fail "README's replay block is not the two commands this test runs: $(cat "$T/recipe.sh")"
grep -q ' LOG$' "$T/recipe.sh" || fail "README's replay block does not end in LOG"
REPLAY_URL=$(grep -o "udpm://[^' ]*" "$T/recipe.sh" | head -1)
[ -n "$REPLAY_URL" ] || fail "no udpm URL in README's replay block"
sed -i "s| LOG\$| '$LOG'|" "$T/recipe.sh"
"$B/spindown-logger" --lcm-url "$REPLAY_URL" --dir "$T/replayed" --prefix replayed --flush-interval 0.2 \
  >"$T/logger2.out" 2>"$T/logger2.err" &
LOGGER2=$!; PIDS+=($LOGGER2)
"$B/spindown-logger" --lcm-url "$URL" --dir "$T/spy" --prefix spy --flush-interval 0.2 >"$T/spy.out" 2>"$T/spy.err" &
SPY=$!; PIDS+=($SPY)
sleep 0.3
# The recipe starts the fitter in the background (its first line ends in &) and then plays the
# log to its end; the fitter is stopped once the last run had time to be fitted.
PATH="$B:$PATH" timeout -k 5 120 bash -c "source '$T/recipe.sh'; sleep 3; kill -TERM %1; wait %1" \
  >"$T/recipe.out" 2>"$T/recipe.err" || fail "README's replay recipe failed"
sleep 0.5
stop "$LOGGER2"; stop "$SPY"

# ---- judged against the bench's truth --------------------------------------------------------
"$B/spindown" refit "$(ls "$T"/replayed/*.lcm | head -1)" --live --json >"$T/replayed.json" 2>"$T/replayed.err" ||
  fail "no FIT recorded from the replay-fed fitter: $(cat "$T/recipe.err")"
python3 - "$T/replayed.json" "$T/truth.json" <<'EOF' || fail "the replay's FITs against the truth"
import json, sys
fits = [r for f in json.load(open(sys.argv[1]))["files"] for r in f["runs"]]
truth = json.load(open(sys.argv[2]))
cuts = [r["cut_device_us"] / 1e6 for r in truth["runs"] if "cut_device_us" in r]
period = truth["period_s"]
assert len(cuts) == 3, cuts
assert len(fits) == len(cuts), f"{len(fits)} FITs from the replay, {len(cuts)} runs in the truth"
for c in cuts:
    near = [f for f in fits if abs(f["t_cut_s"] - c) <= 1.5 * period and f["lead_in"] != "none"]
    assert near, f"no whole FIT cut within 1.5 periods of the true cut {c:.3f} s: {[f['t_cut_s'] for f in fits]}"
print(f"README's replay recipe: {len(fits)} of {len(cuts)} runs fitted whole from the replayed log")
EOF
grep -q "another lab's traffic" "$T/recipe.err" && fail "the replay-fed fitter refused the replay as another lab's"
SPYLOG=$(ls "$T"/spy/*.lcm 2>/dev/null | head -1 || true)
if [ -n "$SPYLOG" ] && "$B/spindown" refit "$SPYLOG" --json 2>/dev/null | grep -q '"t_cut_s"'; then
  fail "the replay reached the lab's own URL"
fi
echo "PASS readme_replay"
