# Shared by the avr_bench*.sh integration tests (sourced; not a test itself): the real sketches
# from deploy/firmware, compiled here, on spindown-avr-bench (simavr's ATmega328P), read by the
# real spindown-bridge; spindown-fitter and spindown-logger over LCM in the private network
# namespace that bridge_common.bash makes. Nothing is skipped: deploy/setup --tests installs
# gcc-avr, arduino-core-avr and simavr, and their absence is a failure.
source "$(dirname "${BASH_SOURCE[0]}")/bridge_common.bash"
SRC=${SPINDOWN_SOURCE_DIR:?SPINDOWN_SOURCE_DIR not set}

[[ -x $BIN/spindown-avr-bench ]] ||
  fail "$BIN/spindown-avr-bench was not built (needs libsimavr-dev: deploy/setup --tests, then configure again)"
command -v avr-gcc >/dev/null || fail "avr-gcc missing (deploy/setup --tests installs gcc-avr avr-libc arduino-core-avr)"

# The friction the emulated benches coast with: the lab's bearings ×3, so a coast takes ~9 s.
AVR_PHYSICS=(--viscous 5.5e-7 --coulomb 3.4e-4 --e0 2.8 --noise 0.003 --lead-in-s 2 --tail-s 1.5)

# build_firmware DIR [MAKE VARIABLES...]: both sketches into DIR (lab_sketch.elf, spindown_coast.elf).
build_firmware() {
  local dir=$1
  shift
  timeout 240 make -C "$SRC/deploy/firmware" BUILD="$dir" -j2 "$@" >"$dir.make.log" 2>&1 ||
    { tail -20 "$dir.make.log"; fail "the firmware did not build"; }
}

# start_services: spindown-fitter (-v: one ' fitted: ' line per FIT) and spindown-logger into $WORK/log.
start_services() {
  mkdir -p "$WORK/log"
  "$BIN/spindown-logger" --lcm-url "$LCM_URL" --dir "$WORK/log" --prefix avr --flush-interval 0.2 \
    >"$WORK/logger.out" 2>"$WORK/logger.err" &
  LOGGER=$!; PIDS+=($LOGGER)
  "$BIN/spindown-fitter" --lcm-url "$LCM_URL" -v >"$WORK/fitter.out" 2>"$WORK/fitter.err" &
  FITTER=$!; PIDS+=($FITTER)
  wait_for "grep -q 'fitting benches' '$WORK/fitter.err' && grep -q 'channels' '$WORK/logger.err'" 20 "the fitter and the logger"
}

# stop_services: the fitter, then the logger (drains to its file).
stop_services() {
  kill -TERM "$FITTER"; wait_pid "$FITTER" 10 || fail "fitter exited with $? on SIGTERM"
  sleep 0.5
  kill -TERM "$LOGGER"; wait_pid "$LOGGER" 15 || fail "logger exited with $? on SIGTERM"
}

fits_published() { grep -c ' fitted: ' "$WORK/fitter.err" 2>/dev/null || true; }

# start_avr NAME FIRMWARE [spindown-avr-bench options...]: the emulated board on $WORK/NAME.tty,
# its truth in $WORK/NAME.truth.json; sets AVR_PID.
start_avr() {
  local name=$1 fw=$2
  shift 2
  rm -f "$WORK/$name.tty"
  "$BIN/spindown-avr-bench" --firmware "$fw" --link "$WORK/$name.tty" --truth "$WORK/$name.truth.json" \
    --wait-reader 30 --linger 0.5 "$@" >"$WORK/$name.avr.out" 2>"$WORK/$name.avr.log" &
  AVR_PID=$!; PIDS+=($AVR_PID)
  wait_for "[[ -L '$WORK/$name.tty' ]]" 15 "the emulated board's pty"
}

# start_bridge NAME BAUD: spindown-bridge on $WORK/NAME.tty as bench NAME; sets BRIDGE_PID.
start_bridge() {
  "$BIN/spindown-bridge" --device "$WORK/$1.tty" --bench "$1" --lcm-url "$LCM_URL" --retry --baud "$2" \
    2>>"$WORK/$1.bridge.log" &
  BRIDGE_PID=$!; PIDS+=($BRIDGE_PID)
}

# capture NAME FILE BAUD: what PuTTY does: opens the port once (the board boots), sets 8N1 raw at
# the sketch's rate, and logs every byte after its header line until the board goes away.
# The rate is set on the descriptor just opened, in the same process: the emulated board has no
# bootloader delay and prints as soon as the bench sees the open (polled every 5 ms), so a
# separate `stty` after the open could come late, and the first bytes, read at the pty's default
# rate, were garbled by the bench as a UART at the wrong rate would (seen: 5 garbled chunks at
# the start of the lab sketch's capture).
capture() {
  local tty=$WORK/$1.tty out=$2 baud=$3
  printf '=~=~=~=~=~=~=~=~=~=~=~= PuTTY log 2024.03.05 14:02:11 =~=~=~=~=~=~=~=~=~=~=~=\r\n' >"$out"
  timeout 200 python3 - "$tty" "$baud" >>"$out" 2>/dev/null <<'PY' || true
import os, sys, termios
fd = os.open(sys.argv[1], os.O_RDONLY | os.O_NOCTTY)
speed = getattr(termios, "B" + sys.argv[2])
iflag, oflag, cflag, lflag, _, _, cc = termios.tcgetattr(fd)
# stty raw -echo -hupcl: bytes as sent (no CR/LF translation), 8N1, no hangup on close.
iflag &= ~(termios.IGNBRK | termios.BRKINT | termios.IGNPAR | termios.PARMRK | termios.INPCK | termios.ISTRIP |
           termios.INLCR | termios.IGNCR | termios.ICRNL | termios.IXON | termios.IXOFF | termios.IXANY)
oflag &= ~termios.OPOST
cflag = (cflag & ~(termios.CSIZE | termios.PARENB | termios.HUPCL)) | termios.CS8 | termios.CREAD
lflag &= ~(termios.ECHO | termios.ICANON | termios.IEXTEN | termios.ISIG)
cc[termios.VMIN], cc[termios.VTIME] = 1, 0
termios.tcsetattr(fd, termios.TCSANOW, [iflag, oflag, cflag, lflag, speed, speed, cc])
while True:
    try:
        chunk = os.read(fd, 65536)
    except OSError:  # EIO: the board (the pty's master) went away
        break
    if not chunk:
        break
    while chunk:
        chunk = chunk[os.write(1, chunk):]
PY
}

