#!/usr/bin/env bash
# spindown-logger on a disk that is full from the start (a 2 MB tmpfs filled by another file)
# and gets space back while it runs: it keeps ONE log file (no new zero-byte file every second),
# says "No space left on device" with the file's path once, on stderr and in its heartbeat
# (state "disk full"), counts what arrives meanwhile as lost, and when the filler is deleted
# writes on to the same file, which stays a valid LCM log (sync word 0xEDA1DA01 at every event,
# up to its last byte) holding every message sent after space returned.
SPINDOWN_NEED_MOUNT_NS=1
source "$(dirname "$0")/logger_common.bash"

disk=$WORK/disk
mkdir "$disk"
mount -t tmpfs -o size=2m tmpfs "$disk"
head -c 4M /dev/zero >"$disk/filler" 2>/dev/null || true  # stops at ENOSPC
free_kb=$(df -k --output=avail "$disk" | tail -1)
(( free_kb == 0 )) || fail "the tmpfs still has $free_kb kB free after the filler"

"$BIN/spindown-bridge-tap" --bench logger --lcm-url "$URL" --status "$WORK/status.jsonl" --timeout 60 \
  --ready "$WORK/tap.ready" 2>/dev/null &
PIDS+=($!)
for _ in $(seq 100); do [[ -e "$WORK/tap.ready" ]] && break; sleep 0.05; done
start_logger full --lcm-url "$URL" --dir "$disk" --flush-interval 0.1
wait_for_log "$disk"
"$BIN/spindown-lcm-publish" --lcm-url "$URL" --bench while-full --count 300 --rate 100 >/dev/null
sleep 1.2  # a heartbeat after the last of them
grep -q '"state":"disk full"' "$WORK/status.jsonl" || fail "no heartbeat with state 'disk full': $(tail -1 "$WORK/status.jsonl")"
n=$(compgen -G "$disk/*.lcm" | wc -l)
[[ $n == 1 ]] || fail "$n log files while the disk is full, want 1: $(ls -l "$disk")"
echo "ok: disk full for 4 s: 1 log file, heartbeat state 'disk full'"

rm "$disk/filler"
for _ in $(seq 100); do grep -q "space is back" "$WORK/full.err" && break; sleep 0.05; done
grep -q "space is back" "$WORK/full.err" || fail "no 'space is back' within 5 s of deleting the filler: $(cat "$WORK/full.err")"
"$BIN/spindown-lcm-publish" --lcm-url "$URL" --bench after --count 200 --rate 200 >/dev/null
sleep 1.2
stop_logger "$LOGGER_PID"

[[ $LOGGER_RC == 1 ]] || fail "logger exit $LOGGER_RC, want 1 (events were lost)"
cat "$WORK/full.err"
files=("$disk"/*.lcm)
[[ ${#files[@]} == 1 ]] || fail "${#files[@]} log files, want 1: $(ls -l "$disk")"
log=${files[0]}
n=$(grep -c "No space left on device" "$WORK/full.err")
[[ $n == 2 ]] || fail "'No space left on device' said $n times on stderr, want once (and once in the exit summary)"
grep -qF "writing $log: No space left on device" "$WORK/full.err" || fail "stderr does not name $log with ENOSPC"
python3 - "$WORK/status.jsonl" "$log" <<'PY'
import json, sys
beats = [json.loads(l) for l in open(sys.argv[1]) if l.strip()]
full = [b for b in beats if b["state"] == "disk full"]
assert full, "no heartbeat in state 'disk full'"
b = full[-1]
assert f"writing {sys.argv[2]}: No space left on device" in b["last_error"], b["last_error"]
assert b["counters"]["write_errors"] == 1 and b["counters"]["disk_full_episodes"] == 1, b["counters"]
assert b["counters"]["events_lost"] >= 300, b["counters"]
after = beats[beats.index(b) + 1:]
assert any(x["state"] == "running" for x in after), "no heartbeat back in state 'running'"
print(f"ok: heartbeat: state 'disk full', events_lost {b['counters']['events_lost']}, then 'running'")
PY
# The file, parsed here from the event log format: every event starts with the sync word and
# the last one ends at the file's last byte.
python3 - "$log" <<'PY'
import struct, sys
data = open(sys.argv[1], "rb").read()
off, channels = 0, {}
while off < len(data):
    sync, num, utime, clen, dlen = struct.unpack_from(">IqqII", data, off)
    assert sync == 0xEDA1DA01, f"no sync word at byte {off}"
    ch = data[off + 28:off + 28 + clen].decode()
    channels[ch] = channels.get(ch, 0) + 1
    off += 28 + clen + dlen
assert off == len(data), f"the last event runs past the end ({off} > {len(data)})"
print(f"ok: {len(data)} bytes, {sum(channels.values())} whole events: {channels}")
PY
"$BIN/spindown-log-summary" "$log" >"$WORK/log.json" || fail "spindown-log-summary cannot read $log"
[[ $(json "$WORK/log.json" 'd["problems"]') == 0 ]] || fail "problems in $log: $(cat "$WORK/log.json")"
[[ $(json "$WORK/log.json" 'd["benches"]["after"]["messages"]') == 200 ]] ||
  fail "want all 200 messages sent after space returned: $(json "$WORK/log.json" 'd["benches"]')"
[[ $(json "$WORK/log.json" '"while-full" in d["benches"]') == False ]] || fail "messages sent while full are in the log"
[[ $(json "$WORK/log.json" 'd["files"][0]["first_logger_status"]["state"]') == resumed ]] ||
  fail "the log does not open with the 'resumed' status event: $(json "$WORK/log.json" 'd["files"][0]["first_logger_status"]')"
# The log holds test messages, no spin-down: exit 1 ("no spin-down run found") is its answer;
# anything else (a crash, bad usage) fails.
rc=0; "$BIN/spindown" refit "$log" >"$WORK/refit.out" 2>&1 || rc=$?
((rc <= 1)) || fail "spindown refit exited $rc: $(cat "$WORK/refit.out")"
! grep -qiE "truncated or damaged|not an LCM event" "$WORK/refit.out" || fail "spindown refit: $(cat "$WORK/refit.out")"
timeout 20 lcm-logplayer --lcm-url "udpm://239.255.76.68:7668?ttl=0" -s 100 "$log" >"$WORK/player.out" 2>&1 ||
  fail "lcm-logplayer rejects $log: $(cat "$WORK/player.out")"
echo "ok: one valid log (log-summary, spindown refit and lcm-logplayer read it), 200 of 200 messages after space returned"
umount "$disk"
echo "PASS: a full disk keeps one valid log and writes on to it when space returns"
