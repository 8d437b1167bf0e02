#!/usr/bin/env bash
# deploy/lcm-logplayer-gui on Java 17 under Xvfb, in a private network namespace: a real
# spindown-logger log (2 benches, every message type) opened paused; the LogPlayer window appears
# (xdotool), nothing is replayed before Play, a click on its Play button replays the log, and a
# second spindown-logger on the replay URL receives every message of every channel (the
# loggers' own STATUS aside). The screenshot is kept beside the build's bin/ for a person.
source "$(dirname "$0")/logger_common.bash"
SRC=${SPINDOWN_SOURCE_DIR:-$(cd "$(dirname "$0")/../.." && pwd)}
SHOT=${SPINDOWN_SCREENSHOT:-$BIN/../logplayer_gui_screenshot.png}
REPLAY_URL='udpm://239.255.76.68:7668?ttl=0'
for tool in Xvfb xdotool java import; do
  command -v "$tool" >/dev/null 2>&1 || fail "$tool not installed (deploy/setup --tests: xvfb, xdotool, imagemagick, default-jdk-headless)"
done

# channels LOG: {channel: events} as JSON, without the loggers' own heartbeats.
channels() {
  "$BIN/spindown-log-summary" "$@" | python3 -c '
import json, sys
out = {}
for f in json.load(sys.stdin)["files"]:
    for ch, n in f["channels"].items():
        if not ch.startswith("SPINDOWN.logger."):
            out[ch] = out.get(ch, 0) + n
print(json.dumps(out, sort_keys=True))'
}
sample_events() { python3 -c 'import json,sys; d=json.loads(sys.argv[1]); print(sum(n for c, n in d.items() if c.endswith(".SAMPLE")))' "$1"; }

# A real log. Its name is short on purpose: LogPlayer's first column is 90 px wide unless the
# file name is wider, which puts the Play button's centre 140 px from the window's left edge.
mkdir "$WORK/rec"
start_logger rec --lcm-url "$URL" --dir "$WORK/rec" --flush-interval 0.2
rec=$LOGGER_PID
wait_for_log "$WORK/rec"
"$BIN/spindown-lcm-publish" --lcm-url "$URL" --benches 2 --count 300 --rate 150 --batch 2 --all-types >/dev/null
stop_logger "$rec"
[[ $LOGGER_RC == 0 ]] || fail "the recording logger exited with $LOGGER_RC"
cp "$WORK"/rec/*.lcm "$WORK/lab.lcm"
recorded=$(channels "$WORK/lab.lcm")
echo "recorded: $recorded"
(( $(sample_events "$recorded") == 600 )) || fail "the recording has not the 600 SAMPLE messages published"

mkdir "$WORK/replay"
start_logger replay --lcm-url "$REPLAY_URL" --dir "$WORK/replay" --flush-interval 0.1
replay=$LOGGER_PID
wait_for_log "$WORK/replay"

Xvfb -displayfd 3 -screen 0 1280x800x24 -nolisten tcp 3>"$WORK/display" 2>"$WORK/xvfb.log" &
PIDS+=($!)
for _ in $(seq 100); do [[ -s "$WORK/display" ]] && break; sleep 0.05; done
[[ -s "$WORK/display" ]] || fail "Xvfb did not start: $(cat "$WORK/xvfb.log")"
export DISPLAY=":$(head -1 "$WORK/display")"

"$SRC/deploy/lcm-logplayer-gui" --types-jar "${SPINDOWN_TYPES_JAR:-}" -l "$REPLAY_URL" -p "$WORK/lab.lcm" \
  >"$WORK/player.log" 2>&1 &
player=$!
PIDS+=("$player")
win=
for _ in $(seq 200); do
  win=$(xdotool search --name '^LogPlayer$' 2>/dev/null | head -1) && [[ -n $win ]] && break
  kill -0 "$player" 2>/dev/null || break
  sleep 0.1
done
[[ -n $win ]] || fail "no 'LogPlayer' window within 20 s: $(cat "$WORK/player.log")"
grep -q "Unrecognized\|Could not create the Java Virtual Machine" "$WORK/player.log" &&
  fail "java refused an option: $(cat "$WORK/player.log")"
# LogPlayer prints the log's length once it has opened it.
for _ in $(seq 100); do grep -q "Total seconds" "$WORK/player.log" && break; sleep 0.1; done
grep -q "Total seconds" "$WORK/player.log" || fail "LogPlayer did not open the log: $(cat "$WORK/player.log")"
xdotool windowmove "$win" 0 0
sleep 1   # let Java map and paint the window before the click
# Paused (-p): nothing is on the replay URL until Play is pressed.
before=$(channels "$WORK"/replay/*.lcm)
[[ $before == "{}" ]] || fail "the paused player replayed already: $before"

geometry=$(xdotool getwindowgeometry --shell "$win")
eval "$geometry"
(( WIDTH >= 300 && HEIGHT >= 150 )) || fail "LogPlayer window only ${WIDTH}x$HEIGHT"
xdotool mousemove --window "$win" 140 14 click 1
# Play turns into Pause and the log plays in real time (about 2 s here); wait for every SAMPLE.
replayed=
for _ in $(seq 300); do
  replayed=$(channels "$WORK"/replay/*.lcm)
  (( $(sample_events "$replayed") >= 600 )) && break
  kill -0 "$player" 2>/dev/null || fail "the player exited: $(cat "$WORK/player.log")"
  sleep 0.1
done
sleep 0.5   # the last non-SAMPLE messages after the last SAMPLE
import -window "$win" "$WORK/shot.png" 2>/dev/null && cp "$WORK/shot.png" "$SHOT" || echo "note: no screenshot"
kill -0 "$player" 2>/dev/null || fail "the player exited: $(cat "$WORK/player.log")"
stop_logger "$replay"
replayed=$(channels "$WORK"/replay/*.lcm)
echo "replayed: $replayed"
[[ $replayed == "$recorded" ]] || fail "the replay differs from the recording (Play not pressed, or messages lost)"
echo "screenshot: $SHOT"
echo "PASS: lcm-logplayer-gui runs on this Java, opens paused, and plays the whole log when Play is clicked"
