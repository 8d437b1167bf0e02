# Shared by tests/integration/lab_*.sh (sourced; not a test itself): re-runs the calling script
# inside `unshare -n` (SKIP when the kernel refuses network namespaces), builds a lab network
# of namespaces (deploy/lab/lab_netns.bash: one per bench, joined by veth to a "lab" namespace)
# and runs a whole session in it with lab_session. Every wait is bounded.
set -euo pipefail
if [[ -z ${SPINDOWN_IN_NETNS:-} ]]; then
  if ! unshare -n true 2>/dev/null; then
    echo "SKIP: this kernel refuses network namespaces (unshare -n true failed)"
    exit 0
  fi
  export SPINDOWN_IN_NETNS=1
  exec timeout 280 unshare -n bash "$0" "$@"
fi

src=${SPINDOWN_SOURCE_DIR:-$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)}
LAB_BIN=${SPINDOWN_BIN_DIR:?SPINDOWN_BIN_DIR not set}
LAB_WORK=$(mktemp -d /tmp/spindown-lab-test.XXXXXX)
source "$src/deploy/lab/lab.bash"
source "$src/deploy/lab/lab_netns.bash"
cleanup() {
  lab_stop_all
  lab_netns_down
  if [[ -z ${KEEP_WORK:-} ]]; then rm -rf "$LAB_WORK"; else echo "work dir kept: $LAB_WORK"; fi
}
trap cleanup EXIT
trap 'echo "lab test: interrupted" >&2; exit 143' TERM INT  # the EXIT trap still removes the namespaces
fail() {
  echo "FAIL: $*" >&2
  for f in "$LAB_WORK"/*.err; do echo "--- $f" >&2; tail -8 "$f" >&2; done
  exit 1
}

URL='udpm://239.255.76.67:7667?ttl=1'

# lab_session RUNS SPEED BENCH...: namespaces PREFIX-b1.. for the benches (profiles 1, 2, 3, 1…)
# and PREFIX-lab with the logger, the fitter (-v) and `spindown watch --plain`; calls
# lab_before_benches (when the caller defines it) once the network is up; runs the benches to
# their end, waits for the fitter's fits (as many as the benches sent runs, or 60 s), stops
# everything with SIGTERM (a non-zero exit is a failure) and sets LOG, EXPECTED and TRUTH_ARGS.
lab_session() {
  local runs=$1 speed=$2 i b rc
  shift 2
  local benches=("$@")
  lab_netns_up "sdlab$$" "${#benches[@]}" || fail "could not build the namespaces"
  if declare -F lab_before_benches >/dev/null; then lab_before_benches; fi
  lab_start_services
  for ((i = 0; i < ${#benches[@]}; ++i)); do
    lab_start_bench "${LAB_NS_BENCH[i]}" "${benches[i]}" "$((i % 3 + 1))" "$URL" "$runs" "$speed" ||
      fail "bench ${benches[i]} did not start"
  done
  for b in "${benches[@]}"; do
    rc=0
    lab_wait_exit "$b.bench" 150 || rc=$?
    ((rc == 0)) || fail "virtual bench $b ended with code $rc"
  done
  TRUTH_ARGS=()
  local truth=()
  for b in "${benches[@]}"; do
    truth+=("$LAB_WORK/$b.truth.json")
    TRUTH_ARGS+=("$b=$LAB_WORK/$b.truth.json")
  done
  lab_end_session "${truth[@]}" -- "${benches[@]/%/.bridge}"
}

# lab_start_services [-k KEY] [-c CREDENTIALS_DIR]: in PREFIX-lab, the logger, the fitter (-v) and
# `spindown watch --plain` on $URL, waited for until each says it listens. -k: the fitter and watch
# take --key KEY; -c: the logger finds its key as a systemd credential in that directory.
lab_start_services() {
  local key=() cred=() opt
  OPTIND=1
  while getopts k:c: opt; do
    case $opt in
      k) key=(--key "$OPTARG") ;;
      c) cred=(env CREDENTIALS_DIRECTORY="$OPTARG") ;;
      *) fail "lab_start_services: bad option" ;;
    esac
  done
  mkdir -p "$LAB_WORK/log"
  lab_start "$LAB_NS_LAB" logger "${cred[@]}" "$LAB_BIN/spindown-logger" --lcm-url "$URL" --dir "$LAB_WORK/log" \
    --prefix lab --flush-interval 0.2
  lab_start "$LAB_NS_LAB" fitter "$LAB_BIN/spindown-fitter" --lcm-url "$URL" --status-period 0.5 -v "${key[@]}"
  lab_start "$LAB_NS_LAB" watch "$LAB_BIN/spindown" watch --lcm-url "$URL" --plain --interval 5 --duration 250 \
    "${key[@]}"
  lab_wait "grep -q channels '$LAB_WORK/logger.err' && grep -q 'fitting benches' '$LAB_WORK/fitter.err' &&
            grep -q listening '$LAB_WORK/watch.out'" 30 || fail "the lab services did not start"
}

# lab_end_session TRUTH... -- BRIDGE...: waits for the fitter's fits (as many as the truth files
# have runs, or 60 s), stops the bridges (named as lab_start named them), the fitter, watch and the
# logger with SIGTERM (a non-zero exit is a failure), prints the fitter's last counts and sets
# EXPECTED and LOG.
lab_end_session() {
  local truth=() b
  while (($#)) && [[ $1 != -- ]]; do truth+=("$1"); shift; done
  shift
  EXPECTED=$(lab_truth_runs "${truth[@]}")
  lab_wait "(( \$(lab_fits_published) >= $EXPECTED ))" 60 ||
    echo "note: the fitter published $(lab_fits_published) fits; the benches sent $EXPECTED runs"
  sleep 1.2  # a last heartbeat of every bridge reaches the log
  for b in "$@"; do lab_stop "$b" 5 || fail "$b: exit code $? on SIGTERM (want 0)"; done
  lab_stop fitter 10 || fail "fitter: exit code $? on SIGTERM"
  sleep 0.5
  lab_stop watch 5 || fail "watch: exit code $? on SIGTERM"
  lab_stop logger 15 || fail "logger: exit code $? on SIGTERM"
  echo "fitter: $(grep 'spindown-fitter: stopped:' "$LAB_WORK/fitter.err" | sed 's/^spindown-fitter: //')"
  echo "fitter: $(grep 'spindown-fitter: sources:' "$LAB_WORK/fitter.err" | sed 's/^spindown-fitter: //')"
  LOG=$(lab_only_log "$LAB_WORK/log")
  [[ -n $LOG ]] || fail "no log written"
}

# watch_last_table: the last table `spindown watch --plain` printed (indented).
watch_last_table() {
  awk '/^spindown watch  /{t=""} {t=t "  " $0 "\n"} END{printf "%s", t}' "$LAB_WORK/watch.out"
}
