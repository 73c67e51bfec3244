#!/usr/bin/env bash
# End-to-end: every input bounded, every refusal early and named (issue 24). Each block is a
# finding of the issue, failing on the code before it (commit 4ac4878), with what it did then:
#  1. frame lists: export's --frames and field's --frame 1:1:9223372036854775807 take frame 1
#     (were a segfault: k += step overflowed), a range past long's end is refused (exit 2), an empty list is refused before
#     the output directory is made (was exit 0 and an empty folder); animate's A:B too (an int
#     overflow read as another frame).
#  2. thorax sigma refuses 1e-320 and 1e308 S/m (and a --scale that takes a region there) with
#     the bounds named, the model unchanged (were accepted, then refused by thorax forward).
#  3. thorax bem refuses two coincident surfaces under different names (was exit 0, potentials
#     33% off here, 48% in the issue's case) and a surface touching another, and still solves the
#     nested spheres; conductivities of 1e308 or 1e-320 S/m are refused (were NaN potentials
#     written with exit 0, by both methods).
#  4. writers: a surface with coordinates of 1e70 mm exported as vtk, vtp, obj and ply reads back
#     exactly (the text was cut at 63 characters: from 1e56 the decimals, from 1e63 the number
#     itself, 1e70 read back as 1e62); binary STL refuses it, nothing written (wrote inf, which
#     thorax import then refused).
# Env: THORAX (built CLI), SRC (source dir), WORK (scratch dir, created here).
set -euo pipefail
: "${THORAX:?}" "${SRC:?}" "${WORK:?}"
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK"
PY=/usr/bin/python3
fail() { echo "e2e_bounds: FAIL: $*" >&2; exit 1; }
refused() { # RC WHAT PATTERN CMD... : exit RC, message matching PATTERN
    local want=$1 what=$2 pat=$3; shift 3
    set +e
    "$@" > out.log 2> err.log
    local rc=$?
    set -e
    [ $rc -eq "$want" ] || fail "$what: exit $rc, expected $want ($(head -c 400 err.log))"
    grep -q -- "$pat" err.log || fail "$what: message does not say '$pat': $(cat err.log)"
    echo "refused ($what): $(head -1 err.log)"
}

# ---- 1. frame lists and ranges
. "$(dirname "$0")/medium_phantom.sh"
medium_phantom || fail "the medium phantom"
"$THORAX" beat model -o beat.raw --frames 4 --dt 40 -q
set +e
"$THORAX" export model --data beat.raw --format vtp --frames 1:1:9223372036854775807 -o f1 -q 2> err.log
rc=$?
set -e
[ $rc -eq 0 ] || fail "--frames 1:1:9223372036854775807: exit $rc ($(cat err.log))"
ls f1 | tr '\n' ' ' | grep -qx "heart.pvd heart_0001.vtp " || fail "--frames 1:1:LONG_MAX: $(ls f1)"
"$THORAX" export model --data beat.raw --format vtp --frames 2:4:9223372036854775807 -o f2 -q
ls f2 | tr '\n' ' ' | grep -qx "heart.pvd heart_0002.vtp " || fail "--frames 2:4:LONG_MAX: $(ls f2)"
# the issue's own command: thorax field's --frame, the same parser
"$THORAX" forward model --epicardial beat.raw -o sol --volume -q
"$THORAX" field sol --slice z=150 --frame 1:1:9223372036854775807 -o fld.vtp -q || fail "field --frame 1:1:LONG_MAX"
[ -s fld.vtp ] || fail "field --frame 1:1:LONG_MAX: no fld.vtp"
refused 2 "field: an empty frame list" "--frame ''" "$THORAX" field sol --slice z=150 --frame "" -o fld2.vtp
[ ! -e fld2.vtp ] || fail "fld2.vtp written"
refused 2 "a range past long" "--frames '1:9223372036854775808'" \
    "$THORAX" export model --data beat.raw --format vtp --frames 1:9223372036854775808 -o f3
[ ! -e f3 ] || fail "f3 written"
refused 2 "an empty frame list" "--frames '': 1-based frames 1..4" \
    "$THORAX" export model --data beat.raw --format vtp --frames "" -o f4
[ ! -e f4 ] || fail "an empty --frames left $(ls -d f4)"
refused 2 "a trailing comma" "--frames '1,'" "$THORAX" export model --data beat.raw --format vtp --frames 1, -o f5
[ ! -e f5 ] || fail "f5 written"
refused 2 "animate --frames beyond int" "--frames '1:99999999999': A:B" \
    "$THORAX" animate model --frames 1:99999999999 -o a1
[ ! -e a1 ] || fail "a1 written"

# ---- 2. conductivities checked where they are given
cp -r model m
cp m/model.json before.json
refused 1 "sigma 1e-320" "below 1e-12 S/m" "$THORAX" sigma m fat=1e-320
refused 1 "sigma 1e308" "beyond 1e+12 S/m" "$THORAX" sigma m fat=1e308
refused 1 "sigma 1e308 off the diagonal" "beyond 1e+12 S/m" "$THORAX" sigma m muscle=1,1,1,1e308,0,0
refused 1 "sigma --scale 1e300" "--scale 1e+300: region" "$THORAX" sigma m --scale 1e300
cmp -s before.json m/model.json || fail "a refused thorax sigma changed model.json"
# the other places a conductivity is given: mesh's and import's --region NAME:SIGMA (usage errors)
refused 2 "mesh --region fat:1e-320" "the conductivity must be a number from 1e-12 to 1e+12" \
    "$THORAX" mesh m --region fat:1e-320
