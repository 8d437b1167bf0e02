# A lab network made of network namespaces (sourced by tests/integration/lab_*.sh, not run):
#
#   PREFIX-b1 (lan0 10.77.0.11/24) ──veth──┐
#   PREFIX-b2 (lan0 10.77.0.12/24) ──veth──┼── PREFIX-lab: bridge device "labnet" 10.77.0.1/24
#   …                                      ┘
#
# Each bench namespace holds a virtual bench and its bridge; the lab namespace holds the
# fitter, the logger and a watch. Every namespace has lo up and a route for 224.0.0.0/4 via its
# LAN device, so LCM's udpm with ttl=1 crosses the veths as it would cross a lab switch. All
# devices are created inside the namespaces (`ip -n`), never in the caller's own namespace; the
# addresses exist only there. Call lab_netns_down in the EXIT trap.

LAB_NS_LAB=""
LAB_NS_BENCH=()

# lab_netns_up PREFIX N
lab_netns_up() {
  local prefix=$1 n=$2 i ns
  LAB_NS_LAB="$prefix-lab"
  ip netns add "$LAB_NS_LAB" || { echo "lab_netns_up: ip netns add $LAB_NS_LAB failed" >&2; return 1; }
  ip -n "$LAB_NS_LAB" link set lo up
  ip -n "$LAB_NS_LAB" link add labnet type bridge
  # No IGMP snooping: every port gets the group's traffic (nobody runs a querier here).
  ip -n "$LAB_NS_LAB" link set labnet type bridge mcast_snooping 0
  ip -n "$LAB_NS_LAB" addr add 10.77.0.1/24 dev labnet
  ip -n "$LAB_NS_LAB" link set labnet up
  ip -n "$LAB_NS_LAB" route add 224.0.0.0/4 dev labnet
  for ((i = 1; i <= n; ++i)); do
    ns="$prefix-b$i"
    ip netns add "$ns" || { echo "lab_netns_up: ip netns add $ns failed" >&2; return 1; }
    LAB_NS_BENCH+=("$ns")
    ip -n "$ns" link set lo up
    ip -n "$LAB_NS_LAB" link add "vb$i" type veth peer name lan0 netns "$ns"
    ip -n "$LAB_NS_LAB" link set "vb$i" master labnet
    ip -n "$LAB_NS_LAB" link set "vb$i" up
    ip -n "$ns" addr add "10.77.0.$((10 + i))/24" dev lan0
    ip -n "$ns" link set lan0 up
    ip -n "$ns" route add 224.0.0.0/4 dev lan0
  done
}

# lab_netns_loss NS PERCENT: drops PERCENT % of the multicast datagrams leaving NS (nftables
# `numgen random`, or iptables `statistic` when nft is missing) — loss on the way from a bench
# to the lab, seen alike by every listener there.
lab_netns_loss() {
  local ns=$1 pct=$2
  if command -v nft >/dev/null; then
    ip netns exec "$ns" nft add table inet lab_loss
    ip netns exec "$ns" nft add chain inet lab_loss out '{ type filter hook output priority 0; policy accept; }'
    ip netns exec "$ns" nft add rule inet lab_loss out ip daddr 224.0.0.0/4 numgen random mod 100 '<' "$pct" \
      counter drop
  elif command -v iptables >/dev/null; then
    ip netns exec "$ns" iptables -A OUTPUT -d 224.0.0.0/4 -m statistic --mode random \
      --probability "$(python3 -c "print($pct / 100)")" -j DROP
  else
    echo "lab_netns_loss: neither nft nor iptables is installed (deploy/setup installs nftables)" >&2
    return 1
  fi
}

# lab_netns_dropped NS: datagrams the loss rule dropped so far.
lab_netns_dropped() {
  if command -v nft >/dev/null; then
    ip netns exec "$1" nft list table inet lab_loss 2>/dev/null | sed -n 's/.*counter packets \([0-9]*\).*/\1/p' | head -1
  else
    ip netns exec "$1" iptables -L OUTPUT -v -x -n | awk '/DROP/ {print $1; exit}'
  fi
}

lab_netns_down() {
  local ns
  for ns in "${LAB_NS_BENCH[@]}" "$LAB_NS_LAB"; do
    [[ -n $ns ]] && ip netns del "$ns" 2>/dev/null || true
  done
  LAB_NS_BENCH=()
  LAB_NS_LAB=""
}
