#!/usr/bin/env bash
# Benchmark of volume meshing (paper 3.3) on the phantom: thorax mesh at the paper's
# sizes (high: ~82,000 nodes / 500,000 tetrahedra; medium: ~22,000 / 130,000) and at
# 2,000,000 tetrahedra, with wall time, peak memory and the check; beside it TetGen
# 1.5 meshing the same surfaces (constrained, boundary preserved: tetgen -pY).
# Prints figures; never fails on time.
set -euo pipefail
cd "$(dirname "$0")/.."
THORAX=${THORAX:-build/bin/thorax}
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
[ -x "$THORAX" ] || { echo "build first (make)"; exit 1; }
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')"
for res in medium high; do
    "$THORAX" phantom --resolution $res --seed 1 -o "$W/c_$res.txt" -q
    "$THORAX" surfaces "$W/c_$res.txt" -o "$W/m_$res" -q
done
run() { # LABEL MODEL ARGS...
    local label=$1 model=$2; shift 2
    /usr/bin/time -f "%e %M" -o "$W/t" "$THORAX" mesh "$model" -o "$W/out" --stats "$@" > "$W/log"
    read -r wall rss < "$W/t"
    echo "thorax mesh $label: $(head -1 "$W/log")"
    echo "    wall $wall s, peak memory $((rss / 1024)) MB; $(grep 'times (s)' "$W/log" | sed 's/.*times (s): /stages (s): /')"
    grep '^repair' "$W/log" | sed 's/^/    /' || true
    /usr/bin/time -f "%e" -o "$W/tc" "$THORAX" check "$W/out" -q && c=pass || c=FAIL
    echo "    thorax check: $c ($(cat "$W/tc") s)"
}
run "medium" "$W/m_medium"
run "high" "$W/m_high"
run "high, about 2 M tetrahedra (planes 2.5 mm apart, grid 3.9 mm)" "$W/m_high" --layer-spacing 2.5 --grid 3.9
# TetGen on the same surfaces, as one piecewise-linear complex
/usr/bin/python3 - "$W/m_high" "$W/ph.poly" <<'PYEOF'
import json, os, sys
d, out = sys.argv[1], sys.argv[2]
m = json.load(open(os.path.join(d, "model.json")))
nodes, facets = [], []
for s in m["surfaces"]:
    off = len(nodes)
    nodes += [l.split() for l in open(os.path.join(d, s["pts"])) if l.strip()]
    facets += [[int(x) + off for x in l.split()] for l in open(os.path.join(d, s["fac"])) if l.strip()]
with open(out, "w") as f:
    f.write("%d 3 0 0\n" % len(nodes))
    for i, n in enumerate(nodes): f.write("%d %s %s %s\n" % (i + 1, n[0], n[1], n[2]))
    f.write("%d 0\n" % len(facets))
    for t in facets: f.write("1\n3 %d %d %d\n" % tuple(t))
    f.write("0\n0\n")
PYEOF
(cd "$W" && /usr/bin/time -f "%e %M" -o t tetgen -pYQ ph.poly)
read -r wall rss < "$W/t"
echo "peer: TetGen 1.5 -pY on the same high-resolution surfaces: $(head -1 "$W/ph.1.ele" | awk '{print $1}') tetrahedra, $(head -1 "$W/ph.1.node" | awk '{print $1}') nodes, wall $wall s, peak memory $((rss / 1024)) MB"
echo "    (constrained: its boundary is exactly the surface triangles; no interior grid)"
