#!/bin/bash
# spindown export --mcap, read back by the MCAP project's own reader:
#  1. a live log (spindown-fitter + spindown-logger on a private LCM URL, spindown-run-publisher
#     publishing runs for 3 benches), so it holds SAMPLE, RUN and FIT messages;
#  2. spindown export --csv (samples and refitted fits) and --mcap of that log;
#  3. @mcap/core (the MCAP project's TypeScript reader, which deploy/setup --tests installs from
#     the npm registry into /usr/local/lib/spindown-tests/node, or $SPINDOWN_TEST_NODE_DIR; this
#     test installs nothing) reads the MCAP indexed and streamed, checks the CRCs, decodes every
#     message (tests/integration/mcap_read.js);
#  4. every sample equals its CSV row, field by field and in order; there is one FIT per run of
#     the fits CSV with the same parameters; RUN messages follow every run to "stopped";
#  5. --bench keeps one bench; a file that is not an LCM log and a missing file fail naming it.
# Everything runs in a private network namespace (unshare -n); ttl=0.
source "$(dirname "${BASH_SOURCE[0]}")/netns_common.bash"
SRC=${SPINDOWN_SOURCE_DIR:?}

# The reader, where deploy/setup --tests put it (never installed from here: no registry while
# a test runs).
NODE_DIR=${SPINDOWN_TEST_NODE_DIR:-/usr/local/lib/spindown-tests/node}
command -v node >/dev/null || fail "node is not installed: run deploy/setup --tests"
[ -f "$NODE_DIR/node_modules/@mcap/core/package.json" ] ||
  fail "@mcap/core is not installed in $NODE_DIR: run deploy/setup --tests (it installs it from the npm registry)"
read_mcap() { NODE_PATH="$NODE_DIR/node_modules" node "$SRC/tests/integration/mcap_read.js" "$@"; }

# ---- 1. a live log --------------------------------------------------------------------------
mkdir -p "$T/live"
"$B/spindown-logger" --lcm-url "$URL" --dir "$T/live" --prefix live --flush-interval 0.2 >"$T/logger.out" 2>"$T/logger.err" &
LOGGER=$!; PIDS+=($LOGGER)
"$B/spindown-fitter" --lcm-url "$URL" --status-period 0.2 --no-explain 2>"$T/fitter.err" &
FITTER=$!; PIDS+=($FITTER)
sleep 0.5
"$B/spindown-run-publisher" --lcm-url "$URL" --benches 3 --runs 2 --speed 20 --config-benches 2 \
  --wait-fits 20 --report "$T/report.json" >"$T/publisher.out" 2>"$T/publisher.err" || fail "run publisher"
