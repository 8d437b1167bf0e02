#!/usr/bin/env bash
# spindown-logger retention with the real logger rotating by size under real traffic:
#  --keep-files 3: of the many files it wrote only the 3 newest are left (the one it was writing
#    last among them, intact), the older ones deleted oldest first; the files that are not its
#    own (another prefix, another bench, a note) are untouched; its heartbeat counts the deletions.
#  --keep-mb: what is left of its own files stays within the budget plus the file being written.
source "$(dirname "$0")/logger_common.bash"

# own_files DIR: the logger's own files there (PREFIX lab), sorted by name.
own_files() { ls "$1" | grep -E '^lab-[0-9]{4}-[0-9]{2}-[0-9]{2}-[0-9]{6}(\.[0-9]+)?\.lcm$' | sort; }

# --- keep N files ------------------------------------------------------------------------------
mkdir "$WORK/n"
echo "not a log" >"$WORK/n/notes.txt"
: >"$WORK/n/other-2020-01-01-000000.lcm"
: >"$WORK/n/lab-2020-01-01-000000-b1.lcm"   # a bench logger's file: another logger's
start_logger n --lcm-url "$URL" --dir "$WORK/n" --prefix lab --rotate-size 0.05 --keep-files 3
wait_for_log "$WORK/n"
N=3000
"$BIN/spindown-lcm-publish" --lcm-url "$URL" --bench ret --count $N --rate 5000 >/dev/null
stop_logger "$LOGGER_PID"
[[ $LOGGER_RC == 0 ]] || fail "logger exited with $LOGGER_RC: $(cat "$WORK/n.err")"
mapfile -t wrote < <(sed -n 's/^spindown-logger: wrote //p' "$WORK/n.err")
mapfile -t left < <(own_files "$WORK/n")
echo "keep 3: wrote ${#wrote[@]} files, ${#left[@]} left"
(( ${#wrote[@]} >= 6 )) || fail "want >= 6 files of 0.05 MB for ~330 kB, got ${#wrote[@]}"
(( ${#left[@]} == 3 )) || fail "want 3 files left, got ${#left[@]}: ${left[*]}"
# The 3 left are the last 3 written (the last one being the file open at the end).
want=$(for f in "${wrote[@]: -3}"; do basename "$f"; done | sort)
[[ $(printf '%s\n' "${left[@]}") == "$want" ]] || fail "left ${left[*]}, want the last three written: ${wrote[*]: -3}"
last_written=$(basename "${wrote[-1]}")
for f in notes.txt other-2020-01-01-000000.lcm lab-2020-01-01-000000-b1.lcm; do
  [[ -e $WORK/n/$f ]] || fail "retention deleted $f, which is not the logger's own"
done
grep -q "retention deleted $(( ${#wrote[@]} - 3 )) files" "$WORK/n.err" || fail "stderr: $(tail -3 "$WORK/n.err")"
# The file written last is whole: it ends with the logger's closing status, and nothing of the
# newest messages is lost (the last seq published is in it).
"$BIN/spindown-log-summary" "$WORK/n/$last_written" >"$WORK/last.json"
[[ $(json "$WORK/last.json" 'd["problems"]') == 0 ]] || fail "last file: $(cat "$WORK/last.json")"
[[ $(json "$WORK/last.json" 'd["files"][0]["last_logger_status"]["state"]') == stopped ]] || fail "last file not closed"
deleted=$(json "$WORK/last.json" 'd["files"][0]["last_logger_status"]["counters"]["files_deleted"]')
[[ $deleted == $(( ${#wrote[@]} - 3 )) ]] || fail "closing status says files_deleted=$deleted, want $(( ${#wrote[@]} - 3 ))"
"$BIN/spindown-log-summary" "${left[@]/#/$WORK/n/}" >"$WORK/left.json"
next_seq=$(json "$WORK/left.json" 'd["benches"]["ret"]["next_seq"]')
gaps=$(json "$WORK/left.json" 'd["benches"]["ret"]["gaps"]')
[[ $next_seq == "$N" && $gaps == 0 ]] ||
  fail "the files left do not end with the newest sample (seq $((N - 1))) without gaps: next seq $next_seq, $gaps gaps"

# --- keep MB ---------------------------------------------------------------------------------
mkdir "$WORK/mb"
start_logger mb --lcm-url "$URL" --dir "$WORK/mb" --prefix lab --rotate-size 0.05 --keep-mb 0.12
wait_for_log "$WORK/mb"
"$BIN/spindown-lcm-publish" --lcm-url "$URL" --bench ret --count $N --rate 5000 >/dev/null
stop_logger "$LOGGER_PID"
[[ $LOGGER_RC == 0 ]] || fail "logger exited with $LOGGER_RC: $(cat "$WORK/mb.err")"
mapfile -t left < <(own_files "$WORK/mb")
total=0
for f in "${left[@]}"; do total=$(( total + $(stat -c %s "$WORK/mb/$f") )); done
echo "keep 0.12 MB: ${#left[@]} files, $total bytes left"
(( ${#left[@]} >= 2 )) || fail "only ${#left[@]} files left"
# At the last prune (when the last file opened) the rest fitted 120 kB; the last file has grown
# since by at most the rotation size (+ its closing status event).
(( total <= 120000 + 52000 )) || fail "$total bytes left with --keep-mb 0.12"
[[ -n $(grep "retention deleted" "$WORK/mb.err") ]] || fail "nothing deleted: $(tail -3 "$WORK/mb.err")"

# --- bad values --------------------------------------------------------------------------------
rc=0; "$BIN/spindown-logger" --lcm-url "$URL" --dir "$WORK" --keep-files 1 2>"$WORK/bad.err" || rc=$?
[[ $rc == 2 ]] && grep -q "keep files 1" "$WORK/bad.err" || fail "--keep-files 1: exit $rc: $(cat "$WORK/bad.err")"
echo "PASS: retention keeps the newest files within the limits, never the file being written nor others' files"
