# Helpers for the issue-42 held-out cases (sourced by case.sh). Bash, run as root.
# Every process started here is recorded (pid) and killed by cleanup; every namespace made here is
# deleted by cleanup. Nothing here touches the host's network namespace or any host interface.

set -u
HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
: "${BIN:?BIN not set}" "${SCR:?SCR not set}"
PFX="i42-$$"                        # namespace prefix, unique per case process
NSES=()                             # namespaces made
PIDS=()                             # processes started
FAKETIME_LIB=""
for f in /usr/lib/x86_64-linux-gnu/faketime/libfaketime.so.1 /usr/lib/faketime/libfaketime.so.1 \
         /usr/local/lib/faketime/libfaketime.so.1; do
    [ -r "$f" ] && { FAKETIME_LIB=$f; break; }
done
URL0='udpm://239.255.76.67:7667?ttl=0'     # every namespace: loopback only, ttl=0

say() { echo "[$(date +%T)] $*" >> "$SCR/harness.log"; }
harness_fail() { echo "HARNESS: $*" > "$SCR/verdict"; say "harness failure: $*"; exit 3; }

cleanup() {
    local p
    for p in "${PIDS[@]}"; do kill -CONT "$p" 2>/dev/null; kill -TERM "$p" 2>/dev/null; done
    for _ in 1 2 3 4 5 6 7 8 9 10; do
        local alive=0
        for p in "${PIDS[@]}"; do kill -0 "$p" 2>/dev/null && alive=1; done
        [ $alive = 0 ] && break
        sleep 0.3
    done
    for p in "${PIDS[@]}"; do kill -KILL "$p" 2>/dev/null; done
    for n in "${NSES[@]}"; do ip netns del "$n" 2>/dev/null; done
}
trap cleanup EXIT
trap 'exit 130' INT TERM

# ns_new NAME: a namespace with lo up. Its full name is $PFX-NAME.
ns_new() {
    local n="$PFX-$1"
    ip netns add "$n" || harness_fail "ip netns add $n"
    NSES+=("$n")
    ip -n "$n" link set lo up
    ip netns exec "$n" sysctl -qw net.ipv4.conf.all.rp_filter=0 net.ipv4.conf.default.rp_filter=0 2>/dev/null
}
# ns_one NAME: one PC alone: multicast on loopback (ttl=0).
ns_one() { ns_new "$1"; ip -n "$PFX-$1" route add 224.0.0.0/4 dev lo || harness_fail "route in $1"; }
# ns_two LAB BENCH: two PCs, each a namespace of its own (multicast on its loopback), joined by the
# user-space network relay.py (this kernel has no netem): every datagram the bench PC sends to the
# lab's group and port is carried to the lab PC's, after the impairments of $SCR/net.json
# (net JSON sets them; {} = a clean link). The bench PC hears its own traffic directly (the witness).
ns_two() {
    ns_one "$1"; ns_one "$2"
    echo '{}' > "$SCR/net.json"
    bg "$2" relay python3 "$HERE/relay.py" --to-netns "/run/netns/$PFX-$1" --ctl "$SCR/net.json" \
        --stats "$SCR/relay.stats.json" --seed "${RELAY_SEED:-42}" --max-seconds 200
    wait_file "$SCR/relay.stats.json" 5 || harness_fail "relay did not start: $(cat "$SCR/relay.err")"
}
# net JSON: change the link's impairments now
net() { printf '%s\n' "$1" > "$SCR/net.json.tmp" && mv "$SCR/net.json.tmp" "$SCR/net.json"; say "net: $1"; }

