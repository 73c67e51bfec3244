#!/usr/bin/env bash
# Contours as real slicing and dense digitizing give them (issue 24, item 3).
# 1. A dense comb: one closed loop of 40,952 points 0.5 mm apart (975 teeth 10 mm tall, 0.5 mm
#    wide, 0.5 mm apart, and their base) on two layers. With the default tolerance every pair of
#    points is merged (40,952 repairs): the warnings are summarized, a count per kind and the first 3 of each kind
#    with FILE:LINE (was: one line per repair), -v lists all, the provenance keeps all. Built at
#    --spacing 0.5 (87,000 nodes) it must finish within 6 s of CPU (RLIMIT_CPU; was 16 s: the
#    signed distance, the cap rows and the crossing sweep were quadratic; now about 1.3 s). Not
#    under THORAX_QUICK (the sanitized build).
# 2. The Dalhousie torso cut across x and y (`thorax slice --axis`; z is tests/e2e_digitized.sh) at
#    10 mm, exact and with 0.5 mm of jitter (tests/digitize.py; THORAX_DIGITIZED_FULL=1: also 5 mm
#    jittered, as measured for docs/design/geom.md), builds
#    (across x at 10 mm a 9-point loop at the torso's flat bottom branches off: an edge in three
#    triangles before), passes `thorax check`, and every layer node lies within 1 mm of the true
#    surface, turned as the model was (tests/digitized_compare.py). The Utah tank and the Dalhousie
#    torso cut at 10 mm into crossing points only (--densify 0, up to 60 mm apart) with 0.5 mm of
#    jitter: within 1 mm too (was up to 2.0 mm). The shared data are
#    skipped with a message when ../shared/data is not beside the checkout (THORAX_DATA overrides).
#    The Utah tank cut across x at 10 and 5 mm (THORAX_QUICK: 10 mm only), exact and jittered: a
#    branching slice whose bridged lacing crossed itself (48-62 crossing pairs, refused) is laced by
#    splitting the single loop; built, checked, layer nodes within 1 mm of the true surface.
#    A loop smaller than the merge tolerance, where a plane grazes the body (the merge left it fewer
#    than 3 points and the model was refused), is dropped with a warning naming it: the Dalhousie
#    torso along z at 4 mm (a branch begins at it) and the Utah tank across x at 7 mm (its first
#    layer; and a split branching part laced again with its seam opposite the chord) build, check,
#    within 1 mm. A 2-point loop, or one of 3 points
#    within 0.2 mm, as a surface's only loop is still refused with its FILE:LINE.
# 3. A surface that truly fails the check (two loops of one surface overlapping on its layers) is
#    refused naming the surface and the fault; --unchecked writes it with a warning.
set -uo pipefail
: "${THORAX:?}" "${SRC:?}" "${WORK:?}"
PY=/usr/bin/python3
DATA=${THORAX_DATA:-$SRC/../shared/data}
rm -rf "$WORK" && mkdir -p "$WORK" && cd "$WORK"
fails=0
ok() { echo "ok: $1"; }
bad() { echo "FAIL: $1" >&2; fails=$((fails + 1)); }

# ---- 1. the comb
$PY - > comb.txt <<'PYEOF'
pts, x = [], 0.0
for tooth in range(975):
    pts += [(x, 0.5 * k) for k in range(20)] + [(x + 0.5, 0.5 * (20 - k)) for k in range(20)]
    x += 1.0
b = x
while b >= -0.5:
    pts.append((b - 0.5, -0.5))
    b -= 0.5
print("thorax-contours 1\nspacing 5\nsurface comb outer")
for z in (0, 10):
    print("layer %g\nloop comb" % z)
    print("\n".join("%.6f %.6f" % p for p in pts))
