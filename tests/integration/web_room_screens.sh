#!/usr/bin/env bash
# The room page on the screens a lab has, in a real browser: spindown-web in a private network
# namespace, spindown-lcm-publish playing N benches' FITs and samples, Debian's Chromium
# (headless, puppeteer-core: tests/integration/web_room_screens.js) at each size. Checked:
#   - 40 benches at 1920x1080, 30 at 1366x768, 22 at 1280x720: the page does not scroll; every
#     tile lies wholly on the screen, no two overlap; every bench's name is whole inside its tile,
#     on top, in a font of at least 14 px; c3 and c4 are whole inside the tile;
#   - 4 benches at 1280x720: the tiles grow to use the screen (at least 30 % of it) and show the
#     whole tile (the run's curve included);
#   - a phone (390x844): the room scrolls as a list, never sideways.
# Screenshots are kept (SPINDOWN_WEB_ARTIFACTS, default build/web-room/).
set -euo pipefail
if [[ -z ${SPINDOWN_IN_NETNS:-} ]]; then
  export SPINDOWN_IN_NETNS=1
  exec timeout 200 unshare -n bash "$0" "$@"
fi
src=${SPINDOWN_SOURCE_DIR:-$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)}
LAB_BIN=${SPINDOWN_BIN_DIR:?SPINDOWN_BIN_DIR not set}
LAB_WORK=$(mktemp -d /tmp/spindown-web-room.XXXXXX)
ART=${SPINDOWN_WEB_ARTIFACTS:-$LAB_BIN/../web-room}
NODE_MODULES=${SPINDOWN_NODE_MODULES:-/opt/spindown-test-node/node_modules}
source "$src/tests/integration/browser_common.bash"
for b in spindown-web spindown-lcm-publish; do [[ -x $LAB_BIN/$b ]] || fail "$LAB_BIN/$b is missing"; done

ip link set lo up
ip route add 224.0.0.0/4 dev lo
rm -rf "$ART"
mkdir -p "$ART"
# One lab per room size, each its own channel group and port: N benches publishing for 60 s.
room() {  # room NAME BENCHES GROUP_PORT HTTP_PORT
  local url="udpm://239.255.76.67:$3?ttl=0"
  lab_start - "web-$1" "$LAB_BIN/spindown-web" --lcm-url "$url" --listen "127.0.0.1:$4"
  lab_start - "pub-$1" "$LAB_BIN/spindown-lcm-publish" --lcm-url "$url" --benches "$2" --count 0 --rate 5 \
    --duration 90 --all-types
}
room r40 40 7681 18240
room r30 30 7682 18241
room r22 22 7683 18242
room r4 4 7684 18243
lab_wait "grep -q serving '$LAB_WORK/web-r40.err' && grep -q serving '$LAB_WORK/web-r4.err'" 30 ||
  fail "spindown-web did not start"
NODE_PATH="$NODE_MODULES" timeout 150 node "$src/tests/integration/web_room_screens.js" --chrome "$chrome" \
  --out "$ART" --room "http://127.0.0.1:18240/,1920,1080,40" --room "http://127.0.0.1:18241/,1366,768,30" \
  --room "http://127.0.0.1:18242/,1280,720,22" --small "http://127.0.0.1:18243/,1280,720,4" \
  --phone "http://127.0.0.1:18241/" || fail "the room page on the lab's screens (above)"
echo "PASS: the room fits 1920x1080 (40), 1366x768 (30), 1280x720 (22, and 4 grown), and a phone"