# bg NS TAG CMD...: start CMD in namespace NS in the background, stdout/stderr to $SCR/TAG.out/.err;
# the pid is recorded in PIDS and in $SCR/TAG.pid.
bg() {
    local n="$PFX-$1" tag=$2; shift 2
    ip netns exec "$n" "$@" > "$SCR/$tag.out" 2> "$SCR/$tag.err" &
    local p=$!
    PIDS+=("$p"); echo "$p" > "$SCR/$tag.pid"
    say "started $tag (pid $p) in $n: $*"
}
pid_of() { cat "$SCR/$1.pid"; }
# stop TAG: SIGTERM and wait (bounded) for it to end
stop() {
    local p; p=$(pid_of "$1")
    kill -CONT "$p" 2>/dev/null; kill -TERM "$p" 2>/dev/null
    for _ in $(seq 1 50); do kill -0 "$p" 2>/dev/null || break; sleep 0.2; done
    kill -KILL "$p" 2>/dev/null
    say "stopped $1"
}
# wait_gone TAG SECONDS: wait for a process to end by itself (bounded)
wait_gone() {
    local p; p=$(pid_of "$1")
    local n=$(( $2 * 5 ))
    for _ in $(seq 1 "$n"); do kill -0 "$p" 2>/dev/null || return 0; sleep 0.2; done
    return 1
}
# wait_file PATH SECONDS
wait_file() { local n=$(( $2 * 10 )); for _ in $(seq 1 "$n"); do [ -e "$1" ] && return 0; sleep 0.1; done; return 1; }

# faketime_env FILE: the environment (as env arguments) that steps a process's wall clock by the
# offset written in FILE ("+0", "+3600"), re-read every second; the monotonic clock is not touched.
faketime_env() {
    [ -n "$FAKETIME_LIB" ] || harness_fail "libfaketime is not installed (deploy/setup --tests installs it)"
    echo "LD_PRELOAD=$FAKETIME_LIB FAKETIME_TIMESTAMP_FILE=$1 FAKETIME_CACHE_DURATION=1 DONT_FAKE_MONOTONIC=1 FAKETIME_DONT_FAKE_MONOTONIC=1"
}

# vbench NS TAG SEED ARGS...: a virtual bench on a pty linked at $SCR/TAG.tty, truth in TAG.truth.json,
# every line sent in TAG.sent.tsv; it waits up to 20 s for its reader.
vbench() {
    local ns=$1 tag=$2 seed=$3; shift 3
    bg "$ns" "$tag" "$BIN/spindown-virtual-bench" --seed "$seed" --link "$SCR/$tag.tty" \
        --truth "$SCR/$tag.truth.json" --sent "$SCR/$tag.sent.tsv" --wait-reader 20 --linger 1 "$@"
    wait_file "$SCR/$tag.tty" 10 || harness_fail "virtual bench $tag made no pty"
}
# Common physics of the cases' motors: short coasts (~10 s), the lab's J and K_b.
VB_COMMON=(--idle 2 --lead-in-s 2 --tail-s 4 --viscous 1.8e-7 --e0 3 --noise 0.003)

# bridge NS TAG BENCH_ID DEVTAG URL [ARGS...]
bridge() {
    local ns=$1 tag=$2 id=$3 dev=$4 url=$5; shift 5
    bg "$ns" "$tag" "$BIN/spindown-bridge" --device "$SCR/$dev.tty" --bench "$id" --lcm-url "$url" "$@"
}
# fitter NS TAG URL [ARGS...]
fitter() { local ns=$1 tag=$2 url=$3; shift 3; bg "$ns" "$tag" "$BIN/spindown-fitter" --lcm-url "$url" -v "$@"; }
# logger NS TAG URL DIR [ARGS...]: logs in $SCR/DIR
logger() {
    local ns=$1 tag=$2 url=$3 dir=$4; shift 4
    mkdir -p "$SCR/$dir"
    bg "$ns" "$tag" "$BIN/spindown-logger" --lcm-url "$url" --dir "$SCR/$dir" --prefix lab --flush-interval 0.2 "$@"
}
# wait_bench_done TAG SECONDS: the virtual bench has written all its lines (it exits after --linger)
wait_bench_done() { wait_gone "$1" "$2" || harness_fail "virtual bench $1 still running after $2 s"; }

judge() { python3 "$HERE/judge.py" "$@"; }
