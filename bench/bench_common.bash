# Sourced by the bench scripts.

# bench_work_dir NAME: WORK is $KEEP (created, kept) or a new /tmp/spindown-NAME.* removed on exit.
bench_work_dir() {
  if [[ -n ${KEEP:-} ]]; then
    WORK=$KEEP
    mkdir -p "$WORK"
  else
    WORK=$(mktemp -d "/tmp/spindown-$1.XXXXXX")
    trap 'rm -rf "$WORK"' EXIT
  fi
}

# generated_runs BIN_DIR COUNT: COUNT lab runs written by BIN_DIR/make_runs into $WORK/runs (seed
# 1; it prints one line), their paths in FILES, read once so both sides find them in the page cache.
generated_runs() {
  "$1/make_runs" "$WORK/runs" "$2" 1
  mapfile -t FILES < <(tail -n +2 "$WORK/runs/index.tsv" | cut -f1 | sed "s|^|$WORK/runs/|")
  cat "${FILES[@]}" >/dev/null
}

# wall_us OUT ERR CMD...: CMD's wall time in microseconds, its stdout to OUT and stderr appended
# to ERR. The clock is bash's own EPOCHREALTIME: a `date` process on each side of CMD would add
# its own start-up (~1.2 ms here) to every figure, most of all to the fastest.
wall_us() {
  local t0 t1
  t0=${EPOCHREALTIME/[.,]/}
  "${@:3}" >"$1" 2>>"$2" || true
  t1=${EPOCHREALTIME/[.,]/}
  echo $((t1 - t0))
}
