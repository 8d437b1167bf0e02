#!/usr/bin/env bash
# The library's modules as CMake sees them (cmake --graphviz): every module links only modules
# listed before it in core/CMakeLists.txt, and no module below `bus` (the physics, the readers,
# the run finding, the fits, explain, health, serial, config, the reports) reaches LCM or the
# message types, directly or through another module.
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
for i, m in enumerate(order):
    target = "spindown_" + m
    if target not in edges and m != "base":
        bad.append(f"{target}: not in the graph")
    for d in edges.get(target, ()):
        if d.startswith("spindown_") and d != "spindown_lcmtypes":
            dm = d[len("spindown_"):]
            if dm not in order[:i]:
                bad.append(f"{target} links {d}, which is not below it")
    lcm = {"PkgConfig::LCM", "spindown_lcmtypes"} & reach(target)
    below_bus = i < order.index("bus")
    if below_bus and lcm:
        bad.append(f"{target} reaches {sorted(lcm)}")
    if not below_bus and m == "bus" and not lcm:
        bad.append("spindown_bus does not link LCM: the check would prove nothing")
    deps = sorted(d[len('spindown_'):] if d.startswith('spindown_') else d for d in edges.get(target, ()))
    print(f"{m:9} {'(no LCM)' if below_bus else '        '} -> {', '.join(deps)}")
if bad:
    print("\n".join(["module graph violations:"] + bad)); sys.exit(1)
print(f"module graph: {len(order)} modules in order; none below bus reaches LCM")
PY
