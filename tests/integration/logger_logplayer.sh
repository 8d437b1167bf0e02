#!/usr/bin/env bash
# lcm-logplayer plays spindown-logger's log: replayed on a separate URL into a second logger it
# gives the same messages per channel, and the first logger (the "live lab" URL) hears none of
# the replay.
source "$(dirname "$0")/logger_common.bash"
REPLAY_URL='udpm://239.255.76.68:7668?ttl=0'

mkdir "$WORK/live" "$WORK/replay"
start_logger live --lcm-url "$URL" --dir "$WORK/live"
live=$LOGGER_PID
wait_for_log "$WORK/live"
"$BIN/spindown-lcm-publish" --lcm-url "$URL" --benches 2 --count 1500 --rate 1000 --batch 4 --all-types >/dev/null
stop_logger "$live"
[[ $LOGGER_RC == 0 ]] || fail "live logger exited with $LOGGER_RC"
recorded=("$WORK"/live/*.lcm)
(( ${#recorded[@]} == 1 )) || fail "want one recorded file, got ${#recorded[@]}"

# A live logger keeps listening on the lab URL while the replay goes to REPLAY_URL.
mkdir "$WORK/live2"
start_logger live2 --lcm-url "$URL" --dir "$WORK/live2"
live2=$LOGGER_PID
start_logger replay --lcm-url "$REPLAY_URL" --dir "$WORK/replay"
replay=$LOGGER_PID
wait_for_log "$WORK/replay"
timeout 60 lcm-logplayer -s 5 --lcm-url "$REPLAY_URL" "${recorded[0]}" >"$WORK/player.out" 2>&1 \
  || fail "lcm-logplayer failed on our log: $(cat "$WORK/player.out")"
sleep 0.3
stop_logger "$replay"
[[ $LOGGER_RC == 0 ]] || fail "replay logger exited with $LOGGER_RC"
stop_logger "$live2"

"$BIN/spindown-log-summary" "${recorded[0]}" >"$WORK/a.json"
"$BIN/spindown-log-summary" "$WORK"/replay/*.lcm >"$WORK/b.json"
"$BIN/spindown-log-summary" "$WORK"/live2/*.lcm >"$WORK/c.json"
python3 - "$WORK/a.json" "$WORK/b.json" "$WORK/c.json" <<'PY'
import json, sys
def channels(path):
    out = {}
    for f in json.load(open(path))["files"]:
        for ch, n in f["channels"].items():
            if not ch.startswith("SPINDOWN.logger."):   # each logger's own status differs
                out[ch] = out.get(ch, 0) + n
    return out
a, b, c = (channels(p) for p in sys.argv[1:])
print("recorded:", a)
print("replayed:", b)
assert a == b, f"replay differs: {a} vs {b}"
assert a.get("SPINDOWN.bench-1.SAMPLE") == 1500 and a.get("SPINDOWN.bench-2.SAMPLE") == 1500, a
for k in ("CONFIG", "RUN", "FIT", "EXPLAIN", "STATUS"):
    assert a.get(f"SPINDOWN.bench-1.{k}", 0) >= 1, f"no {k} recorded"
assert c == {}, f"the replay leaked into the live URL: {c}"
PY
echo "PASS: lcm-logplayer replays our log message for message, on its own URL only"
