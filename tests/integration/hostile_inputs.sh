#!/usr/bin/env bash
# Hostile inputs: what `spindown fit` (text files) and `spindown refit` (LCM logs) do with each.
# Every case must exit with its code (never a crash, hang or sanitizer report), say its key
# phrase on stderr naming the file, give valid JSON with the same exit code under --json, and
# agree with its row in docs/hostile-inputs.md, so the table cannot go stale.
# Also: several files where one is bad: the others are still reported, exit 1.
#
# Usage: hostile_inputs.sh               check (ctest runs this)
#        hostile_inputs.sh --write-doc   rewrite docs/hostile-inputs.md from real runs
set -euo pipefail
src="${SPINDOWN_SOURCE_DIR:-$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)}"
bin="${SPINDOWN_BIN_DIR:-$src/build/bin}/spindown"
data="${SPINDOWN_SAMPLE_DATA:-$src/data}"
doc="$src/docs/hostile-inputs.md"
write_doc=0
[[ "${1:-}" == "--write-doc" ]] && write_doc=1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cd "$tmp"

# Text files: a lab-like coast (combined friction, 20 ms loop) printed as the sketch does, and
# damaged versions of it. LCM logs: the same coast in samples_t messages of 50 samples after a
# config_t, encoded here with the fingerprints of the seed corpus's messages (fuzz/corpus).
python3 - "$src" <<'PY'
import math, os, random, struct, sys
src = sys.argv[1]
def coast(gain=1.0, n=1500):
    rows = []
    for i in range(n):
        t = 5000 + 20 * i
        tau = (i - 150) * 0.02
        w = 0.0 if i < 150 else max(0.0, (346 + 1011) * math.exp(-0.0162 * tau) - 1011)
        rows.append((t, gain * w / 123.569311))
    return rows
def fmt(v): return v if isinstance(v, str) else f"{v:.2f}"
def write(name, rows, endings=("\r\n",)):
    with open(name, "wb") as f:
        for k, (t, v) in enumerate(rows):
            f.write(f"{t}\t{fmt(v)}{endings[k % len(endings)]}".encode())
rows = coast()
write("good.tsv", rows)
open("empty.tsv", "wb").close()
random.seed(6)
open("binary.bin", "wb").write(bytes(random.randrange(256) for _ in range(4096)))
write("zeros.tsv", [(t, 0.0) for t, _ in rows])
write("three.tsv", [(1000, 2.5), (1020, 2.4), (1040, 2.3)])
write("nan_inf.tsv", [(t, {300: "nan", 400: "NaN", 500: "inf", 600: "-inf"}.get(k, v)) for k, (t, v) in enumerate(rows)])
write("backwards.tsv", [(t - 300 if 700 <= k < 710 else t, v) for k, (t, v) in enumerate(rows)])
# Back-EMF above the converter's 5 V: the reading sits at 5.00 V until the motor slows.
write("clipped.tsv", [(t, min(v, 5.0)) for t, v in coast(gain=2.2)])
write("mixed_endings.tsv", rows, endings=("\r\n", "\n", "\r"))
with open("long_line.tsv", "wb") as f:
    for k, (t, v) in enumerate(rows):
        if k == 50: f.write(b"x" * (1 << 20) + b"\r\n")
        f.write(f"{t}\t{fmt(v)}\r\n".encode())
write("millis_wrap.tsv", [((2**32 - 12000 + 20 * k) % 2**32, v) for k, (_, v) in enumerate(rows)])
dup = []
for k, (t, v) in enumerate(rows):
    dup.append((t, v))
    if 400 <= k < 410: dup.append((t, v))
