# Shared by deploy/run-lab and tests/integration/lab_*.sh (sourced, not run): starts and stops
# the lab's processes — virtual benches, bridges, fitter, logger, watch — optionally inside a
# named network namespace (`ip netns exec NS`), with every wait bounded.
#
# The caller sets LAB_BIN (directory of the spindown binaries) and LAB_WORK (a directory for the
# processes' output, ptys, truth files and config files), and calls lab_stop_all in its EXIT trap.

declare -gA LAB_PID=()  # process name -> pid
LAB_ORDER=()            # names in start order (stopped in reverse)

# lab_start NS NAME CMD...: CMD in the background (inside network namespace NS unless NS is
# "-"), stdout to $LAB_WORK/NAME.out, stderr to $LAB_WORK/NAME.err.
lab_start() {
  local ns=$1 name=$2
  shift 2
  if [[ $ns == - ]]; then
    "$@" >"$LAB_WORK/$name.out" 2>"$LAB_WORK/$name.err" &
  else
    ip netns exec "$ns" "$@" >"$LAB_WORK/$name.out" 2>"$LAB_WORK/$name.err" &
  fi
  LAB_PID[$name]=$!
  LAB_ORDER+=("$name")
}

lab_alive() { [[ -n ${LAB_PID[$1]:-} ]] && kill -0 "${LAB_PID[$1]}" 2>/dev/null; }

# lab_wait CONDITION SECONDS: polls the shell condition every 0.1 s; 1 when it timed out.
lab_wait() {
  local deadline=$((SECONDS + $2))
  until eval "$1"; do
    ((SECONDS < deadline)) || return 1
    sleep 0.1
  done
}

# lab_stop NAME [SECONDS]: SIGTERM, then SIGKILL after SECONDS (default 10); returns the
# process's exit code (137 when it had to be killed).
lab_stop() {
  local name=$1 secs=${2:-10} pid=${LAB_PID[$1]:-}
  [[ -n $pid ]] || return 0
  kill -TERM "$pid" 2>/dev/null || true
  if ! lab_wait "! kill -0 $pid 2>/dev/null" "$secs"; then
    echo "lab: $name (pid $pid) did not stop within $secs s of SIGTERM; killing it" >&2
    kill -KILL "$pid" 2>/dev/null || true
  fi
  local rc=0
  wait "$pid" 2>/dev/null || rc=$?
  unset "LAB_PID[$name]"
  return $rc
}

# lab_wait_exit NAME SECONDS: waits for a process to end by itself; its exit code, or 124 when
# it is still running after SECONDS.
lab_wait_exit() {
  local pid=${LAB_PID[$1]:-}
  [[ -n $pid ]] || return 0
  lab_wait "! kill -0 $pid 2>/dev/null" "$2" || return 124
  local rc=0
  wait "$pid" 2>/dev/null || rc=$?
  unset "LAB_PID[$1]"
  return $rc
}

