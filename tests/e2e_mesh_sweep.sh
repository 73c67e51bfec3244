#!/usr/bin/env bash
# The mesher meshes every valid model (issue 24): the Utah tank with its closed sock placed 55 ways
# (scaled 0.90-1.10 about the sock's node centroid, times 11 shifts of up to 15 mm along each axis
# and the diagonals). Each placement is a valid model (`thorax check` passes on the surfaces), and
# `thorax mesh` with default options must give a volume that passes `thorax check`. Before the
# repair inserted nodes, scale 0.90 shifted -15 mm in y failed: a 0.22 deg sliver of four points of
# the tank's surface where two triangles meet nearly flat below the lid, 95 mm from the sock (and,
# in the issue's own sweep, 2 of 25 placements failed so). Also: `--quality 0 --repair 0` (the
# repair still runs at 5 deg) and `--repair 0` give meshes that pass the check at its default
# threshold (the tank's --quality 0 --repair 0 mesh had a 7.6e-7 deg sliver), and two runs of one
# placement give the same files.
# Under THORAX_QUICK (the sanitized build) every eleventh placement runs (5, the failing one among
# them), without --quality 0 alone and the second run; the plain build runs all 55 (93 s wall, about
# 90 s of CPU; two at a time).
set -uo pipefail
: "${THORAX:?}" "${SRC:?}" "${WORK:?}"
PY=/usr/bin/python3
DATA=${THORAX_DATA:-$SRC/../shared/data}
G=$DATA/map3d/geom/tank
[ -r "$G/25feb97_sock_closed.pts" ] || { echo "skip: $G not found (Utah tank)"; exit 0; }
rm -rf "$WORK" && mkdir -p "$WORK" && cd "$WORK"
fails=0
ok() { echo "ok: $1"; }
bad() { echo "FAIL: $1" >&2; fails=$((fails + 1)); }

# the placements: scale and shift (mm), one a line
: > list
for s in 0.90 0.95 1.00 1.05 1.10; do
    for sh in "0 0 0" "15 0 0" "-15 0 0" "0 15 0" "0 -15 0" "0 0 15" "0 0 -15" "10 10 10" "-10 -10 -10" "0 10 0" "5 -5 5"; do
        echo "$s $sh" >> list
    done
done
[ "$(wc -l < list)" -ge 50 ] || bad "fewer than 50 placements"
if [ -n "${THORAX_QUICK:-}" ]; then awk 'NR % 11 == 5' list > l2 && mv l2 list; fi

cat > place.py <<'EOF'
import sys
# place.py SRC.pts OUT.pts SCALE DX DY DZ: the sock scaled about its node centroid, then shifted (mm)
src, out, s, dx, dy, dz = sys.argv[1], sys.argv[2], *map(float, sys.argv[3:7])
P = [list(map(float, l.split())) for l in open(src) if l.strip()]
c = [sum(p[k] for p in P) / len(P) for k in range(3)]
with open(out, "w") as f:
    for p in P:
        f.write("%.6f %.6f %.6f\n" % tuple(c[k] + s * (p[k] - c[k]) + d for k, d in enumerate((dx, dy, dz))))
EOF

# one placement: prints "NAME ok MIN_DIHEDRAL", "NAME invalid" or "NAME FAIL why"
cat > one.sh <<'EOF'
s=$1 x=$2 y=$3 z=$4 n=p_$1_$2_$3_$4
$PY place.py "$G/25feb97_sock_closed.pts" $n.pts $s $x $y $z && cp "$G/25feb97_sock_closed.fac" $n.fac
"$THORAX" import -o m_$n -q "$G/tank_full_771.pts" --name tank --role outer $n.pts --name sock --role heart 2> imp_$n.err ||
    { echo "$n invalid (import: $(head -1 imp_$n.err))"; exit 0; }
"$THORAX" check m_$n -q 2> chk0_$n.err || { echo "$n invalid (check: $(head -1 chk0_$n.err))"; exit 0; }
"$THORAX" mesh m_$n -o v_$n -q 2> mesh_$n.err || { echo "$n FAIL mesh: $(head -1 mesh_$n.err)"; exit 0; }
"$THORAX" check v_$n > chk_$n.txt 2>&1 || { echo "$n FAIL check: $(grep -v '^ ' chk_$n.txt | tail -2 | tr '\n' ' ')"; exit 0; }
grep -q 'provenance.*"mesh"' v_$n/model.json && { echo "$n FAIL a lowered-bar warning in model.json"; exit 0; }
echo "$n ok $(awk '$1 == "volume" && $2 ~ /^[0-9]+$/ {print $8}' chk_$n.txt)"
rm -rf m_$n v_$n
EOF
export THORAX PY G
xargs -P 2 -L 1 bash one.sh < list > results.txt
sort results.txt
n=$(wc -l < list)
nok=$(grep -c ' ok ' results.txt)
ninv=$(grep -c ' invalid' results.txt)
[ "$ninv" -eq 0 ] || bad "$ninv placements are not valid models (the sweep must stay inside the tank)"
[ "$nok" -eq "$n" ] && ok "all $n placements mesh with default options and pass thorax check" ||
    bad "$((n - nok)) of $n placements failed: $(grep -v ' ok ' results.txt | tr '\n' ';')"
echo "smallest dihedral angle over the sweep: $(awk '$2 == "ok" {print $3}' results.txt | sort -g | head -1) deg"

# the one that failed before, with the options that mean "off", and twice for determinism
n=p_0.90_0_-15_0
"$THORAX" import -o m_$n -q "$G/tank_full_771.pts" --name tank --role outer $n.pts --name sock --role heart || bad "import $n"
variants=("--quality 0 --repair 0" "--repair 0" "--quality 0")
[ -n "${THORAX_QUICK:-}" ] && variants=("--quality 0 --repair 0" "--repair 0")
for o in "${variants[@]}"; do
    tag=$(echo "$o" | tr -d ' -')
    if "$THORAX" mesh m_$n -o v_$tag $o -q 2> mesh_$tag.err && "$THORAX" check v_$tag -q 2> chk_$tag.err; then
        ok "$n $o: passes thorax check at its default threshold"
    else bad "$n $o: $(cat mesh_$tag.err chk_$tag.err | head -3)"; fi
done
if [ -z "${THORAX_QUICK:-}" ]; then
    "$THORAX" mesh m_$n -o v_a -q && "$THORAX" mesh m_$n -o v_b -q && cmp -s v_a/volume.pts v_b/volume.pts &&
        cmp -s v_a/volume.tet v_b/volume.tet && cmp -s v_a/volume.steiner v_b/volume.steiner &&
        ok "$n: two runs give the same files" || bad "$n: two runs differ"
fi

[ $fails -eq 0 ] || { echo "$fails failed"; exit 1; }
echo "all passed"
