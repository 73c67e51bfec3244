#!/usr/bin/env bash
# Benchmark of volume meshing (paper 3.3): thorax mesh beside TetGen 1.5 (tetgen -pq1.414/10: a
# constrained, quality tetrahedralization of the same surfaces) in the same run, on the phantom
# (medium, high) and, when the shared data are beside the checkout, the Utah tank + sock, the
# Dalhousie torso + epicardium, OpenMEEG's Head1-3, nested icospheres, and the tank, the Dalhousie
# torso and Head3 rebuilt from contours that thorax slice cuts 10 mm apart (issue 10, item 4). For each: tetrahedra, wall time, peak memory,
# tetrahedra per second and their ratio, and the quality of both meshes measured by one program
# (bench/tet_quality.py: smallest dihedral, counts below 5 and 10 degrees, largest and mean
# radius-edge ratio). thorax's mesh is also judged by thorax check. Prints figures; never fails
# on time.
set -euo pipefail
cd "$(dirname "$0")/.."
THORAX=${THORAX:-build/bin/thorax}
PY=/usr/bin/python3
DATA=${THORAX_DATA:-../shared/data}
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
[ -x "$THORAX" ] || { echo "build first (make)"; exit 1; }
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')"

models=()
for res in medium high; do
    "$THORAX" phantom --resolution $res --seed 1 -o "$W/c_$res.txt" -q
    "$THORAX" surfaces "$W/c_$res.txt" -o "$W/m_$res" -q
    models+=("phantom-$res:$W/m_$res")
done
if [ -d "$DATA/map3d/geom" ]; then
    G=$DATA/map3d/geom
    "$THORAX" import -o "$W/m_tank" -q "$G/tank/tank_full_771.pts" --name tank --role outer \
        "$G/tank/25feb97_sock_closed.pts" --name sock --role heart && models+=("utah-tank+sock:$W/m_tank")
    "$THORAX" import -o "$W/m_dal" -q "$G/torso/daltorso.pts" --name torso --role outer \
        "$G/torso/dalepi.pts" --name epicardium --role heart && models+=("dalhousie+epi:$W/m_dal")
fi
HD=$DATA/openmeeg-spheres/data
for n in 1 2 3; do
    [ -d "$HD/Head$n" ] || continue
    # OpenMEEG .tri, radius 1 -> 100 mm
    "$THORAX" import -o "$W/m_head$n" -q --scale 100 "$HD/Head$n/scalp.$n.tri" --name scalp --role outer \
        "$HD/Head$n/skull.$n.tri" --name skull --role other "$HD/Head$n/cortex.$n.tri" --name brain --role other &&
        models+=("openmeeg-head$n:$W/m_head$n")
done
# nested icospheres (radii 100, 80, 50 mm; 642 vertices each)
(root=$PWD; cd "$W" && $PY "$root/tests/icospheres.py")
"$THORAX" import -o "$W/m_ico" -q "$W/ico_out.pts" --name out --role outer "$W/ico_mid.pts" --name mid --role other \
    "$W/ico_in.pts" --name in --role other && models+=("icospheres:$W/m_ico")
# models rebuilt from contours that thorax slice cuts from these surfaces (10 mm apart)
for src in tank dal head3; do
    [ -d "$W/m_$src" ] || continue
    "$THORAX" slice "$W/m_$src" --spacing 10 -o "$W/c_$src.txt" -q && "$THORAX" surfaces "$W/c_$src.txt" -o "$W/m_${src}_sliced" -q &&
        models+=("$src-sliced:$W/m_${src}_sliced")
done

poly() { # MODEL OUT.poly: the model's surfaces as one piecewise-linear complex
    $PY - "$1" "$2" <<'PYEOF'
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
}

printf "\n%-18s %-7s %9s %8s %8s %9s %7s %6s %6s %7s %6s %s\n" dataset program tets wall_s peak_MB tets/s min_deg "<5" "<10" maxRE meanRE check
for entry in "${models[@]}"; do
    name=${entry%%:*}; model=${entry#*:}
    /usr/bin/time -f "%e %M" -o "$W/t" "$THORAX" mesh "$model" -o "$W/out" --stats > "$W/log" 2>&1 || { echo "$name: thorax mesh FAILED: $(tail -1 "$W/log")"; continue; }
    read -r wall rss < "$W/t"
    "$THORAX" check "$W/out" -q > /dev/null 2>&1 && c=pass || c=FAIL
    read -r n dm b5 b10 remax remean <<< "$($PY bench/tet_quality.py thorax "$W/out")"
    rate_t=$($PY -c "print(round($n / max($wall, 1e-3)))")
    printf "%-18s %-7s %9d %8.2f %8d %9d %7.2f %6d %6d %7.2f %6.3f %s\n" "$name" thorax "$n" "$wall" $((rss / 1024)) "$rate_t" "$dm" "$b5" "$b10" "$remax" "$remean" "$c"
    grep -E '^(conformity|refinement|repair)' "$W/log" | sed 's/^/        /'
    poly "$model" "$W/p.poly"
    if (cd "$W" && /usr/bin/time -f "%e %M" -o tt tetgen -pq1.414/10 -Q p.poly > tlog 2>&1); then
        read -r wall2 rss2 < "$W/tt"
        read -r n2 dm2 b52 b102 remax2 remean2 <<< "$($PY bench/tet_quality.py tetgen "$W/p.1")"
        rate_g=$($PY -c "print(round($n2 / max($wall2, 1e-3)))")
        printf "%-18s %-7s %9d %8.2f %8d %9d %7.2f %6d %6d %7.2f %6.3f\n" "" tetgen "$n2" "$wall2" $((rss2 / 1024)) "$rate_g" "$dm2" "$b52" "$b102" "$remax2" "$remean2"
        echo "        ratio thorax/tetgen: tetrahedra per second $($PY -c "print('%.2f' % ($rate_t / $rate_g))"), wall $($PY -c "print('%.2f' % ($wall / max($wall2, 1e-3)))")"
    else
        echo "        tetgen -pq1.414/10 failed: $(tail -1 "$W/tlog")"
    fi
    rm -rf "$W/out" "$W"/p.*
done
