#!/usr/bin/env bash
# `spindown fit` options: bad usage exits 2 with a message and reads nothing; bench options
# scale the coefficients as the physics says (c ∝ J; the Coulomb torque ∝ 1/K_b for volts);
# delimited text with named columns and units gives the same fit as the Arduino log.
set -euo pipefail
bin="${SPINDOWN_BIN_DIR:?}/spindown"
data="${SPINDOWN_SAMPLE_DATA:?}"
seed="$data/seed-3v-run1.tsv"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0

expect_exit() {  # WANT ARGS...
  local want=$1 rc=0
  shift
  timeout 60 "$bin" "$@" >"$tmp/out" 2>"$tmp/err" || rc=$?
  if ((rc != want)); then
    echo "FAIL [$*]: exit $rc, want $want"; head -n 5 "$tmp/err"; fail=1
  elif ((want == 2)) && ! [[ -s "$tmp/err" ]]; then
    echo "FAIL [$*]: exit 2 without a message on stderr"; fail=1
  else
    echo "ok [$*] -> $rc $(head -n 1 "$tmp/err")"
  fi
}

expect_exit 2
expect_exit 2 fit
expect_exit 2 fit "$seed" --no-such-option
expect_exit 2 fit "$seed" --kb 0.008 --speed-constant 1180
expect_exit 2 fit "$seed" --inertia 0
expect_exit 2 fit "$seed" --inertia -1e-5
expect_exit 2 fit "$seed" --inertia abc
expect_exit 2 fit "$seed" --inertia 100          # 100 kg·m²: a unit mistake, not a bench
expect_exit 2 fit "$seed" --models viscous,friction
expect_exit 2 fit "$seed" --flywheel-radius 0.02 # the rest of the flywheel is missing
expect_exit 2 fit "$seed" --inertia 1e-5 --flywheel-radius 0.02 --flywheel-height 0.015 \
  --flywheel-density 2700 --rotor-inertia 1.09e-6
expect_exit 2 fit "$seed" --time-unit hours
expect_exit 2 fit "$seed" --value-unit furlongs
expect_exit 2 fit "$seed" --delimiter x
expect_exit 2 fit "$seed" --kb nan
# Bad usage reads no file: a missing file is not even mentioned.
expect_exit 2 fit "$tmp/missing.tsv" --kb -1
grep -q "missing.tsv" "$tmp/err" && { echo "FAIL: bad usage still read the files"; fail=1; }
expect_exit 0 --help
expect_exit 0 fit --help
grep -q -- "--speed-constant" "$tmp/out" || { echo "FAIL: fit --help lacks --speed-constant"; fail=1; }

# c3 and c4 (SI) of the combined fit, and the bench J/K_b the report says it used.
coefficients() {
  timeout 60 "$bin" fit --json "$@" 2>/dev/null | python3 -c '
import json, sys
run = json.load(sys.stdin)["files"][0]["runs"][0]
p = [m for m in run["models"] if m["name"] == "combined"][0]["params"]
print(p["c3"]["value"], p["c4"]["value"], run["bench"]["J"], run["bench"]["Kb"])'
}
read -r c3 c4 J Kb < <(coefficients "$seed")
read -r c3j c4j J2 _ < <(coefficients "$seed" --inertia 2.25375204e-5)
read -r c3f c4f Jf _ < <(coefficients "$seed" --flywheel-radius 0.02 --flywheel-height 0.015 \
  --flywheel-density 2700 --rotor-inertia 1.09e-6)
read -r c3k c4k _ Kb2 < <(coefficients "$seed" --kb 0.004046312113854871)
read -r c3s c4s _ Kbs < <(coefficients "$seed" --speed-constant 1180)
if ! python3 - "$c3" "$c4" "$J" "$Kb" "$c3j" "$c4j" "$J2" "$c3f" "$c4f" "$Jf" "$c3k" "$c4k" "$Kb2" "$c3s" "$c4s" "$Kbs" <<'PY'
import sys
c3, c4, J, Kb, c3j, c4j, J2, c3f, c4f, Jf, c3k, c4k, Kb2, c3s, c4s, Kbs = map(float, sys.argv[1:])
def close(a, b, rel, what):
    if abs(a - b) > rel * abs(b):
        print(f"FAIL {what}: {a:.6g} vs {b:.6g}"); return False
    return True