# check_fits LIVE_JSON TRUTH_JSON [MIN_RUNS]: every run of the truth that coasted whole on one
# device clock has one live FIT whose combined-model c3 and c4 are within 4 standard errors of
# the truth and whose cut is within one sample period of it; a run the board's reset cut short
# has a FIT that ends at the clock restart.
check_fits() {
  python3 - "$@" <<'PY'
import json, sys
live = json.load(open(sys.argv[1])); truth = json.load(open(sys.argv[2]))
min_runs = int(sys.argv[3]) if len(sys.argv) > 3 else 1
fits = [r for f in live["files"] for r in f["runs"]]
ok, problems = 0, []
for tr in truth["runs"]:
    if "cut_device_us" not in tr:
        continue
    cut = tr["cut_device_us"] / 1e6
    restarted = [f for f in fits if f.get("end") == "clock restart"]
    if tr.get("reset_mid_coast"):
        # The board reset mid-coast: the fitter must say the device clock restarted there.
        if not any(abs(f["t_cut_s"] - cut) < 0.5 for f in restarted):
            problems.append(f"run {tr['run']} (reset mid-coast): no fit ends at a clock restart")
        else:
            print(f"  run {tr['run']}: reset mid-coast, fitted up to the clock restart")
        continue
    near = [f for f in fits if f.get("t_cut_s") is not None and abs(f["t_cut_s"] - cut) < 0.5 and f not in restarted]
    if len(near) != 1:
        problems.append(f"run {tr['run']} (cut {cut:.3f} s): {len(near)} fits"); continue
    f = near[0]
    comb = next(m for m in f["models"] if m["name"] == "combined")["params"]
    zs = {}
    for name, key in (("c3", "c_v"), ("c4", "c_c")):
        v, e = comb[name]["value"], comb[name]["total_stderr"]
        zs[name] = (v - truth[key]) / e
    dcut = f["t_cut_s"] - cut
    period = f.get("period_s") or 0.02
    line = (f"run {tr['run']}: c3 {comb['c3']['value']:.4e} ± {comb['c3']['total_stderr']:.1e} (truth {truth['c_v']:.4e}, "
            f"z {zs['c3']:+.2f}), c4 {comb['c4']['value']:.4e} ± {comb['c4']['total_stderr']:.1e} (truth {truth['c_c']:.4e}, "
            f"z {zs['c4']:+.2f}), cut {f['t_cut_s']:.4f} s (truth {cut:.4f} s, {1e3 * dcut:+.1f} ms), best {f['best']}, n {f['samples']}")
    print("  " + line)
    if abs(zs["c3"]) > 4 or abs(zs["c4"]) > 4 or abs(dcut) > period + 0.001:
        problems.append("outside the errors: " + line)
    else:
        ok += 1
if ok < min_runs:
    problems.append(f"{ok} runs matched the truth, want at least {min_runs}")
for p in problems: print("  MISMATCH: " + p)
sys.exit(1 if problems else 0)
PY
}

# same_fits A_JSON B_JSON: the runs' cut, stop, sample count and every model parameter agree
# (the live fitter on LCM vs spindown fit of a capture).
same_fits() {
  python3 - "$@" <<'PY'
import json, sys
a, b = ([r for f in json.load(open(p))["files"] for r in f["runs"]] for p in sys.argv[1:3])
if len(a) != len(b):
    print(f"  {len(a)} runs vs {len(b)} runs"); sys.exit(1)
bad = 0
for x, y in zip(a, b):
    for k in ("t_cut_s", "t_stop_s", "samples", "best"):
        if x.get(k) != y.get(k):
            print(f"  run {x['run']}: {k} {x.get(k)} vs {y.get(k)}"); bad += 1
    mx = {m["name"]: m["params"] for m in x["models"]}; my = {m["name"]: m["params"] for m in y["models"]}
    for model, params in mx.items():
        for name, p in params.items():
            q = my.get(model, {}).get(name)
            if q is None or abs(p["value"] - q["value"]) > 1e-9 * max(1e-300, abs(p["value"])) + 1e-300:
                print(f"  run {x['run']}: {model} {name} {p['value']!r} vs {q and q['value']!r}"); bad += 1
sys.exit(1 if bad else 0)
PY
}