write("duplicates.tsv", dup)
# 9 s into the coast the device clock jumps 3 s while the readings go on; or logging stops for a day.
write("clock_jump.tsv", [(t + (3000 if k >= 600 else 0), v) for k, (t, v) in enumerate(rows)])
write("day_gap.tsv", [(t + (86400000 if k >= 600 else 0), v) for k, (t, v) in enumerate(rows)])
with open("latin1.tsv", "wb") as f:
    f.write(b"=~=~=~=~=~=~=~=~=~=~=~= PuTTY log 2023.09.14 10:21:33 =~=~=~=~=~=~=~=~=~=~=~=\r\n")
    f.write("Messung Motor Nr. 3 \xb5C gestartet \xe4\xf6\xfc\r\n".encode("latin-1"))
    for k, (t, v) in enumerate(rows):
        if k == 20: f.write(b"\xff\xfe\xc3\x28\t\xa0\r\n")
        f.write(f"{t}\t{fmt(v)}\r\n".encode())

# The messages below are laid out as logs before issue 31's appended fields hold them (refit
# still reads that layout): its fingerprints, samples_t's also in fuzz/corpus/fuzz_samples_t/legacy.
SAMPLES, CONFIG = bytes.fromhex("6366464c24ab26e1"), bytes.fromhex("f282fe9dc33677bc")
def s(x): b = x.encode() + b"\0"; return struct.pack(">i", len(b)) + b
def samples_msg(seq, part, n_claimed=None):
    b = SAMPLES + struct.pack(">q", 1694686893000000 + seq * 20000) + s("bench-a") + struct.pack(">qib", seq, 0, 0)
    b += struct.pack(">i", len(part) if n_claimed is None else n_claimed)
    b += b"".join(struct.pack(">q", t * 1000) for t, _ in part)
    b += b"".join(struct.pack(">q", 1694686893000000 + t * 1000) for t, _ in part)
    b += b"".join(struct.pack(">d", round(v, 2)) for _, v in part)
    b += b"".join(struct.pack(">i", -1) for _ in part)
    return b
def config_msg():
    return (CONFIG + struct.pack(">q", 1694686893000000) + s("bench-a") + struct.pack(">d", 1.2e-5) + s("lab default")
            + struct.pack(">d", 0.0081) + s("lab default") + struct.pack(">bdi", 0, 5 / 1023, 10) + s("lab sketch")
            + s("lab-tsv") + struct.pack(">di", 0.02, 9600) + s("/dev/ttyACM0") + s("lab-pc"))
def event(num, channel, data):
    c = channel.encode()
    return struct.pack(">IqqII", 0xEDA1DA01, num, 1694686893000000 + num * 1000000, len(c), len(data)) + c + data
def log(name, events):
    with open(name, "wb") as f:
        for k, (ch, d) in enumerate(events): f.write(event(k, ch, d))
chunks = [(seq, rows[seq:seq + 50]) for seq in range(0, len(rows), 50)]
good = [("SPINDOWN.bench-a.CONFIG", config_msg())] + [("SPINDOWN.bench-a.SAMPLE", samples_msg(q, p)) for q, p in chunks]
log("good.lcmlog", good)
data = open("good.lcmlog", "rb").read()
open("truncated.lcmlog", "wb").write(data[:len(data) - 600])
log("fingerprint.lcmlog", good[:10] + [("SPINDOWN.bench-a.SAMPLE", config_msg())] + good[10:])
log("wrong_channel.lcmlog", [("SPINDOWN.bench-a.SAMPLES" if ch.endswith("SAMPLE") else ch, d) for ch, d in good])
q, p = chunks[9]
log("mismatched.lcmlog", good[:10] + [("SPINDOWN.bench-a.SAMPLE", samples_msg(q, p, n_claimed=len(p) + 7))] + good[11:])
with open("garbage_between.lcmlog", "wb") as f:
    for k, (ch, d) in enumerate(good):
        f.write(event(k, ch, d))
        if k == 12: f.write(b"\0" * 300 + b"noise")
open("empty.lcmlog", "wb").close()
# What Windows hands in: a workbook instead of text, a German Excel's CSV (Windows-1252, ';',
# decimal commas, its empty rows), a log closed with DOS's Ctrl-Z.
import io, zipfile
book = io.BytesIO()
with zipfile.ZipFile(book, "w", zipfile.ZIP_DEFLATED) as z:
    z.writestr("[Content_Types].xml", '<?xml version="1.0"?><Types/>')
    z.writestr("xl/workbook.xml", '<?xml version="1.0"?><workbook/>')
    z.writestr("xl/worksheets/sheet1.xml", "<worksheet>" + "".join(f"<row><c><v>{t}</v></c></row>" for t, _ in rows) + "</worksheet>")
