#!/usr/bin/env bash
# The library's modules as CMake sees them (cmake --graphviz): every module links only modules
# listed before it in core/CMakeLists.txt; no physics module (models to report: the readers, the
# run finding, the fits, explain, health, serial, config, the reports) nor base or runtime reaches
# LCM or the message types, directly or through another module; and the transport reaches no
# physics: bus links none of them, and logio (all spindown-logger links) reaches neither NLopt nor
# toml++.
set -euo pipefail
src="${SPINDOWN_SOURCE_DIR:?}"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

cmake -S "$src" -B "$tmp/build" -DSPINDOWN_BUILD_TESTS=OFF -DSPINDOWN_BUILD_BENCH=OFF \
  --graphviz="$tmp/graph.dot" >"$tmp/configure.log" 2>&1 || { cat "$tmp/configure.log"; exit 1; }

python3 - "$tmp/graph.dot" "$src/core/CMakeLists.txt" <<'PY'
import re, sys
dot, core_cmake = open(sys.argv[1]).read(), open(sys.argv[2]).read()
order = re.findall(r'^spindown_module\((\w+)', core_cmake, re.M)
assert len(order) >= 10, f"modules not found in core/CMakeLists.txt: {order}"
label = dict(re.findall(r'"(node\d+)" \[ label = "([^"]+)"', dot))
edges = {}
for a, b in re.findall(r'"(node\d+)" -> "(node\d+)"', dot):
    edges.setdefault(label[a], set()).add(label[b])
def reach(t):
    seen, todo = set(), [t]
    while todo:
        for n in edges.get(todo.pop(), ()):
            if n not in seen:
                seen.add(n); todo.append(n)
    return seen
bad = []
physics = order[order.index("bus") + 1:order.index("report") + 1]
assert "fit" in physics and "bus" not in physics, f"unexpected module order: {order}"
for i, m in enumerate(order):
    target = "spindown_" + m
    if target not in edges and m != "base":
        bad.append(f"{target}: not in the graph")
    for d in edges.get(target, ()):
        if d.startswith("spindown_") and d != "spindown_lcmtypes":
            dm = d[len("spindown_"):]
            if dm not in order[:i]:
                bad.append(f"{target} links {d}, which is not below it")
    reached = reach(target)
    lcm = {"PkgConfig::LCM", "spindown_lcmtypes"} & reached
    no_lcm = m in physics or m in ("base", "runtime")
    if no_lcm and lcm:
        bad.append(f"{target} reaches {sorted(lcm)}")
    if m == "bus":
        if not lcm:
            bad.append("spindown_bus does not link LCM: the check would prove nothing")
        if {"spindown_" + p for p in physics} & reached:
            bad.append(f"spindown_bus reaches the physics: {sorted({'spindown_' + p for p in physics} & reached)}")
    if m == "logio":
        heavy = {"NLopt::nlopt", "tomlplusplus::tomlplusplus"} & reached
        if heavy:
            bad.append(f"spindown_logio (the logger's) reaches {sorted(heavy)}")
    deps = sorted(d[len('spindown_'):] if d.startswith('spindown_') else d for d in edges.get(target, ()))
    print(f"{m:9} {'(no LCM)' if no_lcm else '        '} -> {', '.join(deps)}")
if bad:
    print("\n".join(["module graph violations:"] + bad)); sys.exit(1)
print(f"module graph: {len(order)} modules in order; no physics module reaches LCM, the transport reaches no physics")
PY

# And the program: spindown-logger as built loads neither NLopt nor toml++ (issue 42).
logger="${SPINDOWN_BIN_DIR:?}/spindown-logger"
[ -x "$logger" ] || { echo "no $logger"; exit 1; }
if ldd "$logger" | grep -Ei 'nlopt|toml'; then
  echo "spindown-logger loads the physics' libraries (above)"; exit 1
fi
echo "spindown-logger: $(ldd "$logger" | wc -l) shared libraries, neither NLopt nor toml++"

