#!/usr/bin/env bash
# deploy/systemd/*.service pass `systemd-analyze verify` with no complaint at all (an unknown key
# or a bad value is only a warning there, so any output fails the test), with the ExecStart paths
# pointed at this build's programs through a temporary copy; the bridge template is verified as
# an instance. Also checks what the units promise: Type=notify with a watchdog, the logger's
# retention, the unprivileged user, the hardening, only the bench's serial device, the bench file
# and the LCM env file. Skips (exit 77) only when
# systemd-analyze is not installed (Debian: apt-get install systemd).
set -euo pipefail
src="${SPINDOWN_SOURCE_DIR:?}"
bin="${SPINDOWN_BIN_DIR:?}"
analyze=$(command -v systemd-analyze || true)
if [[ -z $analyze ]]; then
  echo "SKIP: systemd-analyze is not installed (apt-get install systemd); the units were not verified"
  exit 77
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
for p in spindown-bridge spindown-fitter spindown-logger spindown-web; do
  [[ -x $bin/$p ]] || { echo "FAIL: $bin/$p is not built"; exit 1; }
done
cp "$src"/deploy/systemd/*.service "$tmp/"
sed -i "s#/usr/local/bin/#$bin/#g" "$tmp"/*.service
grep -q "ExecStart=$bin/spindown-bridge " "$tmp/spindown-bridge@.service" || { echo "FAIL: ExecStart not rewritten"; exit 1; }

verify() {  # UNIT...
  local out rc=0
  out=$(cd "$tmp" && SYSTEMD_UNIT_PATH="$tmp:" "$analyze" verify --man=no "$@" 2>&1) || rc=$?
  if ((rc != 0)) || [[ -n $out ]]; then
    echo "FAIL: systemd-analyze verify $* (exit $rc):"; echo "$out"; fail=1
  else
    echo "ok: systemd-analyze verify $*"
  fi
}
verify spindown-fitter.service spindown-logger.service spindown-bridge@bench-1.service spindown-web.service
verify spindown-bridge@lab_3.service

# systemd's own exposure score (0 = locked down … 10 = exposed): the hardening stays in place.
for u in spindown-fitter.service spindown-logger.service spindown-bridge@bench-1.service spindown-web.service; do
  score=$(cd "$tmp" && SYSTEMD_UNIT_PATH="$tmp:" "$analyze" security --offline=yes --no-pager "$u" 2>/dev/null |
          sed -n 's/.*Overall exposure level for [^:]*: \([0-9.]*\).*/\1/p')
  if [[ -n $score ]] && python3 -c "import sys; sys.exit(0 if float('$score') <= 2.5 else 1)"; then
    echo "ok: $u exposure $score (systemd-analyze security)"
  else
    echo "FAIL: $u exposure '${score:-?}' (want ≤ 2.5)"; fail=1
  fi
done

# The check itself catches mistakes: an unknown key, and a program that is not there.
cp "$tmp/spindown-fitter.service" "$tmp/broken-key.service"
sed -i 's/^NoNewPrivileges=yes/NoNewPrivilege=yes/' "$tmp/broken-key.service"
cp "$tmp/spindown-fitter.service" "$tmp/broken-exec.service"
sed -i "s#^ExecStart=$bin/spindown-fitter#ExecStart=$tmp/no-such-program#" "$tmp/broken-exec.service"
for u in broken-key broken-exec; do
  out=$(cd "$tmp" && SYSTEMD_UNIT_PATH="$tmp:" "$analyze" verify --man=no "$u.service" 2>&1 || true)
  if [[ -z $out ]]; then echo "FAIL: verify said nothing about $u.service"; fail=1; else echo "ok: verify catches $u: $(head -1 <<<"$out")"; fi
done

# What the units promise.
expect() {  # UNIT LINE
  if grep -qxF -- "$2" "$src/deploy/systemd/$1"; then echo "ok: $1: $2"; else echo "FAIL: $1 lacks '$2'"; fail=1; fi
}
for u in spindown-bridge@.service spindown-fitter.service spindown-logger.service; do
  for line in User=spindown NoNewPrivileges=yes ProtectSystem=strict ProtectHome=yes PrivateTmp=yes \
    DevicePolicy=closed "RestrictAddressFamilies=AF_INET AF_UNIX" CapabilityBoundingSet= \
    SystemCallFilter=@system-service Restart=on-failure EnvironmentFile=/etc/spindown/lcm.env \
    Type=notify NotifyAccess=main WatchdogSec=30; do
    expect "$u" "$line"
  done
