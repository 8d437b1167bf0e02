#!/usr/bin/env bash
# spindown-logger's retention on a nearly full disk (issue 31): a 3 MB tmpfs that the test makes
# in a private mount namespace, and a --keep-mb budget (50 MB) far above the free space, so the
# budget alone never deletes anything. Traffic of about twice the disk's size, rotating at
# 0.25 MB: before an event would be lost to the full disk, the logger deletes its own oldest
# files. Judged against what was sent:
#  - no event is lost (events_lost 0, no "No space left on device", exit code 0);
#  - its heartbeat counts the files it deleted to make room (files_deleted_for_space > 0);
#  - the files left are its newest, read without a problem, and end with the last sample sent,
#    with no gap in what they hold;
#  - a file that is not its own (a note in the same directory) is left alone.
SPINDOWN_NEED_MOUNT_NS=1
source "$(dirname "$0")/logger_common.bash"

disk=$WORK/disk
mkdir "$disk"
mount -t tmpfs -o size=3m tmpfs "$disk"
trap 'umount "$disk" 2>/dev/null; cleanup' EXIT
echo "not a log" >"$disk/notes.txt"

start_logger full --lcm-url "$URL" --dir "$disk" --prefix lab --rotate-size 0.25 --keep-mb 50 \
  --flush-interval 0.1
wait_for_log "$disk"
N=50000
"$BIN/spindown-lcm-publish" --lcm-url "$URL" --bench ret --count $N --rate 5000 >/dev/null
sleep 0.5
stop_logger "$LOGGER_PID"
cat "$WORK/full.err"
[[ $LOGGER_RC == 0 ]] || fail "logger exited with $LOGGER_RC (events lost?)"
! grep -q "No space left on device" "$WORK/full.err" || fail "the disk filled up: events were lost"
sent_bytes=$(awk '/spindown-logger: stopped:/ {for (i = 1; i <= NF; ++i) if ($(i+1) == "bytes") print $i}' "$WORK/full.err")
disk_bytes=$((3 * 1024 * 1024))
((sent_bytes > disk_bytes * 3 / 2)) || fail "only $sent_bytes bytes logged: not enough to fill the $disk_bytes-byte disk"
grep -q "to make room on a disk about to fill" "$WORK/full.err" || fail "no file deleted to make room"
[[ -e $disk/notes.txt ]] || fail "retention deleted notes.txt, which is not the logger's own"

mapfile -t left < <(ls "$disk" | grep -E '^lab-[0-9]{4}-[0-9]{2}-[0-9]{2}-[0-9]{6}(\.[0-9]+)?\.lcm$' | sort)
((${#left[@]} >= 2)) || fail "only ${#left[@]} files left"
"$BIN/spindown-log-summary" "${left[@]/#/$disk/}" >"$WORK/left.json" || fail "spindown-log-summary"
python3 - "$WORK/left.json" "$N" <<'PY' || fail "the files left"
import json, sys
d = json.load(open(sys.argv[1])); n = int(sys.argv[2])
b = d["benches"]["ret"]
assert d["problems"] == 0, d["problems"]
assert b["next_seq"] == n and b["gaps"] == 0, b
last = d["files"][-1]["last_logger_status"]
c = last["counters"]
assert c["events_lost"] == 0 and c["write_errors"] == 0, c
assert c["files_deleted_for_space"] > 0 and c["files_deleted_for_space"] == c["files_deleted"], c
print(f"ok: {n} samples sent; 0 events lost; {c['files_deleted_for_space']} old files deleted to make room "
      f"({c['bytes_deleted']} bytes); the {len(d['files'])} files left hold seq {b['first_seq']}..{b['next_seq'] - 1} "
      f"without a gap")
PY
echo "PASS: retention frees the logger's own oldest files before an event is lost to a full disk"
