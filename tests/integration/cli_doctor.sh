#!/usr/bin/env bash
# `spindown doctor` inside a private network namespace (unshare -n: nothing leaves this machine):
#   1. no multicast route: the route check and the LCM self-test fail, the fix says
#      `ip route add 224.0.0.0/4 dev lo`, exit code 2;
#   2. after `ip link set lo up; ip route add 224.0.0.0/4 dev lo`: both pass, exit 0;
#   3. a firewall rule dropping UDP 7667: the firewall check fails and quotes the rule;
#   4. every check with a bench file and a bridge heartbeating on LCM: one line per check, the
#      bridge's host in "clock skew", the serial device checked; --json agrees with the exit code;
#   5. ttl=0 without --single-host warns (exit 1); --serial-numbers on an empty sysfs says so.
set -euo pipefail
if [[ -z ${SPINDOWN_DOCTOR_INSIDE:-} ]]; then
  if unshare -n true 2>/dev/null; then netns=(unshare -n)
  elif unshare -rn true 2>/dev/null; then netns=(unshare -rn)
  else echo "SKIP: cannot create a network namespace (unshare -n)"; exit 77; fi
  export SPINDOWN_DOCTOR_INSIDE=1
  exec timeout 250 "${netns[@]}" bash "$0" "$@"
fi

bin="${SPINDOWN_BIN_DIR:?}"
spindown="$bin/spindown"
url='udpm://239.255.76.67:7667?ttl=0'
tmp=$(mktemp -d)
pids=()
cleanup() {
  local p
  for p in "${pids[@]}"; do kill -TERM "$p" 2>/dev/null || true; done
  wait 2>/dev/null || true
  rm -rf "$tmp"
}
trap cleanup EXIT
fail=0
check() {  # DESCRIPTION CONDITION
  if eval "$2"; then echo "ok: $1"; else echo "FAIL: $1"; fail=1; fi
}
doctor() {  # NAME ARGS... -> $tmp/NAME.out, $tmp/NAME.err, rc in $doctor_rc
  local name=$1
  shift
  doctor_rc=0
  timeout 60 "$spindown" doctor "$@" >"$tmp/$name.out" 2>"$tmp/$name.err" || doctor_rc=$?
  echo "--- spindown doctor $* (exit $doctor_rc)"
  cat "$tmp/$name.out"
}
export -n LCM_DEFAULT_URL

# ---- 1. no route --------------------------------------------------------------------------------
ip link set lo up
doctor noroute --lcm-url "$url" --env-file /nonexistent --checks route,selftest --timeout 1
check "no route: exit 2" "((doctor_rc == 2))"
check "no route: route check fails" "grep -q '^fail  multicast route' '$tmp/noroute.out'"
check "no route: fix names lo" "grep -q 'fix: ip route add 224.0.0.0/4 dev lo' '$tmp/noroute.out'"
check "no route: self-test fails" "grep -q '^fail  LCM self-test' '$tmp/noroute.out'"

# ---- 2. with the route --------------------------------------------------------------------------
ip route add 224.0.0.0/4 dev lo
doctor route --lcm-url "$url" --env-file /nonexistent --checks route,selftest --timeout 2
check "route: exit 0" "((doctor_rc == 0))"
check "route: route check ok on lo" "grep -q '^ok    multicast route .*goes out on lo' '$tmp/route.out'"
check "route: self-test ok" "grep -q '^ok    LCM self-test .*came back' '$tmp/route.out'"

# ---- 3. a firewall that drops LCM (inside this namespace only) ----------------------------------
if command -v nft >/dev/null; then
  nft add table inet doctor_test
  nft add chain inet doctor_test input '{ type filter hook input priority 0; policy accept; }'
  nft add rule inet doctor_test input udp dport 7667 drop
  doctor firewall --lcm-url "$url" --env-file /nonexistent --checks firewall,selftest --timeout 1
  check "firewall: exit 2" "((doctor_rc == 2))"
  check "firewall: the rule is quoted" "grep -q '^fail  firewall .*udp dport 7667' '$tmp/firewall.out'"
  check "firewall: the fix inserts an accept" "grep -q 'nft insert rule inet doctor_test input ip daddr 224.0.0.0/4 udp dport 7667 accept' '$tmp/firewall.out'"
  check "firewall: the self-test fails" "grep -Eq '^fail  LCM self-test .*(none came back|cannot receive)' '$tmp/firewall.out'"
  nft delete table inet doctor_test
