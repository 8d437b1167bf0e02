# Sourced by deploy/run-tests and deploy/run-lab: phase NAME COMMAND... runs the command and says
# on stderr how long it took, so each step's share of the time to a first result is seen.
phase() {
  local name=$1 start=$SECONDS rc=0
  shift
  "$@" || rc=$?
  echo "[time] $name: $((SECONDS - start)) s$( ((rc == 0)) || echo " (failed, exit $rc)")" >&2
  return $rc
}

# configure_build DIR CMAKE_ARGS...: cmake -S <repository> -B DIR. A new DIR is configured for
# Ninja when it is there (deploy/setup installs ninja-build): Ninja compiles every module's sources
# as soon as their inputs exist, where Make builds one target after another, so both cores stay
# busy. An existing DIR keeps the generator it has; CMAKE_GENERATOR chooses another for a new one.
configure_build() {
  local dir=$1 generator=()
  shift
  if [[ ! -f $dir/CMakeCache.txt && -z ${CMAKE_GENERATOR:-} ]] && command -v ninja >/dev/null; then
    generator=(-G Ninja)
  fi
  cmake -S "$(dirname "${BASH_SOURCE[0]}")/.." -B "$dir" "${generator[@]}" "$@"
}