refused 2 "import --region 1=heart:1e308" "the conductivity must be a number from 1e-12 to 1e+12" \
    "$THORAX" import -o imp m/volume.pts --region 1=heart:1e308
[ ! -e imp ] || fail "imp written"
cmp -s before.json m/model.json || fail "a refused thorax mesh changed model.json"
"$THORAX" sigma m fat=1e-12 muscle=1e12 -q
grep -q '1e-12' m/model.json || fail "fat=1e-12 (the bound itself) not written"

# ---- 3. bem: coincident and touching surfaces refused as mesh refuses them
"$PY" -B - "$SRC/tests" <<'EOF'
import sys
import numpy as np
sys.path.insert(0, sys.argv[1])
from icospheres import icosphere
V, F = icosphere(2)
def tri(name, r, shift=(0, 0, 0)):
    with open(name, "w") as f:
        f.write("- %d\n" % len(V))
        for v in V:
            p = v * r + np.array(shift)
            f.write("%.17g %.17g %.17g %.17g %.17g %.17g\n" % (p[0], p[1], p[2], v[0], v[1], v[2]))
        f.write("- %d %d %d\n" % (len(F), len(F), len(F)))
        for a, b, c in F:
            f.write("%d %d %d\n" % (a, b, c))
tri("outer.tri", 1.0)
tri("inner.tri", 0.6)
tri("inner_copy.tri", 0.6)
tri("touch.tri", 0.4, (0.2, 0, 0))  # reaches x = 0.6: touches inner at its node (0.6, 0, 0)
def geom(name, a, b):
    open(name, "w").write('# Domain Description 1.1\n\nInterfaces 3\n\nInterface: "%s"\nInterface: "%s"\n'
                          'Interface: "outer.tri"\n\nDomains 4\n\nDomain In: -1\nDomain Mid: 1 -2\nDomain Out: 2 -3\n'
                          'Domain Air: 3\n' % (a, b))
    open(name[:-5] + ".cond", "w").write("# Properties Description 1.0 (Conductivities)\n\nAir 0.0\nOut 1\nMid 1\nIn 1\n")
geom("dup.geom", "inner_copy.tri", "inner.tri")
geom("touch.geom", "touch.tri", "inner.tri")
open("good.geom", "w").write('# Domain Description 1.1\n\nInterfaces 2\n\nInterface: "inner.tri"\nInterface: "outer.tri"\n\n'
                             'Domains 3\n\nDomain In: -1\nDomain Out: 1 -2\nDomain Air: 2\n')
open("good.cond", "w").write("# Properties Description 1.0 (Conductivities)\n\nAir 0.0\nOut 1\nIn 1\n")
open("d.dip", "w").write("0 0 0.1 0 0 1\n")
EOF
refused 1 "bem: two coincident surfaces" "surfaces 'inner_copy' and 'inner' coincide" \
    "$THORAX" bem dup.geom --dipoles d.dip -o b1
[ ! -e b1 ] || fail "b1 written"
refused 1 "bem: a surface touching another" "surfaces 'touch' and 'inner' touch: node" \
    "$THORAX" bem touch.geom --dipoles d.dip -o b2
[ ! -e b2 ] || fail "b2 written"
"$THORAX" bem good.geom --dipoles d.dip -o b3 -q || fail "bem on two nested spheres"
# conductivities beyond thorax sigma's bounds gave NaN potentials with exit 0, by either method
for c in 1e308 1e-320; do
    sed "s/^Out 1/Out $c/" good.cond > odd.cond
    cp good.geom odd.geom
    for meth in symmetric collocation; do
        refused 1 "bem: sigma $c ($meth)" "odd.cond:[0-9]*: domain 'Out': conductivity .* is outside 1e-12..1e+12" \
            "$THORAX" bem odd.geom --dipoles d.dip --method $meth -o b4
        [ ! -e b4 ] || fail "b4 written"
    done
done

# ---- 4. writers round-trip what they accept, or refuse it
"$PY" -c "
S = 1e70
V = [(0, 0, 0), (S, 0, 0), (0, S, 0), (0, 0, S)]
open('t.pts', 'w').write(''.join('%r %r %r\n' % v for v in V))
open('t.fac', 'w').write('1 3 2\n1 2 4\n1 4 3\n2 3 4\n')
"
"$THORAX" import -o big t.pts --name t --role outer -q
for f in vtk vtp obj ply; do
    "$THORAX" export big --format $f -o ex -q
    [ $f = vtp ] && continue  # thorax import reads vtk, obj and ply back
    rm -rf back_$f
    "$THORAX" import -o back_$f ex/t.$f --name t --role outer -q || fail "$f with 1e70 mm does not read back"
    "$PY" - big/t.pts back_$f/t.pts <<'EOF' || fail "$f: the coordinates changed"
import sys
a = [[float(x) for x in l.split()] for l in open(sys.argv[1]) if l.strip()]
b = [[float(x) for x in l.split()] for l in open(sys.argv[2]) if l.strip()]
assert a == b and max(max(r) for r in a) == 1e70, (a, b)
EOF
done
grep -q "1.0000000000000001e+70" ex/t.vtp || fail "vtp: 1e70 not written in full"
refused 1 "STL beyond float32" "coordinate 1e+70 is beyond float32's range" "$THORAX" export big --format stl -o ex
[ ! -e ex/t.stl ] || fail "ex/t.stl written"
echo "e2e_bounds: ok"