print("end")
PYEOF
n_pts=$(($(grep -c '^[0-9-]' comb.txt) / 2))
if "$THORAX" surfaces comb.txt -o comb_m > comb.out 2> comb.err; then
    lines=$(wc -l < comb.err)
    n=$(sed -n 's/.*warning: \([0-9]*\) repairs of digitization noise: \([0-9]*\) near-coincident.*/\1 \2/p' comb.err)
    prov=$($PY -c "import json; print(len(json.load(open('comb_m/model.json'))['provenance']['repairs']))")
    shown=$(grep -c 'warning: comb.txt:[0-9]*: surface "comb" layer [12] (z=[01]*) loop 1: 2 near-coincident points' comb.err)
    if [ "$lines" -le 6 ] && [ -n "$n" ] && [ "${n% *}" = "$prov" ] && [ "${n#* }" = "$prov" ] && [ "$shown" = 3 ] &&
        grep -q "and $((prov - 3)) more repairs" comb.err; then
        ok "comb ($n_pts points): $prov repairs summarized in $lines lines: $(head -1 comb.err)"
    else bad "comb: the warnings are not summarized ($lines lines; count '$n', provenance $prov, shown $shown): $(head -c 600 comb.err)"; fi
    "$THORAX" surfaces comb.txt -o comb_v -v > /dev/null 2> comb_v.err
    all=$(grep -c 'warning: comb.txt:[0-9]*: surface' comb_v.err)
    [ "$all" = "$prov" ] && ok "-v lists all $all repairs" || bad "-v lists $all of $prov repairs"
else bad "comb: surfaces: $(tail -3 comb.err)"; fi
# the dense build: no merging (a tenth of 0.5 mm), 44,000-point layer loops laced, capped, oriented
if [ "${THORAX_QUICK:-0}" = 1 ]; then echo "skip: the dense comb build (THORAX_QUICK)"
else
    # a bound on CPU seconds (RLIMIT_CPU, every thread counted), not on the wall clock: the
    # quadratic code took 16 s of CPU, the present one about 1.3 s; a loaded machine slows the wall
    # clock, never the CPU count (the limit is a complexity guard, not a speed target: bench/ has those)
    # (--unchecked and check --min-angle 0: the 0.5 mm teeth 10 mm tall lace into triangles down to
    # 0.97 degrees, under the check's 1-degree floor for what thorax mesh can take; every other check
    # must pass)
    ( ulimit -t 6; exec /usr/bin/time -f '%U %S' -o dense.time "$THORAX" surfaces comb.txt -o comb_dense --spacing 0.5 --unchecked -q ) 2> dense.err; rc=$?
    cpu=$(tail -1 dense.time 2>/dev/null | awk '{ printf "%.1f", $1 + $2 }')
    if [ $rc -eq 0 ] && "$THORAX" check comb_dense --min-angle 0 -q 2> dense.check; then
        ok "comb at --spacing 0.5: $(wc -l < comb_dense/comb.pts) nodes, built and checked in $cpu s of CPU (limit 6 s: SIGXCPU; the quadratic code took 16 s)"
    else bad "comb at --spacing 0.5: exit $rc after $cpu s of CPU (over the 6 s limit: killed by SIGXCPU): $(head -3 dense.err dense.check 2>/dev/null)"; fi
fi

# ---- 2. the Dalhousie torso along each axis (`thorax slice --axis`), and sparse jittered cuts
G=$DATA/map3d/geom
if [ ! -f "$G/torso/daltorso.pts" ]; then
    echo "skip: $G not found (the Dalhousie torso, the Utah tank)"
