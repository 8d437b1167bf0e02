#!/bin/bash
# `spindown refit` over a rotated session (issue 31): a live lab (virtual bench -> bridge ->
# fitter and logger, LCM in a private network namespace, ttl=0) whose logger rotates every 7 s,
# so runs cross file boundaries. Judged against the bench's truth and the live FITs:
#   - `spindown refit F1 F2 … --compare`, the files given in any order, is one session in time
#     order: every run whole (its true cut) and identical to live;
#   - each file refitted alone cuts runs into fragments, and `--compare` on it says why a pair
#     differs (partial, split) instead of only listing differences.
source "$(dirname "${BASH_SOURCE[0]}")/netns_common.bash"

mkdir -p "$T/log"
"$B/spindown-logger" --lcm-url "$URL" --dir "$T/log" --prefix lab --flush-interval 0.2 --rotate-time 7 \
  >"$T/logger.out" 2>"$T/logger.err" &
LOGGER=$!; PIDS+=($LOGGER)
"$B/spindown-fitter" --lcm-url "$URL" --status-period 0.5 --no-explain -v 2>"$T/fitter.err" &
FITTER=$!; PIDS+=($FITTER)
sleep 0.3
"$B/spindown-virtual-bench" --link "$T/bench.tty" --truth "$T/truth.json" --wait-reader 20 --linger 1 --speed 2 \
  --runs 3 --idle 1 --lead-in-s 2 --tail-s 3 --coulomb 2.5e-4 --seed 5 >"$T/bench.out" 2>"$T/bench.err" &
BENCH=$!; PIDS+=($BENCH)
for _ in $(seq 100); do [ -L "$T/bench.tty" ] && break; sleep 0.1; done
"$B/spindown-bridge" --device "$T/bench.tty" --bench rot --lcm-url "$URL" --retry 2>"$T/bridge.err" &
BRIDGE=$!; PIDS+=($BRIDGE)
for _ in $(seq 900); do kill -0 "$BENCH" 2>/dev/null || break; sleep 0.1; done
kill -0 "$BENCH" 2>/dev/null && fail "the virtual bench did not finish within 90 s"
sleep 3
stop "$BRIDGE"; stop "$FITTER"; stop "$LOGGER"

mapfile -t FILES < <(ls "$T"/log/*.lcm | sort)
((${#FILES[@]} >= 4)) || fail "want >= 4 rotated files, got ${#FILES[@]}"
# Given in reverse order: the refit orders them by time.
mapfile -t SHUFFLED < <(printf '%s\n' "${FILES[@]}" | sort -r)
"$B/spindown" refit "${SHUFFLED[@]}" --compare >"$T/compare.out" 2>"$T/compare.err" ||
  { cat "$T/compare.out"; fail "refit of the session --compare found differences"; }
cat "$T/compare.out"
"$B/spindown" refit "${SHUFFLED[@]}" --json >"$T/session.json" 2>"$T/session.err" || fail "refit --json of the session"
"$B/spindown" refit "${FILES[@]}" --live --json >"$T/live.json" 2>/dev/null || fail "refit --live"
python3 - "$T/session.json" "$T/live.json" "$T/truth.json" "${#FILES[@]}" <<'PY' || fail "the session refit"
import json, sys
session = json.load(open(sys.argv[1])); live = json.load(open(sys.argv[2])); truth = json.load(open(sys.argv[3]))
nfiles = int(sys.argv[4])
cuts = [r["cut_device_us"] / 1e6 for r in truth["runs"] if "cut_device_us" in r]
assert len(session["files"]) == 1 and len(session["files"][0]["session_files"]) == nfiles, \
    "the rotated files are not one session"
runs = session["files"][0]["runs"]
lives = [r for f in live["files"] for r in f["runs"]]
assert len(runs) == len(cuts) == len(lives), (len(runs), len(cuts), len(lives))
for r, c in zip(runs, cuts):
    assert r["lead_in"] != "none" and abs(r["t_cut_s"] - c) <= 1.5 * truth["period_s"], (r["t_cut_s"], c)
print(f"PROMISE rotated: {nfiles} files of one session: refit finds {len(runs)} of {len(cuts)} runs whole, "
      f"each with its true cut, identical to the {len(lives)} live FITs")
PY
# Each file alone: fragments, each difference explained.
whole_alone=0
for f in "${FILES[@]}"; do
  # A file alone may hold only fragments (exit 1: nothing whole to fit); a crash or bad usage fails.
  rc=0; "$B/spindown" refit "$f" --json 2>/dev/null >"$T/one.json" || rc=$?
  ((rc <= 1)) || fail "refit $f --json exited $rc"
  n=$(python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print(sum(r['lead_in'] != 'none' and r['end'] == 'stopped' for f in d['files'] for r in f['runs']))" "$T/one.json")
  whole_alone=$((whole_alone + n))
  # … and its comparison differs from the live FITs (exit 1), each difference explained (below).
  rc=0; "$B/spindown" refit "$f" --compare >>"$T/alone.out" 2>/dev/null || rc=$?
  ((rc <= 1)) || fail "refit $f --compare exited $rc"
done
echo "each file alone: $whole_alone runs whole and stopped"
grep -E "differs|did not find|no live FIT" "$T/alone.out" | head -20
if grep -E "differs:" "$T/alone.out" | grep -vqE "\((partial|split|invented cut|samples):"; then
  fail "refit --compare listed a difference without saying why"
fi
grep -qE "\((partial|split)" "$T/alone.out" || fail "refit --compare of a single file explains nothing"
echo "PASS refit_rotated"