sleep 1  # the logger has written every FIT
stop "$FITTER"; stop "$LOGGER"
LOG=$(ls "$T"/live/*.lcm | head -1)

# ---- 2. CSV and MCAP ------------------------------------------------------------------------
"$B/spindown" export "$LOG" --csv -o "$T/samples.csv" 2>"$T/csv.err" || fail "export --csv"
start_ns=$(date +%s%N)
"$B/spindown" export "$LOG" --mcap "$T/log.mcap" 2>"$T/mcap.err" || fail "export --mcap: $(cat "$T/mcap.err")"
ms=$(( ($(date +%s%N) - start_ns) / 1000000 ))
cat "$T/mcap.err"
[ -f "$T/log.mcap.partial" ] && fail "a .partial file was left behind"
echo "LCM log $(stat -c %s "$LOG") bytes -> MCAP $(stat -c %s "$T/log.mcap") bytes in $ms ms"

# ---- 3. the MCAP project's reader -----------------------------------------------------------
read_mcap "$T/log.mcap" "$T/mcap.json" || fail "@mcap/core could not read the file"

# ---- 4. the same numbers as the CSV ---------------------------------------------------------
python3 - "$T/mcap.json" "$T/samples.csv" "$T/samples.fits.csv" <<'EOF' || fail "MCAP != CSV"
import csv, json, math, sys
m = json.load(open(sys.argv[1]))
rows = list(csv.DictReader(open(sys.argv[2])))
fits = list(csv.DictReader(open(sys.argv[3])))
by = lambda kind: [x for x in m["messages"] if x["topic"].endswith("." + kind)]
samples, runs, fit_msgs = by("SAMPLE"), by("RUN"), by("FIT")
assert m["library"] == "spindown export --mcap", m["library"]
for topic, t in m["topics"].items():
    kind = topic.split(".")[-1]
    assert t["encoding"] == "json" and t["schema_encoding"] == "jsonschema", t
    assert t["schema"] == {"SAMPLE": "spindown.sample", "RUN": "spindown.run", "FIT": "spindown.fit"}[kind], t
    assert t["count"] == sum(1 for x in m["messages"] if x["topic"] == topic), (topic, t)
assert len(m["topics"]) == 9, sorted(m["topics"])

def close(a, b, tol):
    return abs(a - b) <= tol * max(1.0, abs(a), abs(b))

# Every sample, in log order, equals its CSV row.
assert len(samples) == len(rows) > 1000, (len(samples), len(rows))
for i, (s, r) in enumerate(zip(samples, rows)):
    d = s["data"]
    where = f"sample {i}: {d} vs {r}"
    assert s["topic"] == f"SPINDOWN.{r['bench']}.SAMPLE" and d["bench"] == r["bench"], where
    assert d["seq"] == int(r["seq"]) and s["sequence"] == int(r["seq"]) % 2**32, where
    assert abs(d["device_time_s"] - float(r["device_time_s"])) <= 5e-7, where
    assert abs(d["host_time_s"] - float(r["host_time_s"])) <= 5e-7, where
    assert abs(int(s["log_time_ns"]) / 1e9 - d["host_time_s"]) <= 1e-6, where  # log_time: the host time
    if r["value"] == "NaN":
        assert d["value"] is None, where
    else:
        assert close(d["value"], float(r["value"]), 1e-9), where
    assert d["unit"] == r["unit"], where
    assert (d["raw_adc"] is None) == (r["raw_adc"] == ""), where
    if r["raw_adc"]: assert d["raw_adc"] == int(r["raw_adc"]), where
    assert d["clock_epoch"] == int(r["clock_epoch"]), where

# One FIT per refitted run, with the refit's numbers (refit == live, fitter_live_refit.sh).
csv_runs = {(f["bench"], int(f["run"])) for f in fits}
mcap_runs = {(x["data"]["bench"]["id"], x["data"]["run"]) for x in fit_msgs}
assert len(fit_msgs) == len(csv_runs) == 6 and mcap_runs == csv_runs, (mcap_runs, csv_runs)
fit_of = {(x["data"]["bench"]["id"], x["data"]["run"]): x["data"] for x in fit_msgs}
checked = 0
for f in fits:
    j = fit_of[(f["bench"], int(f["run"]))]
    model = next(md for md in j["models"] if md["name"] == f["model"])
    assert (j["best"] == f["model"]) == (f["best"] == "1"), (j["best"], f)
    assert close(j["t_cut_s"], float(f["t_cut_s"]), 1e-9), (j["t_cut_s"], f["t_cut_s"])
    if f["rmse"] not in ("", "NaN"):
        assert close(model["rmse"], float(f["rmse"]), 1e-8), (model["rmse"], f["rmse"])
    for p in ("c1", "c2", "c3", "c4", "omega0"):
        if f[p] in ("", "NaN"): continue
        assert close(model["params"][p]["value"], float(f[p]), 1e-8), (p, model["params"][p], f[p])
        checked += 1
assert checked >= 18, checked

# RUN messages: each run's life ends "stopped", at the fits' cut.
last = {}
for x in runs:
    d = x["data"]
    last[(d["bench"], d["run"])] = d
assert set(last) == csv_runs, (sorted(last), sorted(csv_runs))
for k, d in last.items():
    assert d["state"] == "stopped" and d["state_code"] == 2, d
t_cut = {(f["bench"], int(f["run"])): float(f["t_cut_s"]) for f in fits}
for k, d in last.items():
    assert close(d["t_cut_s"], t_cut[k], 1e-9), (k, d["t_cut_s"], t_cut[k])
print(f"MCAP == CSV: {len(samples)} samples field by field, {len(fit_msgs)} FIT ({checked} parameters), "
      f"{len(runs)} RUN messages over {len(last)} runs")
EOF

# ---- 5. --bench, and bad inputs ---------------------------------------------------------------
"$B/spindown" export "$LOG" --mcap "$T/one.mcap" --bench bench001 2>"$T/one.err" || fail "export --mcap --bench"
read_mcap "$T/one.mcap" "$T/one.json" >/dev/null || fail "@mcap/core on the --bench file"
python3 - "$T/one.json" <<'EOF' || fail "--bench"
import json, sys
m = json.load(open(sys.argv[1]))
assert sorted(m["topics"]) == ["SPINDOWN.bench001.FIT", "SPINDOWN.bench001.RUN", "SPINDOWN.bench001.SAMPLE"], sorted(m["topics"])
assert all(x["topic"].startswith("SPINDOWN.bench001.") for x in m["messages"])
print(f"--bench bench001: {len(m['messages'])} messages, that bench only")
EOF
printf 'millis\tvolts\n0\t1.0\n' >"$T/text.tsv"
rc=0; "$B/spindown" export "$T/text.tsv" --mcap "$T/bad.mcap" 2>"$T/bad.err" || rc=$?
[ $rc = 1 ] && grep -q "text.tsv" "$T/bad.err" && grep -q "not an LCM event log" "$T/bad.err" || fail "text file: exit $rc: $(cat "$T/bad.err")"
[ ! -e "$T/bad.mcap" ] && [ ! -e "$T/bad.mcap.partial" ] || fail "an MCAP was left for a file that is not a log"
rc=0; "$B/spindown" export "$T/missing.lcm" --mcap "$T/bad.mcap" 2>"$T/bad.err" || rc=$?
[ $rc = 1 ] && grep -q "missing.lcm" "$T/bad.err" || fail "missing log: exit $rc: $(cat "$T/bad.err")"
rc=0; "$B/spindown" export "$LOG" --mcap "$T/x.mcap" -o "$T/x.csv" 2>"$T/bad.err" || rc=$?
[ $rc = 2 ] || fail "--mcap with -o: exit $rc (want 2, bad usage)"
echo "PASS: export --mcap read back by @mcap/core equals export --csv"