else
    "$THORAX" import -o dal -q "$G/torso/daltorso.pts" --name torso --role outer "$G/torso/dalepi.pts" --name epicardium --role heart || bad "import dal"
    "$THORAX" import -o tank -q "$G/tank/tank_full_771.pts" --name tank --role outer "$G/tank/25feb97_sock_closed.pts" --name sock --role heart || bad "import tank"
    # the reference turned as --axis turns it: (x, y, z) -> (y, z, x) for x, (z, x, y) for y
    turn() { # MODEL AXIS SURFACE -> MODEL_AXIS_SURFACE.pts
        $PY -c "
import sys
perm = {'x': (1, 2, 0), 'y': (2, 0, 1)}[sys.argv[2]]
with open(sys.argv[4], 'w') as f:
    for l in open(sys.argv[3]):
        v = l.split()
        if len(v) >= 3: f.write(' '.join(v[i] for i in perm) + '\\n')" "$1" "$2" "$1/$3.pts" "$1_$2_$3.pts"
        cp "$1/$3.fac" "$1_$2_$3.fac"
    }
    # build, check, layer nodes within 1 mm of the true surface: CASE MODEL SURFACES REF_PREFIX [surfaces options]
    build_case() { # CASE MODEL SURFACES REF [surfaces options]
        local c=$1 m=$2 surfs=$3 ref=$4; shift 4
        if ! "$THORAX" surfaces "$c.txt" -o "$c" -q "$@" 2> "$c.err"; then bad "$c: refused: $(grep -v warning "$c.err" | head -2)"; return; fi
        if "$THORAX" check "$c" -q 2> "$c.check"; then ok "$c: built and checked"; else bad "$c: check: $(head -2 "$c.check")"; fi
        for surf in $surfs; do
            if r=$($PY -B "$SRC/tests/digitized_compare.py" "$c.txt" $surf "$c/$surf.pts" "$c/$surf.fac" --ref "${ref}$surf.pts" "${ref}$surf.fac" --ref-max 1.0); then
                ok "$c $surf: $(echo "$r" | tail -1)"
            else bad "$c $surf: $(echo "$r" | tr '\n' ' ')"; fi
        done
    }
    spacings=10
    [ "${THORAX_DIGITIZED_FULL:-0}" = 1 ] && spacings="10 5"
    for ax in x y; do
        for surf in torso epicardium; do turn dal $ax $surf; done
        for s in $spacings; do
            "$THORAX" slice dal --axis $ax --spacing $s -o "dal_${ax}_$s.txt" -q || { bad "slice --axis $ax at $s mm"; continue; }
            $PY -B "$SRC/tests/digitize.py" "dal_${ax}_$s.txt" "dal_${ax}_${s}_j1.txt" --jitter 0.5 --seed 1
            [ $s = 10 ] && build_case "dal_${ax}_$s" dal "torso epicardium" "dal_${ax}_"
            build_case "dal_${ax}_${s}_j1" dal "torso epicardium" "dal_${ax}_"
        done
    done
    # the frame turns with the model: superior -y, anterior -z become -z, -x across y and -x, -y across x
    "$THORAX" import -o dalf -q --up -y --front -z "$G/torso/daltorso.pts" --name torso --role outer || bad "import with a frame"
    "$THORAX" slice dalf --axis y --spacing 20 -o fy.txt -q && "$THORAX" slice dalf --axis x --spacing 20 -o fx.txt -q
    if grep -qx 'frame -z -x' fy.txt && grep -qx 'frame -x -y' fx.txt; then ok "--axis turns the frame: $(grep '^frame' fy.txt) across y, $(grep '^frame' fx.txt) across x"
    else bad "--axis and the frame: $(grep '^frame' fy.txt fx.txt)"; fi
    # sparse (the crossing points only, up to 60 mm apart) and jittered: the layer nodes within 1 mm
    # of the true surface (was up to 2.0 mm: the spline swung 0.4 of the spacing off long edges)
    for m in tank dal; do
        surfs="tank sock"; [ $m = dal ] && surfs="torso epicardium"
        "$THORAX" slice $m --spacing 10 --densify 0 -o "${m}_sparse.txt" -q || { bad "$m: sparse slice"; continue; }
        $PY -B "$SRC/tests/digitize.py" "${m}_sparse.txt" "${m}_sparse_j1.txt" --jitter 0.5 --seed 1
        build_case "${m}_sparse_j1" $m "$surfs" "$m/" --spacing 5
    done
    # the Utah tank cut across x (issue 24): where the tank's shoulders end, a loop at the flat
    # bottom and the shoulders' loop 97 mm above it meet one loop of the full height on the next
    # layer; the two joined by a bridge were laced with 48-62 pairs of crossing triangles and the
    # surface refused. The single loop is now split by a chord between the two, and each part laced
    # alone: at 5 and 10 mm, exact and with 0.5 mm of jitter, built, checked, within 1 mm
    "$THORAX" import -o tank1 -q "$G/tank/tank_full_771.pts" --name tank --role outer || bad "import tank alone"
    turn tank1 x tank
    tank_spacings="10 5"
    [ "${THORAX_QUICK:-0}" = 1 ] && tank_spacings=10
    for s in $tank_spacings; do
        "$THORAX" slice tank1 --axis x --spacing $s -o "tank_x_$s.txt" -q || { bad "slice the tank across x at $s mm"; continue; }
        $PY -B "$SRC/tests/digitize.py" "tank_x_$s.txt" "tank_x_${s}_j1.txt" --jitter 0.5 --seed 1
        # the whole check, its 1-degree floor included: where the tank's bottom meets the shoulders the
        # lacing left 1-3 triangles of 0.49-1.0 degrees (a node cluster 0.24 mm across laced to nodes
        # 10 mm above) until a lacing with an angle under 1 degree was laced again (src/geom/build.c,
        # quality_retry: the jittered cut at 5 mm), and a pocket inside a bay of the hull was cut
        # (src/geom/lace.c, run_pocket: the other three)
        build_case "tank_x_$s" tank1 tank "tank1_x_"
        build_case "tank_x_${s}_j1" tank1 tank "tank1_x_"
    done
    # a plane that grazes the body cuts a loop smaller than the merge tolerance (a tenth of the
    # spacing), which the merge left with fewer than 3 points: the whole model was refused. Such a
    # loop is dropped where the plane missing the body gives the same surface, with a warning naming
    # it. The Dalhousie torso cut along z at 4 mm: at z=-86 a 0.13 mm loop where a branch of the
    # torso begins (no loop of the layer below encloses it): dropped, built, checked, within 1 mm
    "$THORAX" slice dal --spacing 4 -o dal_z_4.txt -q || bad "slice the torso along z at 4 mm"
    if "$THORAX" surfaces dal_z_4.txt -o dal_z_4 > /dev/null 2> dal_z_4.err; then
        if grep -q 'warning: dal_z_4.txt:[0-9]*: surface "torso" layer 9 (z=-85.9797) loop 1: 1 distinct point is left after merging points within 0.4 mm .*: dropped (no loop of the layer below' dal_z_4.err \
            && grep -q '1 tiny loops dropped' dal_z_4.err; then ok "dal_z_4: the tiny loop dropped: $(grep -o 'dal_z_4.txt:[0-9]*: surface "torso" layer 9.*' dal_z_4.err | cut -c1-100)..."
        else bad "dal_z_4: no warning naming the dropped loop: $(head -3 dal_z_4.err)"; fi
        if "$THORAX" check dal_z_4 -q 2> dal_z_4.check; then ok "dal_z_4: built and checked"; else bad "dal_z_4: check: $(head -2 dal_z_4.check)"; fi
        for surf in torso epicardium; do
            if r=$($PY -B "$SRC/tests/digitized_compare.py" dal_z_4.txt $surf "dal_z_4/$surf.pts" "dal_z_4/$surf.fac" --ref "dal/$surf.pts" "dal/$surf.fac" --ref-max 1.0); then
                ok "dal_z_4 $surf: $(echo "$r" | tail -1)"
            else bad "dal_z_4 $surf: $(echo "$r" | tr '\n' ' ')"; fi
        done
    else bad "dal_z_4: refused: $(grep -v warning dal_z_4.err | head -2)"; fi
    # the Utah tank across x at 7 mm: at its first layer (x=-194.7) a 1.0 mm loop beside a 6 mm one
    # is dropped (was: the model refused), and the branching slice at x=-132.6, whose split part
    # laced with a twist at the chord (777 crossing pairs), is laced again with its seam opposite
    # the chord: built, checked, within 1 mm
    "$THORAX" slice tank1 --axis x --spacing 7 -o tank_x_7.txt -q || bad "slice the tank across x at 7 mm"
    "$THORAX" surfaces tank_x_7.txt -o tank_x_7w > /dev/null 2> tank_x_7.err
    if grep -q 'warning: tank_x_7.txt:8: surface "tank" layer 1 (z=-194.7) loop 1: 1 distinct point is left after merging points within 0.7 mm .*: dropped (its layer is the surface.s first' tank_x_7.err \
        && ! grep -q 'fewer than 3 distinct points' tank_x_7.err; then
        ok "tank_x_7: the tiny end loop dropped, with a warning naming it (tank_x_7.txt:8 loop 1)"
    else bad "tank_x_7: the tiny end loop: $(grep -v 'near-coincident' tank_x_7.err | head -3)"; fi
    build_case tank_x_7 tank1 tank "tank1_x_"