ok = all([
    close(J2, 2 * J, 1e-9, "--inertia J"),
    close(c3j, 2 * c3, 1e-6, "c3 doubles with J"), close(c4j, 2 * c4, 1e-6, "c4 doubles with J"),
    close(Jf, J, 1e-6, "flywheel geometry + rotor = the lab's J"), close(c3f, c3, 1e-5, "c3 from flywheel J"),
    close(Kb2, Kb / 2, 1e-9, "--kb K_b"),
    close(c3k, c3, 1e-6, "c3 does not depend on K_b"), close(c4k, 2 * c4, 1e-6, "c4 doubles when K_b halves"),
    close(Kbs, Kb, 1e-6, "--speed-constant 1180 = lab K_b"), close(c4s, c4, 1e-5, "c4 from speed constant"),
])
sys.exit(0 if ok else 1)
PY
then fail=1; else echo "ok bench options scale c3, c4 as J and K_b say"; fi

# --models picks the models; --lab-units adds the lab's units beside SI.
models=$(timeout 60 "$bin" fit --json --models coulomb,combined --lab-units "$seed" | python3 -c '
import json, sys
run = json.load(sys.stdin)["files"][0]["runs"][0]
c3 = [m for m in run["models"] if m["name"] == "combined"][0]["params"]["c3"]
assert c3["lab"]["unit"] == "g*cm^2/s" and abs(c3["lab"]["value"] - c3["value"] * 1e7) < 1e-9 * c3["lab"]["value"]
print(",".join(m["name"] for m in run["models"]))')
[[ "$models" == "coulomb,combined" ]] || { echo "FAIL --models coulomb,combined gave '$models'"; fail=1; }
timeout 60 "$bin" fit --lab-units "$seed" | grep -qF "g·cm²·s⁻¹" || { echo "FAIL --lab-units text"; fail=1; }

# A list option takes one value per flag: the files after `--models combined` are files, and
# `--bench-config` before them leaves them alone too.
files_fitted=$(timeout 60 "$bin" fit --json --models combined "$seed" "$seed" | python3 -c '
import json, sys
d = json.load(sys.stdin)
print(len(d["files"]), ",".join(m["name"] for f in d["files"] for r in f["runs"] for m in r["models"]))' 2>/dev/null || true)
[[ "$files_fitted" == "2 combined,combined" ]] || { echo "FAIL --models before two files gave '$files_fitted'"; fail=1; }
printf 'bench_id = "b"\n' >"$tmp/b.toml"
n_files=$(timeout 60 "$bin" fit --json --bench-config "$tmp/b.toml" "$seed" "$seed" 2>"$tmp/bc.err" |
  python3 -c 'import json, sys; print(len(json.load(sys.stdin)["files"]))' 2>/dev/null || true)
[[ "$n_files" == 2 ]] || { echo "FAIL --bench-config before two files fitted '$n_files': $(head -c 300 "$tmp/bc.err")"; fail=1; }
# J must be below 10 kg·m², as the message says: 10 itself is bad usage.
rc=0
timeout 60 "$bin" fit --inertia 10 "$seed" >/dev/null 2>"$tmp/j10.err" || rc=$?
[[ $rc -eq 2 ]] && grep -q "below 10" "$tmp/j10.err" || { echo "FAIL --inertia 10 gave rc $rc: $(head -c 300 "$tmp/j10.err")"; fail=1; }

# The same run as CSV in seconds and rpm, columns named by the user.
python3 - "$seed" "$tmp/seed.csv" <<'PY'
import math, sys
src, dst = sys.argv[1:]
kb = 1 / 123.569311
with open(src, newline="") as f, open(dst, "w") as out:
    out.write("when,speed\n")
    for line in f:
        parts = line.strip().split("\t")
        try:
            t, v = int(parts[0]), float(parts[1])
        except (ValueError, IndexError):
            continue
        out.write(f"{t / 1000:.3f},{v / kb * 60 / (2 * math.pi):.3f}\n")
PY
read -r c3c c4c _ _ < <(coefficients "$tmp/seed.csv" --time-column when --value-column speed --time-unit s \
  --value-unit rpm --delimiter ,)
if ! python3 -c '
import sys
c3, c4, c3c, c4c = map(float, sys.argv[1:])
ok = abs(c3c - c3) < 0.02 * c3 and abs(c4c - c4) < 0.02 * c4
print(("ok" if ok else "FAIL") + f" CSV in rpm: c3 {c3c:.5g} vs {c3:.5g}, c4 {c4c:.5g} vs {c4:.5g}")
sys.exit(0 if ok else 1)' "$c3" "$c4" "${c3c:-nan}" "${c4c:-nan}"; then fail=1; fi
exit $fail