# lab_stop_all: every process still running, newest first: SIGTERM, 3 s, then SIGKILL.
lab_stop_all() {
  local i name pids=()
  for ((i = ${#LAB_ORDER[@]} - 1; i >= 0; --i)); do
    name=${LAB_ORDER[i]}
    [[ -n ${LAB_PID[$name]:-} ]] || continue
    kill -TERM "${LAB_PID[$name]}" 2>/dev/null && pids+=("${LAB_PID[$name]}")
  done
  ((${#pids[@]})) || return 0
  local deadline=$((SECONDS + 3)) p alive
  while ((SECONDS < deadline)); do
    alive=0
    for p in "${pids[@]}"; do kill -0 "$p" 2>/dev/null && alive=1; done
    ((alive)) || break
    sleep 0.1
  done
  for p in "${pids[@]}"; do kill -KILL "$p" 2>/dev/null || true; done
  wait 2>/dev/null || true
  LAB_PID=()
}

# The three demo benches: different firmware, flywheel, motor and bearings, so their fits differ.
#   1: the lab's bench as in the students' report — lab sketch (millis<TAB>volts, 9600 baud),
#      zeros before the cut, the aluminium flywheel, Coulomb-dominated friction.
#   2: spindown-coast firmware (115200 baud, 10 ms loop), a brass flywheel (J = 2.0e-5 kg·m²),
#      worn bearings (Coulomb friction ×1.8), the pin floating before the cut.
#   3: lab sketch, the supply on the pin before the cut, a 1000 rpm/V motor, an oily bearing
#      (mostly viscous friction).
LAB_PROFILE_TEXT=(
  ""
  "lab sketch 9600 baud, aluminium flywheel, friction as in the students' report"
  "spindown-coast firmware 115200 baud, brass flywheel J=2.0e-5 kg·m², worn bearings (Coulomb ×1.8)"
  "lab sketch 9600 baud, 1000 rpm/V motor, oily bearing (mostly viscous)"
)

# The same benches with the real firmware on an emulated Arduino Uno (deploy/run-lab --firmware):
# the sketch's own bytes; the pin reads 0 V before the cut where the virtual bench floats it.
LAB_AVR_PROFILE_TEXT=(
  ""
  "lab_sketch.elf on an emulated Uno, 9600 baud, aluminium flywheel, friction as in the students' report"
  "spindown_coast.elf on an emulated Uno, 115200 baud, brass flywheel J=2.0e-5 kg·m², worn bearings (Coulomb ×1.8)"
  "lab_sketch.elf on an emulated Uno, 9600 baud, 1000 rpm/V motor, oily bearing (mostly viscous)"
)

# lab_profile INDEX NAME: sets LAB_BENCH_ARGS (virtual bench options), LAB_AVR_ARGS (the emulated
# Arduino's: sketch and motor) and writes the bridge's config file $LAB_WORK/NAME.toml with the
# same J and K_b (what the bridge says in CONFIG).
lab_profile() {
  local toml="$LAB_WORK/$2.toml"
  case $1 in
    1)
      LAB_BENCH_ARGS=(--protocol lab --lead-in zeros --e0 2.8 --e0-step 0.4 --seed 11)
      LAB_AVR_ARGS=(lab_sketch --lead-in zeros --e0 2.8 --e0-step 0.4 --noise 0.003 --seed 11)
      printf '[bench]\ninertia_source = "aluminium flywheel r=2 cm h=1.5 cm + rotor"\n' >"$toml"
      ;;
    2)
      LAB_BENCH_ARGS=(--protocol spindown-v1 --period-ms 10 --jitter-ms 0.2 --lead-in floating --inertia 2.0e-5
                      --coulomb 2.05e-4 --viscous 1.5e-7 --e0 3.0 --e0-step 0.3 --seed 22)
      LAB_AVR_ARGS=(spindown_coast --lead-in zeros --inertia 2.0e-5 --coulomb 2.05e-4 --viscous 1.5e-7 --e0 3.0
                    --e0-step 0.3 --noise 0.003 --seed 22)
      printf '[bench]\ninertia_kg_m2 = 2.0e-5\ninertia_source = "brass flywheel"\n[serial]\nbaud = 115200\n' >"$toml"
      ;;
    3)
      LAB_BENCH_ARGS=(--protocol lab --lead-in supply --supply 3.2 --kb 0.009549296585513721 --viscous 1.2e-6
                      --coulomb 3.0e-5 --e0 2.5 --e0-step 0.3 --seed 33)
      LAB_AVR_ARGS=(lab_sketch --lead-in supply --supply 3.2 --kb 0.009549296585513721 --viscous 1.2e-6
                    --coulomb 3.0e-5 --e0 2.5 --e0-step 0.3 --noise 0.003 --seed 33)
      printf '[bench]\nspeed_constant_rpm_per_v = 1000\nkb_source = "motor datasheet 1000 rpm/V"\n' >"$toml"
      ;;
    *) echo "lab_profile: no profile $1 (1..3)" >&2; return 2 ;;
  esac
}

# lab_start_bench NS NAME PROFILE URL RUNS SPEED [EXTRA VIRTUAL BENCH OPTIONS...]: a virtual bench
# on a pty ($LAB_WORK/NAME.tty) and a bridge reading it, publishing on URL. Processes are named
# NAME.bench and NAME.bridge; the bench writes its truth to $LAB_WORK/NAME.truth.json.
lab_start_bench() {
  local ns=$1 name=$2 profile=$3 url=$4 runs=$5 speed=$6
  shift 6
  lab_profile "$profile" "$name" || return 2
  rm -f "$LAB_WORK/$name.tty"
  lab_start "$ns" "$name.bench" "$LAB_BIN/spindown-virtual-bench" "${LAB_BENCH_ARGS[@]}" --runs "$runs" \
    --speed "$speed" --idle 1.0 --link "$LAB_WORK/$name.tty" --truth "$LAB_WORK/$name.truth.json" \
    --wait-reader 30 --linger 1 "$@"
  if ! lab_wait "[[ -L '$LAB_WORK/$name.tty' ]]" 15; then
    echo "lab: the virtual bench $name did not make its pty: $(tail -3 "$LAB_WORK/$name.bench.err")" >&2
    return 1
  fi
  lab_start "$ns" "$name.bridge" "$LAB_BIN/spindown-bridge" --device "$LAB_WORK/$name.tty" --bench "$name" \
    --lcm-url "$url" --config "$LAB_WORK/$name.toml"
}

# lab_start_avr NS NAME PROFILE URL RUNS SPEED FIRMWARE_DIR: the profile's sketch (FIRMWARE_DIR/
# SKETCH.elf, built by make -C deploy/firmware) on an emulated Arduino Uno (spindown-avr-bench,
# SPEED: at most that many emulated seconds per wall second, 0: as fast as it runs) on a pty
# ($LAB_WORK/NAME.tty), and a bridge reading it. Processes NAME.bench and NAME.bridge; the truth
# in $LAB_WORK/NAME.truth.json as with lab_start_bench.
lab_start_avr() {
  local ns=$1 name=$2 profile=$3 url=$4 runs=$5 speed=$6 fw=$7
  lab_profile "$profile" "$name" || return 2
  local sketch=${LAB_AVR_ARGS[0]}
  rm -f "$LAB_WORK/$name.tty"
  lab_start "$ns" "$name.bench" "$LAB_BIN/spindown-avr-bench" --firmware "$fw/$sketch.elf" "${LAB_AVR_ARGS[@]:1}" \
    --runs "$runs" --speed "$speed" --idle 1.0 --link "$LAB_WORK/$name.tty" --truth "$LAB_WORK/$name.truth.json" \
    --wait-reader 30 --linger 1
  if ! lab_wait "[[ -L '$LAB_WORK/$name.tty' ]]" 15; then
    echo "lab: the emulated Arduino $name did not make its pty: $(tail -3 "$LAB_WORK/$name.bench.err")" >&2
    return 1
  fi
  lab_start "$ns" "$name.bridge" "$LAB_BIN/spindown-bridge" --device "$LAB_WORK/$name.tty" --bench "$name" \
    --lcm-url "$url" --config "$LAB_WORK/$name.toml"
}

# lab_truth_runs NAME...: runs the benches will send, in all.
lab_truth_runs() {
  python3 - "$@" <<'PY'
import json, os, sys
print(sum(len(json.load(open(p))["runs"]) for p in sys.argv[1:] if os.path.exists(p)))
PY
}

# lab_fits_published: FIT messages the fitter published (its -v log).
lab_fits_published() { grep -c ' fitted: ' "$LAB_WORK/fitter.err" 2>/dev/null || true; }

# lab_only_log DIR: the one LCM log in DIR.
lab_only_log() { ls "$1"/*.lcm 2>/dev/null | head -1; }
