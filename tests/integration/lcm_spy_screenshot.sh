#!/usr/bin/env bash
# deploy/lcm-spy on this Java, under Xvfb, with every spindown type published for 2 benches in a
# private network namespace: lcm-spy loads our 6 types and lists and decodes every channel.
#
# What is checked, and how without OCR or accessibility (neither exists here). Java draws the
# table under Xvfb without anti-aliasing (text one dark grey, grid lines one mid grey), so
# gui_pixels.py finds the table's columns and rows from its grid lines alone, not from fixed
# coordinates or a reference image:
#  - listed: the table has exactly the 12 rows expected, and double-clicking row i opens a
#    decoder window titled with the i-th channel in sorted order (xdotool search --name), so every
#    channel is there, each once, FIT among them;
#  - decoded: a row's Type cell shows the class name (fit_t, samples_t: at most 9 characters)
#    when the types jar decodes the channel, and "?? <16 hex digits>" (19 characters, as wide as
#    the channel name) when it does not; so each row's Type ink must be under 0.6 of its Channel
#    ink (decoded rows measure 0.16..0.36 here, undecoded ones 0.79..0.96), a ratio of widths in
#    the same font that no font size changes;
#  - each decoder window shows the message's fields: at least 8 lines of text (an undecodable
#    channel's window stays blank).
# The screenshot (lcm_spy_screenshot.png beside the build's bin/, never in git) is for a person.
# Without a types jar, or with one that lacks a type, the test fails and says which rows. A tool
# missing (Xvfb, xdotool, ImageMagick, NumPy: deploy/setup --tests) is a failure, not a skip.
source "$(dirname "$0")/logger_common.bash"
SRC=${SPINDOWN_SOURCE_DIR:-$(cd "$(dirname "$0")/../.." && pwd)}
SHOT=${SPINDOWN_SCREENSHOT:-$BIN/../lcm_spy_screenshot.png}
PY=${SPINDOWN_PYTHON:-/usr/bin/python3}
for tool in Xvfb xdotool java import convert; do
  command -v "$tool" >/dev/null 2>&1 ||
    fail "$tool not installed (deploy/setup --tests: xvfb, xdotool, imagemagick, default-jdk-headless)"
done
"$PY" -c 'import numpy' 2>/dev/null || fail "$PY has no NumPy (deploy/setup --tests: python3-numpy)"
[[ -n "${SPINDOWN_TYPES_JAR:-}" && -f "${SPINDOWN_TYPES_JAR}" ]] ||
  fail "no types jar (SPINDOWN_TYPES_JAR='${SPINDOWN_TYPES_JAR:-}'): cmake --build build --target spindown_types_jar"
pixels() { "$PY" "$SRC/tests/integration/gui_pixels.py" "$@"; }

CHANNELS=()
for bench in bench-1 bench-2; do
  for kind in CONFIG EXPLAIN FIT RUN SAMPLE STATUS; do CHANNELS+=("SPINDOWN.$bench.$kind"); done
done

# Xvfb picks a free display and writes its number to fd 3.
Xvfb -displayfd 3 -screen 0 1600x1000x24 -nolisten tcp 3>"$WORK/display" 2>"$WORK/xvfb.log" &
PIDS+=($!)
for _ in $(seq 100); do [[ -s "$WORK/display" ]] && break; sleep 0.05; done
[[ -s "$WORK/display" ]] || fail "Xvfb did not start: $(cat "$WORK/xvfb.log")"
export DISPLAY=":$(head -1 "$WORK/display")"

"$BIN/spindown-lcm-publish" --lcm-url "$URL" --benches 2 --count 0 --rate 20 --duration 120 --all-types \
  >/dev/null &
PIDS+=($!)
"$SRC/deploy/lcm-spy" --types-jar "$SPINDOWN_TYPES_JAR" --lcm-url "$URL" >"$WORK/spy.log" 2>&1 &
spy=$!
PIDS+=("$spy")

main=
for _ in $(seq 150); do
  main=$(xdotool search --name '^LCM Spy$' 2>/dev/null | head -1) && [[ -n $main ]] && break
  kill -0 "$spy" 2>/dev/null || break
  sleep 0.1
