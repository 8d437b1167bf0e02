#!/bin/bash
# The live fitter, its log, the refit and a replay agree:
#  1. spindown-fitter + a logger on a private LCM URL; spindown-run-publisher publishes
#     generated runs for 3 benches (one without CONFIG) and waits for every FIT;
#  2. `spindown refit LOG --compare`: the refit equals every recorded FIT (timing fields aside); the
#     live fitter's health verdicts (bench000 has a bench file) are said as verdicts only it gave,
#     not as differences, and reproduced with --bench-config; a bench file's [bench] J wins over
#     the CONFIG in a refit and is said, while --compare still compares like with like;
#     `spindown refit --json` and `spindown fit --json` of the same log give the same runs;
#  3. lcm-logplayer replays the log's SAMPLE/CONFIG on a *different* URL (other group and port)
#     into a fresh fitter: its FITs equal the refit again, and nothing reached the first URL.
# Everything runs in a private network namespace (unshare -n); ttl=0.
source "$(dirname "${BASH_SOURCE[0]}")/netns_common.bash"
REPLAY_URL='udpm://239.255.76.68:7668?ttl=0'

start_logger() {  # URL DIR NAME; sets STARTED
  mkdir -p "$2"
  # Not lcm-logger 1.3.1: its queue of 30 drops messages silently in a burst (design §7), and
  # then the refit rightly differs from the live fits.
  "$B/spindown-logger" --lcm-url "$1" --dir "$2" --prefix "$3" --flush-interval 0.2 >"$T/$3-logger.out" 2>"$T/$3-logger.err" &
  STARTED=$!
  PIDS+=($STARTED)
}
only_log() { ls "$1"/*.lcm | head -1; }

# ---- 1. live --------------------------------------------------------------------------------
# bench000 has a bench file with a baseline: its live FITs carry a health verdict.
mkdir -p "$T/benches" "$T/named"
cat >"$T/benches/bench000.toml" <<'TOML'
bench_id = "bench000"
[baseline]
c_viscous_n_m_s = 1.8e-07
c_viscous_stderr = 2.0e-09
c_coulomb_n_m = 1.14e-04
c_coulomb_stderr = 4.0e-07
runs = 3
date = "2024-09-14"
TOML
start_logger "$URL" "$T/live" live; LOGGER=$STARTED
"$B/spindown-fitter" --lcm-url "$URL" --status-period 0.2 --bench-config "$T/benches" -v 2>"$T/fitter.err" &
FITTER=$!; PIDS+=($FITTER)
sleep 0.5
"$B/spindown-run-publisher" --lcm-url "$URL" --benches 3 --runs 2 --speed 20 --config-benches 2 \
  --wait-fits 20 --report "$T/report.json" >"$T/publisher.out" 2>"$T/publisher.err"
sleep 1  # heartbeats after the last FIT: the logger has written every FIT
stop "$FITTER"; stop "$LOGGER"
LOG=$(only_log "$T/live")
python3 - "$T/report.json" <<'EOF' || fail "live fits"
import json, sys
r = json.load(open(sys.argv[1]))
assert r["expected_fits"] == 6 and r["fits"] == 6 and r["matched"] == 6, r
src = {f["bench"]: f["bench_source"] for f in r["fit_list"]}
assert src["bench000"] == "config" and src["bench001"] == "config", src
assert src["bench002"].startswith("default") and "no CONFIG" in src["bench002"], src
print("live: 6 fits; after the true stop p50 %.3f s (host, speed 20); latency p50 %.1f ms"
      % (r["after_true_stop_s"]["p50"], 1e3 * r["latency_s"]["p50"]))
EOF

# The discrepancy workflow ran on every fitted run: one EXPLAIN per FIT, each with a story.
"$B/spindown-log-summary" "$LOG" >"$T/summary.json" || fail "spindown-log-summary"
python3 - "$T/summary.json" <<'EOF' || fail "EXPLAIN messages"
import json, sys
ch = json.load(open(sys.argv[1]))["files"][0]["channels"]
fits = sum(n for c, n in ch.items() if c.endswith(".FIT"))
explains = sum(n for c, n in ch.items() if c.endswith(".EXPLAIN"))
assert fits == 6 and explains == 6, ch
print("live: 6 FIT and 6 EXPLAIN messages in the log")
EOF
grep -q "explained: viscous -> " "$T/fitter.err" || { cat "$T/fitter.err"; fail "fitter did not explain from the viscous base"; }

# ---- 2. refit == live, refit == fit -----------------------------------------------------------
"$B/spindown" refit "$LOG" --compare >"$T/compare.out" 2>"$T/compare.err" || { cat "$T/compare.out"; fail "refit --compare"; }
grep -q "6 runs refitted, 6 live FIT messages: 6 identical, 0 different" "$T/compare.out" || { cat "$T/compare.out"; fail "compare counts"; }
# The live fitter had a bench file for bench000, this refit none: its verdicts are said as that, the
# numbers are identical (issue 30: not "different").
grep -q "0 only live; 2 with a health verdict live only (the live fitter had a bench file, this refit none)" "$T/compare.out" ||
  { cat "$T/compare.out"; fail "compare: the verdicts only the live fitter gave"; }
[ "$(grep -c "bench000 run [12] .*: identical numbers; health OK live, none here: the live fitter had a bench file for bench bench000" "$T/compare.out")" -eq 2 ] ||
  { cat "$T/compare.out"; fail "compare: each verdict-only run named"; }
# With the bench file the refit gives the same verdicts.
"$B/spindown" refit "$LOG" --compare --bench-config "$T/benches" >"$T/compare-h.out" 2>"$T/compare-h.err" ||
  { cat "$T/compare-h.out"; fail "refit --compare --bench-config"; }
grep -q "6 identical, 0 different, 0 only refitted, 0 only live$" "$T/compare-h.out" || { cat "$T/compare-h.out"; fail "compare with the bench file"; }
# A bench file whose [bench] names another J wins over the CONFIG in a refit, and says so; --compare
# still compares like with like (the live fitter's J), and says that.
cat "$T/benches/bench000.toml" >"$T/named/bench000.toml"
printf '[bench]\ninertia_kg_m2 = 2.2537520e-5\n' >>"$T/named/bench000.toml"
"$B/spindown" refit "$LOG" --json --bench-config "$T/named" >"$T/named.json" 2>"$T/named.err" || fail "refit --bench-config with [bench]"
"$B/spindown" refit "$LOG" --compare --bench-config "$T/named" >"$T/compare-n.out" 2>"$T/compare-n.err" || { cat "$T/compare-n.out"; fail "compare with a named J"; }
grep -q "6 identical, 0 different" "$T/compare-n.out" || { cat "$T/compare-n.out"; fail "compare with a named J: counts"; }
grep -q "J and K_b as the live fitter chose them .* so that like is compared with like" "$T/compare-n.err" || fail "compare with a named J: not said"
"$B/spindown" refit "$LOG" --json --bench-config "$T/benches" >"$T/refit.json" 2>"$T/refit.err" || fail "refit --json"
"$B/spindown" refit "$LOG" --live --json >"$T/live.json" 2>"$T/live.err" || fail "refit --live"
"$B/spindown" fit "$LOG" --json >"$T/fit.json" 2>"$T/fit.err" || fail "spindown fit on the log"
python3 - "$T/refit.json" "$T/live.json" "$T/fit.json" <<'EOF' || fail "JSON comparison"
import json, sys
refit, live, fit = (json.load(open(p)) for p in sys.argv[1:4])
def strip(run, extras):
    run = json.loads(json.dumps(run))
    for k in ("latency_s", "utime"): run.pop(k, None)
    if extras:  # spindown fit has no --bench-config here: no health
        run["bench"].pop("id", None); run.pop("first_seq", None); run.pop("last_seq", None); run.pop("health", None)
    return run
rr = refit["files"][0]["runs"]; lr = live["files"][0]["runs"]; fr = fit["files"][0]["runs"]
assert len(rr) == 6 and len(lr) == 6 and len(fr) == 6, (len(rr), len(lr), len(fr))
key = lambda r: (r["bench"]["id"], r["run"])
assert sorted(map(strip, rr, [False]*6), key=key) == sorted(map(strip, lr, [False]*6), key=key), "refit != live"
assert [strip(r, True) for r in rr] == [strip(r, True) for r in fr], "refit != spindown fit"
# spindown fit names each run's bench when the log holds several (run numbers restart per bench).
benches = [r["bench"]["id"] for r in rr]
fit_ids = [r["bench"].get("id") for r in fr]
assert fit_ids == (benches if len(set(benches)) > 1 else [None] * len(fr)), (fit_ids, benches)
assert sum(1 for r in rr if "health" in r) == 2 and all(r["health"]["level"] == "ok" for r in rr if "health" in r)
print("refit == live FIT messages == spindown fit: 6 runs (bench000's with the live health verdicts)")
EOF
python3 - "$T/refit.json" "$T/named.json" <<'EOF' || fail "a bench file's J in a refit"
import json, sys
plain, named = (json.load(open(p))["files"][0]["runs"] for p in sys.argv[1:3])
for a, b in zip(plain, named):
    assert a["bench"]["id"] == b["bench"]["id"]
    if a["bench"]["id"] != "bench000":
        assert a == b, "another bench's runs changed"
        continue
    assert abs(b["bench"]["J"] / a["bench"]["J"] - 2) < 1e-6, (a["bench"], b["bench"])
    c3 = [next(m for m in r["models"] if m["name"] == "combined")["params"]["c3"]["value"] for r in (a, b)]
    assert abs(c3[1] / c3[0] - 2) < 1e-6, c3   # c/J is what the data say
print("a bench file's [bench] J wins over the log's CONFIG in a refit: c3 x2 for bench000 only")
EOF
"$B/spindown" refit "$LOG" --bench-config "$T/named" >"$T/named.txt" 2>/dev/null || fail "refit text with a named J"
grep -qF -- "-- bench bench000 (J/K_b: J: bench file $T/named/bench000.toml (over the log's CONFIG: 1.12688e-05 kg·m²); K_b: CONFIG)" "$T/named.txt" ||
  fail "the refit does not say J came from the bench file over the CONFIG"

# ---- 3. replay on a separate URL into a fresh fitter --------------------------------------------
start_logger "$URL" "$T/spy" spy; SPY=$STARTED  # must stay empty: the replay is elsewhere
start_logger "$REPLAY_URL" "$T/replay" replay; LOGGER2=$STARTED
"$B/spindown-fitter" --lcm-url "$REPLAY_URL" --instance replay --bench-config "$T/benches" -v 2>"$T/fitter2.err" &
FITTER2=$!; PIDS+=($FITTER2)
sleep 0.5
lcm-logplayer --lcm-url="$REPLAY_URL" --speed=1 --regexp='SPINDOWN\..*\.(SAMPLE|CONFIG)' "$LOG" \
  >"$T/player.err" 2>&1 || fail "lcm-logplayer"
for _ in $(seq 100); do
  [ "$(grep -c ' fitted: ' "$T/fitter2.err" || true)" -ge 6 ] && break; sleep 0.1
done
sleep 0.6
stop "$FITTER2"; stop "$LOGGER2"; stop "$SPY"
[ "$(grep -c ' fitted: ' "$T/fitter2.err" || true)" -eq 6 ] || fail "replay fitter: expected 6 fits"
LOG2=$(only_log "$T/replay")
"$B/spindown" refit "$LOG2" --compare >"$T/compare2.out" 2>"$T/compare2.err" || { cat "$T/compare2.out"; fail "replay compare"; }
grep -q "6 identical, 0 different" "$T/compare2.out" || { cat "$T/compare2.out"; fail "replay counts"; }
"$B/spindown" refit "$LOG2" --live --json >"$T/live2.json" 2>/dev/null || fail "refit --live of the replay"
python3 - "$T/live.json" "$T/live2.json" <<'EOF' || fail "replay differs from live"
import json, sys
a, b = (json.load(open(p))["files"][0]["runs"] for p in sys.argv[1:3])
key = lambda r: (r["bench"]["id"], r["run"])
assert sorted(a, key=key) == sorted(b, key=key), "replayed FITs differ from the live ones"
print("replay on a separate URL: the same 6 fits")
EOF
SPYLOG=$(ls "$T"/spy/*.lcm 2>/dev/null | head -1 || true)
if [ -n "$SPYLOG" ] && "$B/spindown" refit "$SPYLOG" --json >/dev/null 2>&1; then
  fail "the replay leaked onto the live URL"
fi
echo "PASS: live fitter, log, refit, spindown fit and replay agree"
