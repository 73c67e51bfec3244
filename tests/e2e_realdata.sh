#!/bin/bash
# Real surfaces from the Utah torso-tank experiments (shared/data/map3d): the closed
# tank surface and the closed epicardial sock are cut into contours (`thorax slice`),
# rebuilt (`thorax surfaces`), checked (`thorax check`), and compared with the
# originals: enclosed volume and the distance of every rebuilt node to the original
# surface (tests/surface_compare.py).
# Environment: THORAX = the CLI, SRC = the source tree, WORK = a scratch directory.
set -u
: "${THORAX:?}" "${SRC:?}" "${WORK:?}"
DATA="$SRC/../shared/data/map3d/geom/tank"
PY=/usr/bin/python3
rm -rf "$WORK"
mkdir -p "$WORK"
fails=0
ok() { echo "ok: $1"; }
bad() { echo "FAIL: $1" >&2; fails=$((fails + 1)); }
[ -f "$DATA/tank_full_771.pts" ] || { echo "FAIL: data missing: $DATA" >&2; exit 1; }

# model NAME ROLE PTS FAC: a model directory holding one surface read from the data folder
model() {
    local d="$WORK/$1"
    mkdir -p "$d"
    cp "$3" "$d/$1.pts"
    cp "$4" "$d/$1.fac"
    printf '{"format": "thorax-model", "version": 1, "units": "mm", "surfaces": [{"name": "%s", "role": "%s", "pts": "%s.pts", "fac": "%s.fac", "n_nodes": %d, "n_tris": %d}]}\n' \
        "$1" "$2" "$1" "$1" "$(grep -c . "$3")" "$(grep -c . "$4")" > "$d/model.json"
}

# round_trip NAME SPACING VOL DIST CAP_DIST MAX_ASPECT
round_trip() {
    local n=$1
    "$THORAX" check "$WORK/$n" -q && ok "$n: the original passes thorax check" || bad "$n: original fails thorax check"
    if "$THORAX" slice "$WORK/$n" --spacing "$2" -o "$WORK/$n.txt" -q &&
       "$THORAX" surfaces "$WORK/$n.txt" -o "$WORK/${n}_rebuilt" -q; then ok "$n: sliced and rebuilt"; else bad "$n: slice/rebuild"; return; fi
    "$THORAX" check "$WORK/${n}_rebuilt" -q --max-aspect "$6" && ok "$n: rebuilt surface passes thorax check (aspect ratio <= $6)" || bad "$n: rebuilt surface fails thorax check"
    if (cd "$WORK" && $PY "$SRC/tests/surface_compare.py" "$n/$n.pts" "$n/$n.fac" "${n}_rebuilt/$n.pts" "${n}_rebuilt/$n.fac" \
            --vol "$3" --dist "$4" --cap-band 0.01 --cap-dist "$5"); then ok "$n: matches the original"; else bad "$n: differs from the original"; fi
}

model tank outer "$DATA/tank_full_771.pts" "$DATA/tank_full_771.fac"
round_trip tank 5 0.005 1.0 0.6 5
model sock heart "$DATA/25feb97_sock_closed.pts" "$DATA/25feb97_sock_closed.fac"
round_trip sock 3 0.015 1.0 1.0 10

# the contours of the tank are what a digitizer would give: every loop closed, counterclockwise
# when the surface is oriented outward; reversing the surface's triangles is detected by slice
awk '{print $1, $3, $2}' "$WORK/tank/tank.fac" > "$WORK/rev.fac"
model tank_reversed outer "$DATA/tank_full_771.pts" "$WORK/rev.fac"
"$THORAX" slice "$WORK/tank_reversed" -o "$WORK/rev.txt" -q
"$THORAX" surfaces "$WORK/rev.txt" -o "$WORK/rev_rebuilt" -q && "$THORAX" check "$WORK/rev_rebuilt" -q &&
    ok "a reversed surface slices into clockwise loops, which rebuild outward all the same" || bad "reversed surface"

# the tank with the closed sock inside, imported and meshed (grid planes at the grid spacing):
# the volume passes thorax check (conforming, closed, positive, within 1% of the tank's volume)
if "$THORAX" import -o "$WORK/tanksock" "$DATA/tank_full_771.pts" --name tank --role outer \
        "$DATA/25feb97_sock_closed.pts" --name sock --role heart -q &&
   "$THORAX" mesh "$WORK/tanksock" --grid 10 -q && "$THORAX" check "$WORK/tanksock" -q; then
    ok "tank and sock imported, meshed and checked"
else
    bad "tank and sock mesh"
fi

if [ $fails -ne 0 ]; then echo "$fails failed"; exit 1; fi
echo "all passed"
