#!/usr/bin/env bash
# spindown-logger's errors are clear: bad usage exits 2; a missing directory, a file given as
# the directory and a read-only file system exit 1 naming the path and the errno text; a disk
# that fills up (a 64 kB tmpfs) is reported on stderr and in the heartbeat (state "disk full",
# write_errors, last_error with the path and "No space left on device"), the logger keeps that
# one file, cut at its last whole event (no damage at its end, no new empty files), and the
# exit code is 1. (Space coming back: logger_disk_full.sh.)
SPINDOWN_NEED_MOUNT_NS=1
source "$(dirname "$0")/logger_common.bash"

expect_error() {  # expect_error RC TEXT ARGS...: the logger exits with RC and TEXT on stderr
  local want_rc=$1 text=$2; shift 2
  local rc=0
  timeout 10 "$BIN/spindown-logger" --lcm-url "$URL" "$@" >"$WORK/err.out" 2>"$WORK/err.txt" || rc=$?
  [[ $rc == "$want_rc" ]] || fail "spindown-logger $*: exit $rc, want $want_rc ($(cat "$WORK/err.txt"))"
  grep -qF -- "$text" "$WORK/err.txt" || fail "spindown-logger $*: stderr lacks '$text': $(cat "$WORK/err.txt")"
  echo "ok: exit $rc: $(head -1 "$WORK/err.txt")"
}

expect_error 2 "rotate-size" --rotate-size -1
expect_error 2 "bench id" --bench "not a bench"
expect_error 1 "$WORK/missing/spindown-" --dir "$WORK/missing"
grep -qF "No such file or directory" "$WORK/err.txt" || fail "no errno text: $(cat "$WORK/err.txt")"
touch "$WORK/plainfile"
expect_error 1 "Not a directory" --dir "$WORK/plainfile"
mkdir "$WORK/ro"
mount -t tmpfs -o ro,size=64k tmpfs "$WORK/ro"
expect_error 1 "Read-only file system" --dir "$WORK/ro"
grep -qF "$WORK/ro/spindown-" "$WORK/err.txt" || fail "path not named: $(cat "$WORK/err.txt")"

# A disk that fills up while logging.
mkdir "$WORK/full"
mount -t tmpfs -o size=64k tmpfs "$WORK/full"
"$BIN/spindown-bridge-tap" --bench logger --lcm-url "$URL" --status "$WORK/status.jsonl" --timeout 30 \
  --ready "$WORK/tap.ready" 2>/dev/null &
tap=$!
PIDS+=("$tap")
start_logger full --lcm-url "$URL" --dir "$WORK/full" --flush-interval 0.1
wait_for_log "$WORK/full"
"$BIN/spindown-lcm-publish" --lcm-url "$URL" --bench disk --count 3000 --rate 2000 >/dev/null
sleep 1.5   # a heartbeat after the error
stop_logger "$LOGGER_PID"
kill -TERM "$tap"; wait "$tap" || true
[[ $LOGGER_RC == 1 ]] || fail "disk full: logger exit $LOGGER_RC, want 1"
grep -q "No space left on device" "$WORK/full.err" || fail "disk full not on stderr: $(cat "$WORK/full.err")"
grep -qF "$WORK/full/spindown-" "$WORK/full.err" || fail "path not named on stderr: $(cat "$WORK/full.err")"
echo "ok: disk full: $(grep -m1 "No space" "$WORK/full.err")"
python3 - "$WORK/status.jsonl" <<'PY'
import json, sys
beats = [json.loads(l) for l in open(sys.argv[1]) if l.strip()]
assert beats, "no heartbeat received on SPINDOWN.logger.STATUS"
bad = [b for b in beats if b["counters"].get("write_errors", 0) > 0]
assert bad, f"no heartbeat with write_errors > 0 in {len(beats)} beats"
last = bad[-1]
assert "No space left on device" in last["last_error"], last["last_error"]
assert last["counters"]["drops"] > 0, last["counters"]
assert any(b["state"] == "disk full" for b in bad), "no heartbeat in state 'disk full'"
print(f"ok: heartbeat: write_errors {last['counters']['write_errors']}, drops {last['counters']['drops']}, "
      f"events {last['counters']['events']}, last_error '{last['last_error']}'")
PY
files=("$WORK"/full/*.lcm)
[[ ${#files[@]} == 1 ]] || fail "${#files[@]} log files on the full disk, want 1: $(ls -l "$WORK/full")"
"$BIN/spindown-log-summary" "${files[0]}" >"$WORK/full.json" || fail "the filled log is unreadable"
msgs=$(json "$WORK/full.json" 'd["benches"]["disk"]["messages"]')
(( msgs > 100 )) || fail "only $msgs messages readable from the log that filled the disk"
[[ $(json "$WORK/full.json" 'd["problems"]') == 0 ]] || fail "the log that filled the disk is damaged: $(json "$WORK/full.json" 'd["files"][0]["problem_texts"]')"
echo "ok: one log on the full disk, $msgs messages, no damage at its end"
umount "$WORK/full" "$WORK/ro"
echo "PASS: clear errors for bad usage, missing/unwritable directories and a full disk"
