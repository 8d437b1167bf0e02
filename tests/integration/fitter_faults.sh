#!/bin/bash
# spindown-fitter under bad traffic: NaN values, repeated messages, sequence gaps, wrong
# fingerprints, truncated messages, time going backwards, a new bench id every few messages
# (max-benches 8) and an invalid bench id. Every run of the real benches is still fitted, the
# heartbeat on SPINDOWN.fitter.STATUS counts each kind of damage and names the last one, the
# refit of the log still equals the live fits, and `spindown export --csv` writes every sample
# and every fitted model. Private network namespace, ttl=0.
source "$(dirname "${BASH_SOURCE[0]}")/netns_common.bash"

mkdir -p "$T/log"
"$B/spindown-logger" --lcm-url "$URL" --dir "$T/log" --prefix faults --flush-interval 0.2 >"$T/logger.out" 2>"$T/logger.err" &
LOGGER=$!; PIDS+=($LOGGER)
"$B/spindown-fitter" --lcm-url "$URL" --status-period 0.2 --max-benches 8 2>"$T/fitter.err" &
FITTER=$!; PIDS+=($FITTER)
sleep 0.5
"$B/spindown-run-publisher" --lcm-url "$URL" --benches 3 --runs 2 --speed 20 --batch 4 --wait-fits 20 \
  --nan-every 37 --dup-every 41 --gap-every 43 --garbage-every 47 --truncate-every 53 --backwards-every 59 \
  --new-bench-every 7 --invalid-bench-every 61 --report "$T/report.json" >"$T/publisher.out" 2>"$T/publisher.err"
sleep 1
stop "$FITTER"; stop "$LOGGER"
LOG=$(ls "$T"/log/*.lcm | head -1)

python3 - "$T/report.json" <<'EOF' || fail "fits under faults"
import json, sys
r = json.load(open(sys.argv[1]))
real = [f for f in r["fit_list"] if f["bench"].startswith("bench")]
assert len(real) == 6, [ (f["bench"], f["run"]) for f in r["fit_list"] ]
print("faults: all 6 runs of the 3 real benches fitted")
EOF

# The fitter's counters (also in every heartbeat) from its summary line.
SUMMARY=$(grep "stopped: " "$T/fitter.err" | tail -1)
echo "$SUMMARY"
for what in "decode errors" "sequence gaps" "duplicates" "NaN values" "time backwards" "benches evicted"; do
  n=$(echo "$SUMMARY" | grep -o "[0-9]* $what" | grep -o '^[0-9]*')
  [ "${n:-0}" -gt 0 ] || fail "fitter did not count $what"
done

# The heartbeat is in the log, with its counters and a last error naming a channel.
python3 - "$LOG" <<'EOF' || fail "heartbeat"
import sys
data = open(sys.argv[1], "rb").read()
n = data.count(b"SPINDOWN.fitter.STATUS")
assert n >= 3, f"{n} heartbeats"
for counter in (b"decode_errors", b"seq_gaps", b"duplicates", b"nan_values", b"time_backwards", b"dropped_benches",
                b"flood_drops"):
    assert counter in data, counter
assert b"skipped" in data or b"evicted" in data, "last_error text"
print(f"heartbeat: {n} STATUS messages with every counter")
EOF

# Refit equals the live fits, damage and all (the logger saw the same traffic, so the same
# benches are evicted at the same moments: a bench that lost its CONFIG that way is fitted with
# the default J in both).
"$B/spindown" refit "$LOG" --compare --max-benches 8 >"$T/compare.out" 2>"$T/compare.err" || fail "refit --compare"
grep -q "6 identical, 0 different" "$T/compare.out" || fail "compare counts"

# Export: every sample row, every fitted model row.
"$B/spindown" export "$LOG" --csv -o "$T/samples.csv" --bench 'bench.*' 2>"$T/export.err" || fail "export"
python3 - "$T/samples.csv" "$T/samples.fits.csv" <<'EOF' || fail "export content"
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
assert rows and list(rows[0].keys()) == ["bench", "seq", "device_time_s", "host_time_s", "value", "unit", "raw_adc",
                                          "clock_epoch"], rows[0].keys()
assert {r["bench"] for r in rows} == {"bench000", "bench001", "bench002"}
assert any(r["value"] == "NaN" for r in rows), "NaN samples are exported as recorded"
fits = list(csv.DictReader(open(sys.argv[2])))
assert len(fits) == 6 * 3, len(fits)
best = [f for f in fits if f["best"] == "1"]
assert len(best) == 6 and all(float(f["c4"]) > 0 for f in best if f["model"] == "combined")
print(f"export: {len(rows)} sample rows, {len(fits)} model rows")
EOF
echo "PASS: faults counted, every run fitted, refit == live, export complete"
