#!/usr/bin/env bash
# Digitization noise repaired, not refused (issue 11 item 6; paper 3.1: hand-digitized points are
# "inevitably jagged"). Contours that `thorax slice` cuts from the Utah tank (tank + sock) and the
# Dalhousie torso (torso + epicardium) at 5 and 10 mm, with 0.5 mm of jitter added
# (tests/digitize.py: every point moved up to 0.5 mm, uniformly over the disc), must all build with
# `thorax surfaces` (repairs reported, not refused), pass `thorax check`, and every node away from
# the caps (the nodes of the layer loops) must lie within 1 mm of the true (original triangulated)
# surface (tests/digitized_compare.py). Sparse polygons (the crossing points only, --densify 0:
# up to 60 mm between points) are resampled without overshoot: every layer node within half the
# node spacing of the digitized polygon and within 1 mm of the true surface (issue 24: the spline
# strayed up to 2 mm from 60 mm edges). --strict refuses what is otherwise repaired, with the
# same message; the repairs are listed in model.json's provenance.
# THORAX_DIGITIZED_FULL=1 also runs jitter seeds 2 and 3 (the figures of the notes).
# The shared data sets are skipped (with a message) when ../shared/data is not beside the checkout.
set -uo pipefail
: "${THORAX:?}" "${SRC:?}" "${WORK:?}"
PY=/usr/bin/python3
DATA=${THORAX_DATA:-$SRC/../shared/data}
rm -rf "$WORK" && mkdir -p "$WORK" && cd "$WORK"
fails=0
ok() { echo "ok: $1"; }
bad() { echo "FAIL: $1" >&2; fails=$((fails + 1)); }

G=$DATA/map3d/geom
if [ ! -d "$G/tank" ]; then
    echo "skip: $DATA/map3d not found (Utah tank, Dalhousie torso)"
    exit 0
fi
"$THORAX" import -o tank -q "$G/tank/tank_full_771.pts" --name tank --role outer "$G/tank/25feb97_sock_closed.pts" --name sock --role heart || bad "tank: import"
"$THORAX" import -o dal -q "$G/torso/daltorso.pts" --name torso --role outer "$G/torso/dalepi.pts" --name epicardium --role heart || bad "dalhousie: import"
surfaces_of() { case $1 in tank) echo "tank sock" ;; dal) echo "torso epicardium" ;; esac; }

seeds="1"
[ "${THORAX_DIGITIZED_FULL:-0}" = 1 ] && seeds="1 2 3"
for m in tank dal; do
    for s in 5 10; do
        "$THORAX" slice $m --spacing $s -o "${m}_$s.txt" -q || { bad "$m $s: slice"; continue; }
        for seed in $seeds; do
            c="${m}_${s}_j$seed"
            $PY -B "$SRC/tests/digitize.py" "${m}_$s.txt" "$c.txt" --jitter 0.5 --seed $seed
            if ! "$THORAX" surfaces "$c.txt" -o "$c" > "$c.out" 2> "$c.err"; then bad "$c: surfaces: $(grep -v warning "$c.err" | head -3)"; continue; fi
            ok "$c: built ($(sed -n 's/.*warning: \([0-9]*\) repairs\{0,1\} of digitization noise.*/\1/p' "$c.err") repairs reported)"
            if "$THORAX" check "$c" -q 2> "$c.check"; then ok "$c: thorax check"; else bad "$c: check: $(head -3 "$c.check")"; fi
            for surf in $(surfaces_of $m); do
                if r=$($PY -B "$SRC/tests/digitized_compare.py" "$c.txt" $surf "$c/$surf.pts" "$c/$surf.fac" --ref "$m/$surf.pts" "$m/$surf.fac" --ref-max 1.0); then
                    ok "$c $surf: $(echo "$r" | tail -1)"
                else bad "$c $surf: $(echo "$r" | tr '\n' ' ')"; fi
            done
        done
    done
    # sparse polygons: the crossing points of the planes with the mesh's edges only
    "$THORAX" slice $m --spacing 10 --densify 0 -o "${m}_sparse.txt" -q || { bad "$m sparse: slice"; continue; }
    longest=$($PY -c "
import math, sys
best, prev = 0, None
for l in open(sys.argv[1]):
    f = l.split()
    if len(f) == 2 and f[0][0] in '-.0123456789':
        p = (float(f[0]), float(f[1]))
        if prev: best = max(best, math.dist(p, prev))
        prev = p
    else: prev = None
print('%.0f' % best)" "${m}_sparse.txt")
    c="${m}_sparse"
    if ! "$THORAX" surfaces "$c.txt" -o "$c" --spacing 5 -q 2> "$c.err"; then bad "$c: surfaces: $(head -3 "$c.err")"; continue; fi
    "$THORAX" check "$c" -q 2> "$c.check" && ok "$c: thorax check" || bad "$c: check: $(head -3 "$c.check")"
    for surf in $(surfaces_of $m); do
        if r=$($PY -B "$SRC/tests/digitized_compare.py" "$c.txt" $surf "$c/$surf.pts" "$c/$surf.fac" --max 2.5 --ref "$m/$surf.pts" "$m/$surf.fac" --ref-max 1.0); then
            ok "$c $surf (up to $longest mm between points, spacing 5 mm): $(echo "$r" | tr '\n' ';')"
        else bad "$c $surf: nodes beyond half the spacing from the polygon or 1 mm from the true surface: $(echo "$r" | tr '\n' ' ')"; fi
    done
done

# --strict refuses what is repaired otherwise, with the same message, and writes nothing
c=dal_5_j1
if [ -f "$c.err" ]; then
    first=$(grep -m1 'warning: .*:[0-9]*: surface' "$c.err" | sed 's/^thorax: warning: //')
    if "$THORAX" surfaces "$c.txt" -o strict_out --strict -q 2> strict.err; then bad "--strict: exit 0"
    elif grep -qF "$first" strict.err && [ ! -e strict_out ]; then ok "--strict refuses, same message: $(head -c 160 strict.err)"
    else bad "--strict: message differs or output written: $(cat strict.err) / $first"; fi
    # every repair is in the provenance (the warnings give the count and the first few)
    n=$(sed -n 's/.*warning: \([0-9]*\) repairs\{0,1\} of digitization noise.*/\1/p' "$c.err")
    $PY -c "
import json, sys
r = json.load(open('$c/model.json'))['provenance']['repairs']
sys.exit(0 if len(r) == $n and all(':' in x and 'surface' in x and 'layer' in x for x in r) else 1)" &&
        ok "provenance lists the $n repairs" || bad "provenance repairs differ from the $n warnings"
fi

[ $fails -eq 0 ] || { echo "$fails failed"; exit 1; }
echo "all passed"