fi

# ---- 2b. a loop tiny because the file is broken is still refused, naming it: a 2-point loop as a
# surface's only loop (the structure check), and a loop of 3 points within 0.2 mm as a surface's
# only loop (the merge leaves it 1 point: dropping it would leave the surface nothing)
for k in 2 3; do
    { printf 'thorax-contours 1\nspacing 5\nsurface box outer\nsurface dot outer\nlayer 0\nloop box\n0 0\n40 0\n40 40\n0 40\nloop dot\n'
      [ $k = 2 ] && printf '60 60\n61 61\n' || printf '60 60\n60.2 60\n60 60.2\n'
      printf 'layer 10\nloop box\n0 0\n40 0\n40 40\n0 40\nend\n'; } > broken$k.txt
    want='broken2.txt:11: surface "dot" layer 1 (z=0) loop 1: loop has 2 points (at least 3 needed)'
    [ $k = 3 ] && want='broken3.txt:11: surface "dot" layer 1 (z=0) loop 1: fewer than 3 distinct points are left after merging points within 0.5 mm (the loop is smaller than the merge tolerance: 0.283 mm across); it is not dropped: it is the surface.s only loop'
    if "$THORAX" surfaces broken$k.txt -o broken$k -q 2> broken$k.err; then bad "a $k-point loop as a surface's only loop: written, exit 0"
    elif grep -q "$want" broken$k.err && [ ! -e broken$k ]; then ok "a $k-point loop as a surface's only loop: refused: $(head -1 broken$k.err)"
    else bad "a $k-point loop as a surface's only loop: $(head -2 broken$k.err)"; fi
