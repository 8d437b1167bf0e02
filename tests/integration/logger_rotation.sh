#!/usr/bin/env bash
# spindown-logger rotation: by size (several files, each within the limit, each readable, no
# event split or lost at a boundary) and by time (a new file every second while traffic flows).
source "$(dirname "$0")/logger_common.bash"

# --- by size ---------------------------------------------------------------------------------
mkdir "$WORK/size"
start_logger size --lcm-url "$URL" --dir "$WORK/size" --rotate-size 0.05
wait_for_log "$WORK/size"
N=3000
"$BIN/spindown-lcm-publish" --lcm-url "$URL" --bench rot --count $N --rate 5000 >/dev/null
stop_logger "$LOGGER_PID"
[[ $LOGGER_RC == 0 ]] || fail "size logger exited with $LOGGER_RC"
files=("$WORK"/size/*.lcm)
echo "by size: ${#files[@]} files"
(( ${#files[@]} >= 4 )) || fail "want >= 4 files of 0.05 MB for ~330 kB, got ${#files[@]}"
for f in "${files[@]}"; do
  size=$(stat -c %s "$f")
  (( size <= 50000 + 2000 )) || fail "$f is $size bytes, over the 0.05 MB limit (+ the closing status event)"
  "$BIN/spindown-log-summary" "$f" >"$WORK/one.json"
  [[ $(json "$WORK/one.json" 'd["problems"]') == 0 ]] || fail "$f: $(cat "$WORK/one.json")"
  state=$(json "$WORK/one.json" 'd["files"][0]["last_logger_status"]["state"]')
  [[ $state == rotating || $state == stopped ]] || fail "$f ends with status state '$state'"
done
"$BIN/spindown-log-summary" "${files[@]}" >"$WORK/all.json"
msgs=$(json "$WORK/all.json" 'd["benches"]["rot"]["messages"]')
gaps=$(json "$WORK/all.json" 'd["benches"]["rot"]["gaps"]')
repeats=$(json "$WORK/all.json" 'd["benches"]["rot"]["repeats"]')
[[ $msgs == "$N" && $gaps == 0 && $repeats == 0 ]] || fail "across files: $msgs of $N messages, $gaps gaps, $repeats repeats"
rotating=$(python3 -c "import json; d=json.load(open('$WORK/all.json')); print(sum(f['last_logger_status']['state']=='rotating' for f in d['files']))")
(( rotating == ${#files[@]} - 1 )) || fail "$rotating files end with 'rotating', want $(( ${#files[@]} - 1 ))"

# --- by time ---------------------------------------------------------------------------------
mkdir "$WORK/time"
start_logger time --lcm-url "$URL" --dir "$WORK/time" --rotate-time 1 --prefix lab
wait_for_log "$WORK/time"
"$BIN/spindown-lcm-publish" --lcm-url "$URL" --bench rot --count 350 --rate 100 >/dev/null
stop_logger "$LOGGER_PID"
[[ $LOGGER_RC == 0 ]] || fail "time logger exited with $LOGGER_RC"
files=("$WORK"/time/lab-*.lcm)
echo "by time: ${#files[@]} files over 3.5 s"
(( ${#files[@]} >= 3 )) || fail "want >= 3 files with --rotate-time 1 over 3.5 s, got ${#files[@]}"
"$BIN/spindown-log-summary" "${files[@]}" >"$WORK/all.json"
msgs=$(json "$WORK/all.json" 'd["benches"]["rot"]["messages"]')
gaps=$(json "$WORK/all.json" 'd["benches"]["rot"]["gaps"]')
[[ $msgs == 350 && $gaps == 0 ]] || fail "across files: $msgs of 350 messages, $gaps gaps"
[[ $(json "$WORK/all.json" 'd["problems"]') == 0 ]] || fail "problems: $(cat "$WORK/all.json")"
echo "PASS: rotation by size and by time, every file readable, nothing lost"