open("workbook.xlsx", "wb").write(book.getvalue())
with open("excel_de.csv", "wb") as f:
    f.write("Zeit [\u00b5s];Spannung [V];Bemerkung\r\n".encode("cp1252"))
    for t, v in rows: f.write(f"{t * 1000};{fmt(v).replace('.', ',')};\r\n".encode("cp1252"))
    f.write(b";;\r\n" * 5)
with open("ctrl_z.tsv", "wb") as f:
    for t, v in rows: f.write(f"{t}\t{fmt(v)}\r\n".encode())
    f.write(b"\x1a")
PY
mkdir a_directory
mkfifo fifo_no_writer

# input | command | file | exit | key phrase (ERE, case-insensitive, on stderr+stdout)
cases=(
  "empty file|fit|empty.tsv|1|the file is empty"
  "binary file (4 KiB random bytes)|fit|binary.bin|1|binary data"
  "zeros only (1500 samples at 0.00 V)|fit|zeros.tsv|1|no spin-down"
  "3 samples|fit|three.tsv|1|no spin-down"
  "NaN and ±inf values|fit|nan_inf.tsv|0|NaN or infinite"
  "time going backwards (10 lines)|fit|backwards.tsv|0|time goes back"
  "back-EMF clipped at 5 V|fit|clipped.tsv|0|pinned at 5"
  "CR LF, LF and lone CR mixed|fit|mixed_endings.tsv|0|best: "
  "a 1 MiB line|fit|long_line.tsv|0|line too long"
  "millis() wrapping at 2^32 mid-coast|fit -v|millis_wrap.tsv|0|wrapped"
  "duplicate timestamps (10 lines twice)|fit|duplicates.tsv|0|duplicate line"
  "device clock jumping 3 s mid-coast, readings going on|fit|clock_jump.tsv|0|device clock jumped"
  "a day without samples mid-coast|fit|day_gap.tsv|0|cut short there"
  "non-UTF-8 bytes (Latin-1 line, invalid sequences)|fit|latin1.tsv|0|not a number"
  "an Excel workbook (.xlsx) instead of text|fit|workbook.xlsx|1|an Excel workbook"
  "a German Excel's CSV (Windows-1252, ';', decimal commas, ';;' rows)|fit|excel_de.csv|0|best: "
  "a trailing Ctrl-Z (DOS end of file)|fit|ctrl_z.tsv|0|best: "
  "a directory|fit|a_directory|1|it is a directory"
  "a missing file|fit|missing.tsv|1|No such file"
  "a FIFO with no writer|fit|fifo_no_writer|1|the file is empty"
  "/dev/null|fit|/dev/null|1|the file is empty"
  "sound LCM log (reference)|refit|good.lcmlog|0|best: "
  "truncated LCM log (last event cut)|refit|truncated.lcmlog|0|truncated or damaged"
  "wrong-fingerprint message on a SAMPLE channel|refit|fingerprint.lcmlog|0|not a samples_t"
  "samples on the wrong channel (…SAMPLES)|refit|wrong_channel.lcmlog|1|no samples on SPINDOWN"
  "sample count larger than the arrays sent|refit|mismatched.lcmlog|0|sample count 57 does not fit"
  "garbage between log events|refit|garbage_between.lcmlog|0|not an LCM event"
  "empty LCM log|refit|empty.lcmlog|1|no samples on SPINDOWN"
  "a text file given to refit|refit|good.tsv|1|not an LCM event"
  "a directory given to refit|refit|a_directory|1|it is a directory"
  "a FIFO given to refit|refit|fifo_no_writer|1|not a regular file"
  "/dev/null given to refit|refit|/dev/null|1|not a regular file"
)

fail=0
rows=()
# The table's cells for a case, '|' escaped for markdown.
md() { sed -e 's/|/\\|/g' <<<"$1"; }