done
expect spindown-bridge@.service "DeviceAllow=/dev/spindown/%i rw"
# spindown-web: the same, serving TCP (IPv4 or IPv6) on the admin's address (web.env, default this PC
# only), with one capability (ports below 1024).
for line in User=spindown NoNewPrivileges=yes ProtectSystem=strict ProtectHome=yes PrivateTmp=yes PrivateDevices=yes \
  DevicePolicy=closed "RestrictAddressFamilies=AF_INET AF_INET6 AF_UNIX" CapabilityBoundingSet=CAP_NET_BIND_SERVICE \
  SystemCallFilter=@system-service Restart=on-failure EnvironmentFile=/etc/spindown/lcm.env \
  EnvironmentFile=-/etc/spindown/web.env Environment=SPINDOWN_WEB_LISTEN=127.0.0.1:8080 \
  Type=notify NotifyAccess=main WatchdogSec=30 \
  "ExecStart=/usr/local/bin/spindown-web --listen \${SPINDOWN_WEB_LISTEN} --bench-config /etc/spindown/benches"; do
  expect spindown-web.service "$line"
done
grep -qx 'SPINDOWN_WEB_LISTEN=127.0.0.1:8080' "$src/deploy/systemd/web.env" ||
  { echo "FAIL: web.env does not default to this PC only"; fail=1; }
expect spindown-bridge@.service "SupplementaryGroups=dialout"
expect spindown-bridge@.service "ExecStart=/usr/local/bin/spindown-bridge --config /etc/spindown/benches/%i.toml --bench %i"
expect spindown-fitter.service "ExecStart=/usr/local/bin/spindown-fitter --bench-config /etc/spindown/benches"
expect spindown-logger.service "StateDirectory=spindown/logs"
# Retention on by default (four benches at 50 Hz: ~2 GB a day), and its options the logger knows.
grep -Eq '^ExecStart=.* --keep-mb [1-9][0-9]* --keep-files [1-9][0-9]*$' "$src/deploy/systemd/spindown-logger.service" ||
  { echo "FAIL: spindown-logger.service does not set --keep-mb and --keep-files"; fail=1; }
logger_help=$("$bin/spindown-logger" --help)
if grep -q -- '--keep-mb' <<<"$logger_help" && grep -q -- '--keep-files' <<<"$logger_help"; then
  echo "ok: spindown-logger has --keep-mb and --keep-files"
else
  echo "FAIL: spindown-logger --help lacks --keep-mb/--keep-files"; fail=1
fi
grep -q '^DeviceAllow=' "$src/deploy/systemd/spindown-fitter.service" && { echo "FAIL: the fitter may open devices"; fail=1; }
grep -qx 'LCM_DEFAULT_URL=udpm://239.255.76.67:7667?ttl=1' "$src/deploy/systemd/lcm.env" ||
  { echo "FAIL: lcm.env does not set the lab URL with ttl=1"; fail=1; }

# The bridge reads its serial device from the bench file the unit names (no --device).
cat >"$tmp/bench-9.toml" <<'TOML'
bench_id = "bench-9"
[serial]
device = "/nonexistent/spindown/bench-9"
TOML
rc=0
timeout 20 "$bin/spindown-bridge" --config "$tmp/bench-9.toml" --bench bench-9 --lcm-url memq:// --exit-on-missing \
  >"$tmp/bridge.out" 2>"$tmp/bridge.err" || rc=$?
if ((rc == 1)) && grep -q '/nonexistent/spindown/bench-9' "$tmp/bridge.err"; then
  echo "ok: the bridge takes [serial] device from the bench file"
else
  echo "FAIL: bridge with only --config (exit $rc):"; cat "$tmp/bridge.err"; fail=1
fi
exit $fail
