#!/usr/bin/env bash
# `spindown fit` on every sample file: exit 0, valid JSON with design §5's keys, a readable
# table naming the best model; on the pure combined-friction files the CLI reproduces the
# truth (c3, c4 within 5 %, the cut within one sample period).
set -euo pipefail
bin="${SPINDOWN_BIN_DIR:?}/spindown"
data="${SPINDOWN_SAMPLE_DATA:?}"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# The samples are the project's simulator's output: made again, they are byte for byte the same.
src="${SPINDOWN_SOURCE_DIR:?}"
mkdir -p "$tmp/regen"
"$src/data/make-samples" "$(dirname "$bin")" "$tmp/regen" >/dev/null
for f in "$data"/*.tsv "$data"/*.truth.json; do
  cmp -s "$f" "$tmp/regen/$(basename "$f")" ||
    { echo "FAIL: $(basename "$f") differs from what data/make-samples makes now (re-run it and say why)"; exit 1; }
done
[[ $(ls "$tmp/regen" | wc -l) == $(ls "$data"/*.tsv "$data"/*.truth.json | wc -l) ]] ||
  { echo "FAIL: data/make-samples makes other files than data/ holds"; exit 1; }
echo "ok: data/ is what data/make-samples makes"

shopt -s nullglob
files=("$data"/*.tsv)
((${#files[@]} > 0)) || { echo "FAIL: no sample files in $data"; exit 1; }

fail=0
for f in "${files[@]}"; do
  name=$(basename "$f")
  rc=0
  timeout 60 "$bin" fit --json "$f" >"$tmp/out.json" 2>"$tmp/err" || rc=$?
  if ((rc != 0)); then
    echo "FAIL $name: --json exit $rc"; cat "$tmp/err"; fail=1; continue
  fi
  strict=0
  case "$name" in seed-3v-run1.tsv | seed-3v5-run2.tsv | offset-example.tsv) strict=1 ;; esac
  if ! python3 - "$tmp/out.json" "$f" "$strict" <<'PY'
import json, math, sys
out, path, strict = sys.argv[1], sys.argv[2], sys.argv[3] == "1"
doc = json.load(open(out))  # raises on invalid JSON
problems = []
def need(cond, what):
    if not cond: problems.append(what)
files = doc["files"]
need(len(files) == 1 and files[0]["file"] == path, "one file entry naming the file")
runs = files[0]["runs"]
need(len(runs) >= 1, "at least one run")
for run in runs:
    for key in ("run", "t_cut_s", "t_stop_s", "samples", "models", "best"):
        need(key in run, f"run key {key}")
    need(isinstance(run["t_cut_s"], float), "t_cut_s is a number")
    need(isinstance(run["samples"], int) and run["samples"] > 100, "samples > 100")
    names = [m["name"] for m in run["models"]]
    need(names == ["viscous", "coulomb", "combined"], f"models in order, got {names}")
    need(run["best"] in names, "best names a model")
    for m in run["models"]:
        for key in ("name", "params", "rmse", "residual_unit", "r2", "aic", "bic"):
            need(key in m, f"{m['name']}: key {key}")
        need(m["residual_unit"] == "V", "residual_unit V")
        for pname, p in m["params"].items():
            need(set(("value", "stderr", "unit")) <= set(p), f"{m['name']}.{pname} has value/stderr/unit")
    units = {m["name"]: {k: p["unit"] for k, p in m["params"].items()} for m in run["models"]}
    need(units["viscous"].get("c1") == "N*m*s/rad", "c1 unit")
    need(units["coulomb"].get("c2") == "N*m", "c2 unit")
    need(units["combined"].get("c3") == "N*m*s/rad" and units["combined"].get("c4") == "N*m", "c3/c4 units")
    need(all(k in units["combined"] for k in ("A", "B", "C")), "combined curve constants A, B, C")
    need([m for m in run["models"] if m["name"] == "viscous"][0]["t_stop_pred_s"] is None,
         "viscous never stops: t_stop_pred_s null")
if strict and not problems:
    truth = json.load(open(path + ".truth.json"))
    run = runs[0]
    comb = [m for m in run["models"] if m["name"] == "combined"][0]["params"]
    for key, true in (("c3", truth["c_v"]), ("c4", truth["c_c"])):
        got = comb[key]["value"]
        need(abs(got - true) <= 0.05 * true, f"{key} = {got:.5g} not within 5 % of truth {true:.5g}")
    t_cut = truth["runs"][0].get("connect_device_us", truth["runs"][0]["cut_device_us"]) / 1e6  # a floating pin: its connection
    need(abs(run["t_cut_s"] - t_cut) <= 0.025, f"cut {run['t_cut_s']} s vs truth {t_cut} s")
if problems:
    print("\n".join(problems)); sys.exit(1)
PY
  then
    echo "FAIL $name: JSON does not meet the contract"; fail=1; continue
  fi

  # Text: the table and the verdict.
  rc=0
  timeout 60 "$bin" fit "$f" >"$tmp/out.txt" 2>"$tmp/err" || rc=$?
  if ((rc != 0)); then echo "FAIL $name: text exit $rc"; fail=1; continue; fi
  for want in "== $f" "run 1:" "viscous" "coulomb" "combined" "c3 = " "c4 = " "RMSE" "BIC" "best: "; do
    grep -qF -- "$want" "$tmp/out.txt" || { echo "FAIL $name: text lacks '$want'"; fail=1; }
  done
  echo "ok $name"
done

# All files at once: one JSON object with one entry per file, in order.
rc=0
timeout 120 "$bin" fit --json "${files[@]}" >"$tmp/all.json" 2>/dev/null || rc=$?
count=$(python3 -c 'import json,sys; print(len(json.load(open(sys.argv[1]))["files"]))' "$tmp/all.json" || echo 0)
if ((rc != 0 || count != ${#files[@]})); then
  echo "FAIL all files: exit $rc, $count file entries for ${#files[@]} files"; fail=1
fi

# Several files fitted at once (--jobs) give the very same output, in the order given, as one
# at a time: text and JSON, the files listed twice over so workers finish out of order.
for fmt in "" "--json"; do
  rc1=0 rc3=0
  timeout 120 "$bin" fit $fmt -j 1 "${files[@]}" "${files[@]}" >"$tmp/serial" 2>"$tmp/serial.err" || rc1=$?
  timeout 120 "$bin" fit $fmt -j 3 "${files[@]}" "${files[@]}" >"$tmp/parallel" 2>"$tmp/parallel.err" || rc3=$?
  # Both must have worked (a rejected -j would give two identical usage errors) …
  if ((rc1 != 0 || rc3 != 0)) || [[ ! -s $tmp/serial ]]; then
    echo "FAIL fit $fmt -j: exit $rc1 (-j 1), $rc3 (-j 3)"; fail=1
  fi
  # … and given the same bytes, in the same order.
  if ! cmp -s "$tmp/serial" "$tmp/parallel" || ! cmp -s "$tmp/serial.err" "$tmp/parallel.err"; then
    echo "FAIL fit $fmt -j 3 differs from -j 1"; fail=1
  fi
done
python3 -c 'import json,sys; d=json.load(open(sys.argv[1])); sys.exit(0 if len(d["files"]) == 2 * int(sys.argv[2]) else 1)' \
  "$tmp/parallel" "${#files[@]}" || { echo "FAIL fit --json -j 3: not one entry per file given"; fail=1; }

# Into a file --json goes out in pieces as the files are done, compact; on a terminal it is printed
# once at the end, indented. Both are the same document: the files listed often enough that the JSON is several
# pieces long (more than 256 kB), the terminal a real pty (script), its CR LF made LF again.
many=()
for ((k = 0; k < 20; ++k)); do many+=("${files[@]}"); done
rc=0
timeout 120 "$bin" fit --json "${many[@]}" >"$tmp/many.file" 2>/dev/null || rc=$?
printf -v cmd '%q ' "$bin" fit --json "${many[@]}"
timeout 120 script -qec "$cmd 2>/dev/null" /dev/null </dev/null | tr -d '\r' >"$tmp/many.tty" || true
size=$(stat -c %s "$tmp/many.file")
if ((rc != 0 || size <= 256 * 1024)); then
  echo "FAIL fit --json into a file: exit $rc, $size bytes (more than 256 kB wanted)"; fail=1
elif ! /usr/bin/python3 - "$tmp/many.file" "$tmp/many.tty" <<'PY'; then
import json, sys
piped, tty = (open(p, encoding="utf-8").read() for p in sys.argv[1:3])
assert json.loads(piped) == json.loads(tty), "a file and a terminal get different documents"
# Into a file it is compact (no layout whitespace), on a terminal indented for reading.
assert "\n " not in piped and len(piped) < 0.75 * len(tty), "the file's JSON is not compact: %d vs %d bytes" % (len(piped), len(tty))
assert "\n  " in tty, "the terminal's JSON is not indented"
PY
  echo "FAIL fit --json: a file and a terminal (see above)"; fail=1
fi
exit $fail