for c in "${cases[@]}"; do
  IFS='|' read -r what cmd file want phrase <<<"$c"
  read -r -a argv <<<"$cmd"
  rc=0
  timeout 60 "$bin" "${argv[@]}" "$file" >out.txt 2>err.txt || rc=$?
  if ((rc >= 124)); then
    echo "FAIL $what: crashed or hung (exit $rc)"; head -20 err.txt; fail=1; continue
  fi
  ((rc == want)) || { echo "FAIL $what: exit $rc, want $want"; head -5 err.txt; fail=1; }
  if grep -qE "AddressSanitizer|runtime error|LeakSanitizer" err.txt; then echo "FAIL $what: sanitizer report"; fail=1; fi
  if [[ -s err.txt ]] && ! grep -qF -- "$file" err.txt; then echo "FAIL $what: stderr does not name $file"; fail=1; fi
  message=$(cat err.txt out.txt | grep -iE -m1 -- "$phrase" || true)
  [[ -n "$message" ]] || { echo "FAIL $what: no /$phrase/ in the output"; head -5 err.txt; fail=1; }
  # JSON: the same exit code and one valid object; what was kept comes from it.
  rc_json=0
  timeout 60 "$bin" "${argv[0]}" --json "$file" >out.json 2>/dev/null || rc_json=$?
  kept=$(python3 - out.json <<'PY' 2>/dev/null || echo "INVALID JSON"
import json, sys
f = json.load(open(sys.argv[1]))["files"][0]
runs = len(f["runs"])
print(f'{f["samples_read"]} samples, {runs} run{"s" if runs != 1 else ""} fitted')
PY
)
  if ((rc_json != want)) || [[ "$kept" == "INVALID JSON" ]]; then
    echo "FAIL $what: --json exit $rc_json or invalid JSON"; fail=1
  fi
  message=${message//$tmp\//}
  ((${#message} > 160)) && message="${message:0:157}…"
  rows+=("| $(md "$what") | \`spindown $cmd\` | $want | \`$(md "$message")\` | $kept |")
  echo "ok $what (exit $rc): $message [$kept]"

  if ((!write_doc)); then
    # The documented row for this input must show the same exit code and the key phrase.
    row=$(grep -F -- "| $(md "$what") |" "$doc" 2>/dev/null | head -1 || true)
    doc_exit=$(awk -F' \\| ' '{print $3}' <<<"$row")
    doc_msg=$(awk -F' \\| ' '{print $4}' <<<"$row" | sed -e 's/\\|/|/g')
    if [[ -z "$row" || "$doc_exit" != "$want" ]] || ! grep -qiE -- "$phrase" <<<"$doc_msg"; then
      echo "FAIL $what: docs/hostile-inputs.md is stale (run tests/integration/hostile_inputs.sh --write-doc)"
      fail=1
    fi
  fi
done

# Several files, one bad: the good ones are still reported, the exit code says one was not used.
rc=0
timeout 60 "$bin" fit good.tsv empty.tsv "$data/seed-3v-run1.tsv" >out.txt 2>err.txt || rc=$?
if ((rc != 1)); then echo "FAIL mixed files: exit $rc, want 1"; fail=1; fi
if (($(grep -c "best: " out.txt) != 2)); then echo "FAIL mixed files: want two fitted files"; cat out.txt; fail=1; fi
grep -qF "empty.tsv: error: not used" err.txt || { echo "FAIL mixed files: no reason for empty.tsv"; fail=1; }
rc=0
timeout 60 "$bin" fit --json good.tsv empty.tsv "$data/seed-3v-run1.tsv" >out.json 2>/dev/null || rc=$?
if ((rc != 1)) || ! python3 - out.json <<'PY'
import json, sys
files = json.load(open(sys.argv[1]))["files"]
assert [len(f["runs"]) for f in files] == [1, 0, 1], [len(f["runs"]) for f in files]
assert files[1]["failures"] and not files[0]["failures"]
PY
then echo "FAIL mixed files --json: exit $rc"; fail=1; fi
echo "ok mixed files (exit 1)"

# Live, on the network: one 1 kB datagram whose LCM fragment header claims a 100 MB message.
# LCM 1.3.1 (lcm_udpm.c) takes the claimed size as it is, up to LCM_MAX_MESSAGE_SIZE (256 MB):
# it mallocs a fragment buffer that large (address space only: untouched pages cost no memory)
# and, when the header also claims that this is the message's only fragment, delivers it at
# once: a 100 MB message, zeros past the first kB. Claiming more fragments, the buffer waits
# for fragments that never come until later ones evict it: nothing is delivered and LCM says
# nothing (its "rejecting huge message" is a debug print, for claims above 256 MB only).
# spindown-fitter must name the delivered one as too large for its queue (before: "receive
# queue full"), say nothing of the other, and stay small. Private network namespace, ttl=0.
if ! unshare -n true 2>/dev/null; then
  echo "skip forged fragment header: cannot create a network namespace (unshare -n)"
elif ! unshare -n bash -s -- "$(dirname "$bin")" "$tmp" <<'LIVE'; then fail=1; fi
set -euo pipefail
B=$1 T=$2
ip link set lo up
ip route add 224.0.0.0/4 dev lo
URL='udpm://239.255.76.67:7667?ttl=0'
"$B/spindown-bridge-tap" --bench fitter --lcm-url "$URL" --status "$T/fitter.status.jsonl" --timeout 30 \
  --ready "$T/tap.ready" </dev/null 2>/dev/null &
tap=$!
"$B/spindown-fitter" --lcm-url "$URL" --status-period 0.2 </dev/null 2>"$T/fitter.err" &
fitter=$!
mkdir -p "$T/livelog"
"$B/spindown-logger" --lcm-url "$URL" --dir "$T/livelog" --prefix hostile --flush-interval 0.1 </dev/null \
  2>"$T/logger.err" &
logger=$!
trap 'kill -KILL $tap $fitter $logger 2>/dev/null || true' EXIT
for _ in $(seq 100); do [[ -e "$T/tap.ready" ]] && grep -qs fitter "$T/fitter.status.jsonl" && break; sleep 0.05; done
rss_kb() { awk '/^VmRSS/ {print $2}' "/proc/$fitter/status"; }
# send CLAIMED_FRAGMENTS SEQNO: the forged datagram (header "LC03", seqno, 100 MB, offset 0,
# fragment 0 of CLAIMED_FRAGMENTS, a bench's SAMPLE channel, 1000 bytes).
send() {
  python3 - "$1" "$2" <<'PY'
import socket, struct, sys
s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
s.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_TTL, 0)
s.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_LOOP, 1)
header = struct.pack(">IIIIHH", 0x4C433033, int(sys.argv[2]), 100_000_000, 0, 0, int(sys.argv[1]))
s.sendto(header + b"SPINDOWN.hostile.SAMPLE\0" + b"\x5a" * 1000, ("239.255.76.67", 7667))
PY
}
# last_status EXPR: a Python expression over the fitter's last heartbeat d.
last_status() { python3 -c "import json,sys; d=[json.loads(l) for l in open(sys.argv[1])][-1]; print($1)" "$T/fitter.status.jsonl"; }
rss0=$(rss_kb)
send 65535 1  # 100 MB in 65535 fragments (the most a header can say): only the first ever comes
sleep 0.6
[[ $(last_status 'd["counters"]["oversize_drops"], d["counters"]["queue_drops"], d["last_error"]') == "0 0 " ]] ||
  { echo "FAIL forged fragment header (more fragments claimed): $(last_status 'd["counters"], d["last_error"]')"; exit 1; }
rss1=$(rss_kb)
send 1 2  # 100 MB claimed to be in this one fragment
sleep 0.6
rss2=$(rss_kb)
want="1 messages dropped: larger than the receive queue's limit of 67108864 bytes (last: 100000000 bytes on SPINDOWN.hostile.SAMPLE"
got=$(last_status 'd["last_error"]')
[[ $got == "$want"* && $(last_status 'd["counters"]["oversize_drops"], d["counters"]["queue_drops"]') == "1 0" ]] ||
  { echo "FAIL forged fragment header (one fragment claimed): $(last_status 'd["counters"]["oversize_drops"], d["counters"]["queue_drops"]'), '$got'"; exit 1; }
# A copy of the message would add 100 MB; LCM's own untouched buffer adds nothing (under ASan
# its shadow and poisoning add ~25 MB).
(( rss2 - rss0 < 50000 )) || { echo "FAIL forged fragment header: the fitter grew from $rss0 to $rss2 kB"; exit 1; }
kill -TERM $fitter $logger
wait $fitter
wait $logger
grep -q "0 queue drops, 1 oversize drops" "$T/fitter.err" || { echo "FAIL forged fragment header: stop summary: $(tail -1 "$T/fitter.err")"; exit 1; }
# The logger does not record it: counted and named, the log stays small.
log_bytes=$(stat -c %s "$T"/livelog/*.lcm)
((log_bytes < 1000000)) || { echo "FAIL forged fragment header: the logger wrote $log_bytes bytes"; exit 1; }
grep -q "1 oversize drops" "$T/logger.err" || { echo "FAIL forged fragment header: logger summary: $(tail -2 "$T/logger.err")"; exit 1; }
grep -aq "message of 100000000 bytes on SPINDOWN.hostile.SAMPLE not recorded" "$T"/livelog/*.lcm ||
  { echo "FAIL forged fragment header: the logger's heartbeat does not name the oversize message"; exit 1; }
echo "ok forged fragment header claiming 100 MB: more fragments claimed: nothing delivered, nothing said;" \
  "one claimed: '$got'; fitter VmRSS $rss0 -> $rss1 -> $rss2 kB"
LIVE

if ((write_doc)); then
  ((fail == 0)) || { echo "hostile_inputs.sh: not writing $doc while a case fails" >&2; exit 1; }
  mkdir -p "$(dirname "$doc")"
  {
    cat <<'EOF'
# Hostile inputs

What `spindown fit` (text recordings) and `spindown refit` (LCM logs) do with damaged, strange or
hostile input. Every row is a real run: `tests/integration/hostile_inputs.sh` (a ctest test)
builds each input, checks the exit code, the key phrase of the message (which names the file),
that `--json` gives valid JSON with the same exit code, and that this table still says so.
Regenerate it with `tests/integration/hostile_inputs.sh --write-doc` (uses `build/bin`).

Exit codes: 0 every file was used (warnings say what was skipped), 1 a file (or run) could not
be used, 2 bad usage. "Kept" is from `--json`: samples read and runs fitted. Lines or messages
that are not used are counted and reported, never silently dropped (text in Windows-1252, as the
Latin-1 file below is, is decoded to UTF-8 first; text that mixes UTF-8 with other bytes shows them
as `\xNN`); a text file's diagnostics beyond the first 20 problem lines are summarised as a count.

| Input | Command | Exit | Message (first matching line) | Kept |
|---|---|---|---|---|
EOF
    printf '%s\n' "${rows[@]}"
    cat <<'EOF'

Live, `spindown-fitter` is sent one 1 kB datagram whose LCM fragment header claims a 100 MB
message. LCM 1.3.1 believes the claim (up to 256 MB): claiming more fragments, it waits for
them and delivers nothing; claiming this one fragment, it delivers a 100 MB message at once
(zeros past the first kB). The fitter drops that one and says `1 messages dropped: larger than
the receive queue's limit of 67108864 bytes (last: 100000000 bytes on SPINDOWN.hostile.SAMPLE;
…)`, using no memory for it. spindown-logger does not record it either (`--max-event-bytes`,
8 MiB by default; spindown's messages are a few kB): it counts it in `oversize_drops` and names it
in its heartbeat, and its log stays small.

Below the CLI, the parsers and decoders are fuzzed continuously (`fuzz/`, see README's
"What it promises"); every crash the fuzzers found has a regression case in `tests/` and its
input in `fuzz/corpus/`.
EOF
  } >"$doc"
  echo "wrote $doc"
fi
exit $fail
