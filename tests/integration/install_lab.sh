#!/usr/bin/env bash
# deploy/install-lab: --dry-run prints every step and changes nothing; --root installs into a
# temporary root (programs, units, sysusers with the user created offline, udev rule, lcm.env,
# bridges enabled for the bench files there), a second run changes nothing, and a technician's
# edited lcm.env is never overwritten. Nothing is installed on this machine.
set -euo pipefail
src="${SPINDOWN_SOURCE_DIR:?}"
bin="${SPINDOWN_BIN_DIR:?}"
install="$src/deploy/install-lab"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
check() {  # DESCRIPTION CONDITION
  if eval "$2"; then echo "ok: $1"; else echo "FAIL: $1"; fail=1; fi
}

# ---- dry run -------------------------------------------------------------------------------------
rc=0
"$install" --dry-run --no-build --bin-dir "$bin" >"$tmp/dry.out" 2>&1 || rc=$?
cat "$tmp/dry.out"
check "dry run exits 0" "((rc == 0))"
for step in "install -m 0755 $bin/spindown-bridge /usr/local/bin/spindown-bridge" \
            "/etc/sysusers.d/spindown.conf" "systemd-sysusers" \
            "/etc/systemd/system/spindown-bridge@.service" "/etc/systemd/system/spindown-fitter.service" \
            "/etc/systemd/system/spindown-logger.service" "/etc/udev/rules.d/99-spindown.rules" \
            "/etc/systemd/system/spindown-web.service" "/etc/spindown/web.env" \
            "install -m 0755 $bin/spindown-web /usr/local/bin/spindown-web" \
            "/etc/spindown/lcm.env" "/etc/sysctl.d/60-spindown.conf" "sysctl -q -p /etc/sysctl.d/60-spindown.conf" \
            "/usr/local/bin/spindown-lcm-spy" "/usr/local/bin/spindown-lcm-logplayer-gui" \
            "dry run: nothing was changed"; do
  check "dry run mentions $step" "grep -qF -- '$step' '$tmp/dry.out'"
done
# The dry run with the build: says it would run setup and a Release build, runs neither.
had_release=0
[[ -e $src/build-release ]] && had_release=1
"$install" --dry-run >"$tmp/dry-build.out" 2>&1 || true
check "dry run shows deploy/setup and the Release build" \
  "grep -q 'deploy/setup' '$tmp/dry-build.out' && grep -q 'CMAKE_BUILD_TYPE=Release' '$tmp/dry-build.out'"
check "dry run built nothing" "((had_release)) || [[ ! -e '$src/build-release' ]]"
rc=0
"$install" --no-such-option >/dev/null 2>"$tmp/usage.err" || rc=$?
check "bad usage exits 2 with a message" "((rc == 2)) && grep -q 'unknown option' '$tmp/usage.err'"

# ---- into a temporary root -----------------------------------------------------------------------
root="$tmp/root"
mkdir -p "$root/etc/spindown/benches"
printf 'bench_id = "bench-1"\n[serial]\ndevice = "/dev/spindown/bench-1"\n' >"$root/etc/spindown/benches/bench-1.toml"
printf 'bench_id = "bench-2"\n[serial]\ndevice = "/dev/spindown/bench-2"\n' >"$root/etc/spindown/benches/bench-2.toml"
rc=0
"$install" --root "$root" --no-build --bin-dir "$bin" --enable >"$tmp/first.out" 2>&1 || rc=$?
cat "$tmp/first.out"
check "install into --root exits 0" "((rc == 0))"
for p in spindown spindown-bridge spindown-fitter spindown-logger spindown-web; do
  check "/usr/local/bin/$p installed, executable, same as the build" "[[ -x '$root/usr/local/bin/$p' ]] && cmp -s '$bin/$p' '$root/usr/local/bin/$p'"
done
for f in etc/systemd/system/spindown-bridge@.service etc/systemd/system/spindown-fitter.service \
         etc/systemd/system/spindown-logger.service etc/systemd/system/spindown-web.service \
         etc/spindown/web.env etc/sysusers.d/spindown.conf etc/udev/rules.d/99-spindown.rules \
         etc/spindown/lcm.env etc/sysctl.d/60-spindown.conf usr/local/share/doc/spindown/README.md; do
  check "$f installed" "[[ -s '$root/$f' ]]"
done
check "user spindown created (offline sysusers)" "grep -q '^spindown:' '$root/etc/passwd'"
check "spindown is in dialout" "grep -Eq '^dialout:[^:]*:[0-9]+:(.*,)?spindown(,|$)' '$root/etc/group'"
for u in spindown-fitter.service spindown-logger.service spindown-web.service spindown-bridge@bench-1.service \
         spindown-bridge@bench-2.service; do
  check "$u enabled" "[[ -L '$root/etc/systemd/system/multi-user.target.wants/$u' ]]"
done

# ---- idempotent: a second run changes nothing, an edited lcm.env stays ----------------------------
echo 'LCM_DEFAULT_URL=udpm://239.255.76.68:7668?ttl=1   # edited by the technician' >"$root/etc/spindown/lcm.env"
sleep 1
touch "$tmp/marker"
rc=0
"$install" --root "$root" --no-build --bin-dir "$bin" >"$tmp/second.out" 2>&1 || rc=$?
check "second run exits 0" "((rc == 0))"
check "second run installs nothing" "! grep -q '^  + install' '$tmp/second.out'"
check "second run says unchanged" "grep -q 'spindown-bridge@.service (unchanged)' '$tmp/second.out'"
changed=$(cd "$root" && find . -type f -newer "$tmp/marker" ! -name '.pwd.lock' | sort)
check "second run modified no file (found: $changed)" "[[ -z '$changed' ]]"
check "edited lcm.env kept" "grep -q 'edited by the technician' '$root/etc/spindown/lcm.env'"
check "second run says lcm.env is the technician's" "grep -q '/etc/spindown/lcm.env (exists; yours' '$tmp/second.out'"
check "the install names the pages' URL" "grep -q 'The pages: http://127.0.0.1:8080/' '$tmp/second.out'"
exit $fail
