# Network topology helpers for the issue-31 held-out cases (sourced by run.sh).
# A "host" is a network namespace (its own eth0 on a lab switch) plus, when a process runs
# there, its own UTS namespace with the host's name (so services report distinct hosts).
# The "switch" is a Linux bridge in a namespace of its own; every host's eth0 is a veth whose
# peer is a bridge port. LCM runs with ttl=1 on the lab's group, as on a real lab LAN.

H31_NETNS=()      # every namespace made here (deleted at exit)
H31_PIDS=()       # every process started here (killed at exit)

# ns_name CASE HOST -> the namespace's name
ns_name() { echo "h31-${H31_TAG}-$1-$2"; }

# make_switch CASE
make_switch() {
  local sw; sw=$(ns_name "$1" sw)
  ip netns add "$sw" || return 1
  H31_NETNS+=("$sw")
  ip -n "$sw" link set lo up
  ip -n "$sw" link add br0 type bridge || return 1
  # no IGMP snooping: a lab's unmanaged switch floods multicast to every port
  ip -n "$sw" link set br0 type bridge mcast_snooping 0 2>/dev/null || true
  ip -n "$sw" link set br0 up
}

# add_host CASE HOST IPSUFFIX  (10.31.X.IPSUFFIX/24 with X from the case number $H31_NET)
add_host() {
  local c=$1 h=$2 ipx=$3 sw ns port
  sw=$(ns_name "$c" sw); ns=$(ns_name "$c" "$h")
  ip netns add "$ns" || return 1
  H31_NETNS+=("$ns")
  ip -n "$ns" link set lo up
  port="p$ipx"
  ip link add eth0 netns "$ns" type veth peer name "$port" netns "$sw" || return 1
  ip -n "$sw" link set "$port" master br0
  ip -n "$sw" link set "$port" up
  ip -n "$ns" addr add "10.31.${H31_NET:-1}.$ipx/24" dev eth0
  ip -n "$ns" link set eth0 up
  ip -n "$ns" route add 224.0.0.0/4 dev eth0
}

# on CASE HOST HOSTNAME CMD... : (in a subshell or background job: it execs) run CMD in the host's network namespace with its hostname
# (exec chain: ip netns exec -> unshare -u -> sh -> exec CMD, so $! is CMD's pid)
on() {
  local ns; ns=$(ns_name "$1" "$2"); local hn=$3; shift 3
  exec ip netns exec "$ns" unshare -u /bin/sh -c 'hostname "$0" && exec "$@"' "$hn" "$@"
}

cleanup_all() {
  local p ns i
  for p in "${H31_PIDS[@]}"; do kill -CONT "$p" 2>/dev/null; kill -TERM "$p" 2>/dev/null; done
  for i in 1 2 3 4 5 6 7 8 9 10; do
    local alive=0
    for p in "${H31_PIDS[@]}"; do kill -0 "$p" 2>/dev/null && alive=1; done
    [ $alive = 0 ] && break
    sleep 0.2
  done
  for p in "${H31_PIDS[@]}"; do kill -KILL "$p" 2>/dev/null; done
  # anything still left inside our own namespaces was started by this runner
  for ns in "${H31_NETNS[@]}"; do
    for p in $(ip netns pids "$ns" 2>/dev/null); do kill -KILL "$p" 2>/dev/null; done
  done
  for ns in "${H31_NETNS[@]}"; do ip netns del "$ns" 2>/dev/null; done
}