else
  echo "note: nft is not installed; the firewall case was not run"
fi

# ---- 4. every check, a bench and a bridge heartbeating -------------------------------------------
mkdir -p "$tmp/benches" "$tmp/dev"
ln -s /dev/null "$tmp/dev/bench-1"   # a character device anyone may read and write
printf 'bench_id = "bench-1"\n[serial]\ndevice = "%s"\n' "$tmp/dev/bench-1" >"$tmp/benches/bench-1.toml"
printf 'LCM_DEFAULT_URL=%s\n' "$url" >"$tmp/lcm.env"
"$bin/spindown-bridge" --device "$tmp/no-such-tty" --bench bench-9 --lcm-url "$url" 2>"$tmp/bridge.err" &
pids+=($!)
for _ in $(seq 50); do grep -q 'bench bench-9' "$tmp/bridge.err" && break; sleep 0.1; done
doctor all --env-file "$tmp/lcm.env" --single-host --bench-config "$tmp/benches" --service-user root --listen 2.5
check "all: exit code is 0, 1 or 2 as the lines say" \
  "((doctor_rc == (\$(grep -c '^fail ' '$tmp/all.out') ? 2 : \$(grep -c '^warn ' '$tmp/all.out') ? 1 : 0)))"
check "all: the URL came from the env file" "grep -q '^ok    LCM TTL .*from $tmp/lcm.env.*--single-host' '$tmp/all.out'"
for name in 'LCM TTL' 'multicast route' 'firewall' 'receive buffer' 'LCM self-test' 'bench files' 'serial bench-1' 'clock sync'; do
  check "all: a line for $name" "grep -Eq '^(ok|warn|fail|skip) +$name ' '$tmp/all.out'"
done
check "all: route and self-test pass" "grep -q '^ok    multicast route' '$tmp/all.out' && grep -q '^ok    LCM self-test' '$tmp/all.out'"
check "all: serial device checked for the service user" "grep -q 'serial bench-1 .*-> /dev/null.*may read and write it' '$tmp/all.out'"
check "all: the bridge's host has a clock skew line" "grep -Eq '^ok +clock skew $(hostname) .*bridge bench-9' '$tmp/all.out'"
check "all: a summary line" "grep -q '^doctor: [0-9]* ok, ' '$tmp/all.out'"

doctor json --env-file "$tmp/lcm.env" --single-host --bench-config "$tmp/benches" --service-user root --listen 1.5 --json
python3 - "$tmp/json.out" "$doctor_rc" <<'PY' || fail=1
import json, sys
j = json.load(open(sys.argv[1]))
rc = int(sys.argv[2])
levels = [c["level"] for c in j["checks"]]
want = 2 if "fail" in levels else 1 if "warn" in levels else 0
assert j["exit_code"] == rc == want, (j["exit_code"], rc, want)
names = {c["name"] for c in j["checks"]}
for n in ["LCM TTL", "multicast route", "LCM self-test", "serial bench-1", "clock sync"]:
    assert n in names, n
assert any(n.startswith("clock skew ") for n in names), names
assert j["lcm_url_source"].endswith("lcm.env"), j["lcm_url_source"]
assert all(set(c) == {"name", "level", "detail", "fix"} for c in j["checks"])
print("ok: --json: %d checks, exit_code %d" % (len(levels), rc))
PY

# ---- 5. ttl=0 for a lab LAN; serial numbers --------------------------------------------------------
doctor ttl --lcm-url "$url" --checks ttl
check "ttl=0 without --single-host: exit 1" "((doctor_rc == 1))"
check "ttl=0: the fix says ttl=1" "grep -q 'fix: LCM_DEFAULT_URL=udpm://239.255.76.67:7667?ttl=1' '$tmp/ttl.out'"
mkdir -p "$tmp/sysfs-empty"
doctor serial --serial-numbers --sysfs-tty "$tmp/sysfs-empty"
check "--serial-numbers with no port: exit 1 and says so" "((doctor_rc == 1)) && grep -q 'no USB serial port found' '$tmp/serial.out'"
doctor usage --checks nonsense
check "bad --checks: exit 2" "((doctor_rc == 2))"
exit $fail
