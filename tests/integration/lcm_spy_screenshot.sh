#!/usr/bin/env bash
# deploy/lcm-spy on this Java: under Xvfb, with every spindown type published in a private
# network namespace, lcm-spy stays up, loads our 6 types, lists the channels and (with xdotool)
# opens decoded views of FIT, SAMPLE and STATUS; the screenshot is non-trivial. The PNG is kept
# beside the build's bin/ (lcm_spy_screenshot.png), never in git. Skips with a message when X
# tools, Java or the types jar are missing.
skip() { echo "SKIP: $*"; exit 0; }
for tool in Xvfb java import identify; do
  command -v "$tool" >/dev/null 2>&1 || skip "$tool not installed (deploy/setup: xvfb, imagemagick, default-jdk-headless)"
done
[[ -n "${SPINDOWN_TYPES_JAR:-}" && -f "${SPINDOWN_TYPES_JAR}" ]] || skip "no types jar (SPINDOWN_TYPES_JAR='${SPINDOWN_TYPES_JAR:-}')"
source "$(dirname "$0")/logger_common.bash"
SRC=${SPINDOWN_SOURCE_DIR:-$(cd "$(dirname "$0")/../.." && pwd)}
SHOT=${SPINDOWN_SCREENSHOT:-$BIN/../lcm_spy_screenshot.png}

# Xvfb picks a free display and writes its number to fd 3.
Xvfb -displayfd 3 -screen 0 1600x1000x24 -nolisten tcp 3>"$WORK/display" 2>"$WORK/xvfb.log" &
PIDS+=($!)
for _ in $(seq 100); do [[ -s "$WORK/display" ]] && break; sleep 0.05; done
[[ -s "$WORK/display" ]] || fail "Xvfb did not start: $(cat "$WORK/xvfb.log")"
export DISPLAY=":$(head -1 "$WORK/display")"

"$BIN/spindown-lcm-publish" --lcm-url "$URL" --benches 2 --count 0 --rate 20 --duration 60 --all-types \
  >/dev/null &
PIDS+=($!)
"$SRC/deploy/lcm-spy" --types-jar "$SPINDOWN_TYPES_JAR" --lcm-url "$URL" >"$WORK/spy.log" 2>&1 &
spy=$!
PIDS+=("$spy")

have_xdotool=0
command -v xdotool >/dev/null 2>&1 && have_xdotool=1
if (( have_xdotool )); then
  main=
  for _ in $(seq 150); do
    main=$(xdotool search --name '^LCM Spy$' 2>/dev/null | head -1) && [[ -n $main ]] && break
    sleep 0.1
  done
  [[ -n $main ]] || fail "no 'LCM Spy' window within 15 s: $(cat "$WORK/spy.log")"
  sleep 3   # a few seconds of traffic so every channel has shown up
  xdotool windowmove "$main" 0 0
  # Rows are sorted by channel: 0 CONFIG, 1 EXPLAIN, 2 FIT, 3 RUN, 4 SAMPLE, 5 STATUS of bench-1.
  open_view() {  # open_view ROW NAME X Y HEIGHT: double-click a row, place its decoded view
    local w=
    xdotool mousemove 60 $((27 + 16 * $1)) click --repeat 2 --delay 80 1
    for _ in $(seq 50); do
      w=$(xdotool search --name "$2" 2>/dev/null | tail -1) && [[ -n $w ]] && break
      sleep 0.1
    done
    [[ -n $w ]] || fail "double-clicking row $1 opened no '$2' view"
    sleep 1   # let Java place the new window first, or it lands back on top of the list
    xdotool windowmove "$w" "$3" "$4" windowsize "$w" 780 "$5"
  }
  open_view 2 'SPINDOWN.bench-1.FIT' 800 0 560
  open_view 4 'SPINDOWN.bench-1.SAMPLE' 0 620 380
  open_view 5 'SPINDOWN.bench-1.STATUS' 800 580 420
  sleep 2
else
  echo "note: xdotool not installed: the screenshot shows the channel list only"
  sleep 6
fi

kill -0 "$spy" 2>/dev/null || fail "lcm-spy exited: $(cat "$WORK/spy.log")"
import -window root "$WORK/shot.png"
cp "$WORK/shot.png" "$SHOT"
kill -0 "$spy" 2>/dev/null || fail "lcm-spy died while the screenshot was taken"

grep -q "Found 6 LCM types" "$WORK/spy.log" || fail "lcm-spy did not load our 6 types: $(cat "$WORK/spy.log")"
grep -q -- "-Xincgc\|Unrecognized option" "$WORK/spy.log" && fail "java refused an option: $(cat "$WORK/spy.log")"
bytes=$(stat -c %s "$WORK/shot.png")
colors=$(identify -format '%k' "$WORK/shot.png")
echo "screenshot: $SHOT ($bytes bytes, $colors colours)"
(( bytes > 20000 )) || fail "screenshot only $bytes bytes: nothing drawn?"
(( colors > 50 )) || fail "screenshot has only $colors colours: nothing drawn?"
echo "PASS: lcm-spy runs with spindown's types and stays up"