done

# ---- 3. a surface that truly fails the check is refused, not written for thorax check to find
# (issue 24): two loops of one surface that overlap on both of its layers (their caps overlap in
# the plane); --unchecked writes it anyway, for correction by hand
cat > overlap.txt <<'EOF2'
thorax-contours 1
spacing 5
surface box outer
layer 0
loop box
0 0
40 0
40 40
0 40
loop box
20 20
60 20
60 60
20 60
layer 20
loop box
0 0
40 0
40 40
0 40
loop box
20 20
60 20
60 60
20 60
end
EOF2
if "$THORAX" surfaces overlap.txt -o overlap -q 2> overlap.err; then bad "overlapping loops: written, exit 0"
else
    grep -q 'nothing written: the surfaces built from these contours fail thorax check' overlap.err && [ ! -e overlap ] \
        && grep -q 'surface "box" fails the check: self-intersection' overlap.err \
        && ok "overlapping loops: refused, naming the surface and the fault" || bad "overlapping loops: $(head -3 overlap.err)"
fi
if "$THORAX" surfaces overlap.txt -o overlap -q --unchecked 2> overlap.err && [ -f overlap/model.json ] \
    && grep -q 'written failing the check (--unchecked)' overlap.err && ! "$THORAX" check overlap -q 2>/dev/null; then
    ok "--unchecked writes it, with a warning, and thorax check fails it"
else bad "--unchecked: $(head -3 overlap.err)"; fi

[ $fails -eq 0 ] || { echo "$fails failed"; exit 1; }
echo "all passed"