done
[[ -n $main ]] || fail "no 'LCM Spy' window within 15 s: $(cat "$WORK/spy.log")"
grep -q -- "-Xincgc\|Unrecognized option" "$WORK/spy.log" && fail "java refused an option: $(cat "$WORK/spy.log")"
# Wide enough for whole channel names; the decoder windows go below it. Java sizes its frame
# once more after showing it, so the size is set until it holds.
for _ in $(seq 50); do
  xdotool windowmove "$main" 0 0 windowsize "$main" 1580 400
  sleep 0.2
  eval "$(xdotool getwindowgeometry --shell "$main")"
  (( WIDTH == 1580 )) && break
done

# Every channel shows up within a few seconds (CONFIG, RUN, … come once a second).
n=0
for _ in $(seq 100); do
  # A window just mapped cannot be read yet ("Resource temporarily unavailable"): try again.
  import -window "$main" "$WORK/main.png" 2>"$WORK/import.err" || { sleep 0.2; continue; }
  pixels table "$WORK/main.png" >"$WORK/table.json"
  n=$("$PY" -c 'import json,sys; print(len(json.load(open(sys.argv[1]))["rows"]))' "$WORK/table.json")
  (( n >= ${#CHANNELS[@]} )) && break
  kill -0 "$spy" 2>/dev/null || fail "lcm-spy exited: $(cat "$WORK/spy.log")"
  sleep 0.2
done
(( n == ${#CHANNELS[@]} )) || fail "the channel table has $n rows, want ${#CHANNELS[@]}: $(cat "$WORK/table.json")"

# Decoded: each row's Type cell is a short class name, not "?? <fingerprint>".
"$PY" - "$WORK/table.json" "${CHANNELS[@]}" <<'PY' || fail "not every channel is decoded (is every type in the jar?)"
import json, sys
rows = json.load(open(sys.argv[1]))["rows"]
bad = [(ch, r["ratio"]) for ch, r in zip(sys.argv[2:], rows) if not 0 < r["ratio"] < 0.6]
for ch, r in zip(sys.argv[2:], rows):
    print("row %-24s Type/Channel ink %.2f" % (ch, r["ratio"]))
if bad:
    print("undecoded rows (Type as wide as '?? <fingerprint>', or empty):", bad)
    sys.exit(1)
PY

# Listed, each once, in order: double-click row i opens a decoder window titled channel i, with fields.
i=0
while read -r x y; do
  channel=${CHANNELS[$i]}
  pattern="^${channel//./\\.}\$"
  xdotool mousemove --window "$main" "$x" "$y" click --repeat 2 --delay 80 1
  view=
  for _ in $(seq 50); do
    view=$(xdotool search --name "$pattern" 2>/dev/null | tail -1) && [[ -n $view ]] && break
    sleep 0.1
  done
  [[ -n $view ]] || fail "double-clicking row $((i + 1)) opened no window titled $channel (is the channel listed there?)"
  sleep 1   # Java places the new window first; moved before that, it lands back on the list
  xdotool windowmove "$view" $(( (i % 6) * 200 )) $(( 420 + (i / 6) * 40 )) windowsize "$view" 600 520
  lines=0
  for _ in $(seq 25); do
    import -window "$view" "$WORK/view.png" 2>"$WORK/import.err" || { sleep 0.2; continue; }
    lines=$(pixels lines "$WORK/view.png")
    (( lines >= 8 )) && break
    sleep 0.2
  done
  echo "view $channel: $lines lines of fields"
  (( lines >= 8 )) || fail "the $channel window shows $lines lines, not its message's fields (undecoded?)"
  i=$((i + 1))
done < <("$PY" -c 'import json,sys; [print(r["x"], r["y"]) for r in json.load(open(sys.argv[1]))["rows"]]' "$WORK/table.json")
(( i == ${#CHANNELS[@]} )) || fail "opened $i views, want ${#CHANNELS[@]}"

# The FIT view on top for the person looking at the screenshot.
fit=$(xdotool search --name '^SPINDOWN\.bench-1\.FIT$' | tail -1)
xdotool windowraise "$fit" windowmove "$fit" 1000 420 2>/dev/null || true
sleep 0.5
kill -0 "$spy" 2>/dev/null || fail "lcm-spy exited: $(cat "$WORK/spy.log")"
grep -q "Found 6 LCM types" "$WORK/spy.log" || fail "lcm-spy did not load our 6 types: $(cat "$WORK/spy.log")"
import -window root "$WORK/shot.png"
cp "$WORK/shot.png" "$SHOT"
echo "screenshot: $SHOT"
echo "PASS: lcm-spy lists and decodes all ${#CHANNELS[@]} spindown channels, and opens a decoded view of each"
