# The browser tests' common set-up (web_browser.sh, web_room_screens.sh), sourced after they set
# src, LAB_BIN, LAB_WORK and NODE_MODULES: the lab helpers, a cleanup that stops what the test
# started, fail() with the services' last words, and Chromium, node and puppeteer-core present
# (deploy/setup --tests installs them: a failure, never a skip). Sets chrome.
source "$src/deploy/lab/lab.bash"
browser_cleanup() {
  lab_stop_all
  if [[ -z ${KEEP_WORK:-} ]]; then rm -rf "$LAB_WORK"; else echo "work dir kept: $LAB_WORK"; fi
}
trap browser_cleanup EXIT
fail() {
  echo "FAIL: $*" >&2
  for f in "$LAB_WORK"/*.err; do [[ -s $f ]] && { echo "--- $f" >&2; tail -8 "$f" >&2; }; done
  exit 1
}
chrome=$(command -v chromium || true)
[[ -n $chrome ]] || fail "chromium is not installed (deploy/setup --tests installs it)"
command -v node >/dev/null || fail "node is not installed (deploy/setup --tests installs nodejs)"
[[ -f $NODE_MODULES/puppeteer-core/package.json ]] ||
  fail "puppeteer-core is not in $NODE_MODULES (deploy/setup --tests installs it; SPINDOWN_NODE_MODULES names another place)"
