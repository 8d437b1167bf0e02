# Sourced by deploy/run-tests and deploy/run-lab: phase NAME COMMAND... runs the command and says
# on stderr how long it took, so each step's share of the time to a first result is seen.
phase() {
  local name=$1 start=$SECONDS rc=0
  shift
  "$@" || rc=$?
  echo "[time] $name: $((SECONDS - start)) s$( ((rc == 0)) || echo " (failed, exit $rc)")" >&2
  return $rc
}
