#!/usr/bin/env bash
# thorax streamlines (thorax field --streamlines, issue 16) end to end:
#  1. the medium phantom (meshed without the heart), thorax forward --volume: lines from |J|-density,
#     sphere, rake and region seeds with RK2, RK4 and RK45, read back by VTK (tests/streamlines_read.py:
#     every point inside its tetrahedron, the potential the frame's there); tubes (VTP polygons read by VTK,
#     OBJ); the same file whatever the number of threads; without --seed, 100 seeds by |J| x volume
#     (issue 24); bad seeds and other bad input refused by name,
#     nothing written; a file thorax did not write never replaced.
#  2. the real Dalhousie torso and epicardium (map3d's daltorsoepi.geom@1/@2) meshed with the heart, the
#     1992 epicardial potentials p2_3200_77_epi.tsdf (record 77) as the epicardial problem: lines from
#     seeds on the heart's surface run out through the torso and back to the heart (current loops).
set -euo pipefail
: "${THORAX:?}" "${WORK:?}" "${SRC:?}"
DATA="$SRC/../shared/data/map3d"
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK"
PY=/usr/bin/python3
HERE=$(cd "$(dirname "$0")" && pwd)
fail() { echo "FAIL: $*"; exit 1; }
refused() { # WHAT FILE NEEDLE CMD... : must exit 1 naming NEEDLE, leave FILE absent
    local what=$1 file=$2 needle=$3; shift 3
    if "$@" > out.log 2> err.log; then fail "$what: accepted"; fi
    grep -qF -- "$needle" err.log || fail "$what: message without '$needle': $(cat err.log)"
    [ ! -e "$file" ] || fail "$what: $file written"
    echo "refused ($what): $(head -1 err.log)"
}

# ---- 1. the medium phantom
. "$HERE/medium_phantom.sh"
medium_phantom || fail "the medium phantom"
"$THORAX" beat model -o beat.raw --frames 8 --dt 30 -q
"$THORAX" forward model --epicardial beat.raw --volume -o sol -q
S="$THORAX streamlines sol --streamlines --frame 4"
$S --seed density:150 -o dens.vtp
$PY "$HERE/streamlines_read.py" dens.vtp model sol 4 || fail "density lines read back"
for ig in rk2 rk4 rk45; do
    $S --seed sphere:0,0,0:40:30 --seed line:-60,-20,0:60,-20,0:10 --integrator $ig -o sph_$ig.vtp -q
    $PY "$HERE/streamlines_read.py" sph_$ig.vtp model sol 4 || fail "$ig lines read back"
done
$S --seed region:mean_thorax:40 --direction forward --max-length 50 -o fwd.vtp -q
$PY - <<'PYEOF' || fail "forward, max length"
import vtk
from vtk.util.numpy_support import vtk_to_numpy as n
r = vtk.vtkXMLPolyDataReader(); r.SetFileName("fwd.vtp"); r.Update(); o = r.GetOutput()
d, L = n(o.GetCellData().GetArray("direction")), n(o.GetCellData().GetArray("length"))
assert o.GetNumberOfLines() == 40 and (d == 1).all() and L.max() <= 50 + 1e-9, (o.GetNumberOfLines(), L.max())
PYEOF
# without --seed (issue 24: it was refused): seeded by |J| x volume, 100 seeds, the same file as
# --seed density:100 given, through thorax field as through thorax streamlines
"$THORAX" field sol --streamlines --frame 4 -o def.vtp -q || fail "thorax field --streamlines without --seed"
$S --seed density:100 -o d100.vtp -q
cmp -s def.vtp d100.vtp || fail "the default seeds are not density:100"
$PY - <<'PYEOF' || fail "default seeds"
import vtk
from vtk.util.numpy_support import vtk_to_numpy as n
r = vtk.vtkXMLPolyDataReader(); r.SetFileName("def.vtp"); r.Update(); o = r.GetOutput()
s = n(o.GetCellData().GetArray("seed"))
assert len(set(s.tolist())) == 100 and s.min() == 0 and s.max() == 99, (len(set(s.tolist())), s.min(), s.max())
print("no --seed: %d lines from 100 seeds drawn by |J| x volume (the file of --seed density:100)" % o.GetNumberOfLines())
PYEOF
$PY "$HERE/streamlines_read.py" def.vtp model sol 4 || fail "default lines read back"
# threads do not change the file
OMP_NUM_THREADS=1 $S --seed density:60 -o t1.vtp -q
OMP_NUM_THREADS=2 $S --seed density:60 -o t2.vtp -q
cmp -s t1.vtp t2.vtp || fail "1 and 2 threads differ"
# tubes: VTP polygons and OBJ
$S --seed density:20 --tubes 1.5 --sides 6 --caps -o tubes.vtp -q
$S --seed density:20 --tubes 1.5 --sides 6 --caps -o tubes.obj -q
$S --seed density:20 -o lines.obj -q
$PY - <<'PYEOF' || fail "tubes read back"
import vtk
r = vtk.vtkXMLPolyDataReader(); r.SetFileName("tubes.vtp"); r.Update(); o = r.GetOutput()
assert o.GetNumberOfPolys() > 0 and o.GetNumberOfLines() == 0
fe = vtk.vtkFeatureEdges(); fe.SetInputData(o); fe.BoundaryEdgesOn(); fe.NonManifoldEdgesOn(); fe.FeatureEdgesOff(); fe.ManifoldEdgesOff(); fe.Update()
assert fe.GetOutput().GetNumberOfCells() == 0, "tubes with caps are not closed"
ob = vtk.vtkOBJReader(); ob.SetFileName("tubes.obj"); ob.Update()
assert ob.GetOutput().GetNumberOfPolys() == o.GetNumberOfPolys() and ob.GetOutput().GetNumberOfPoints() == o.GetNumberOfPoints()
ol = vtk.vtkOBJReader(); ol.SetFileName("lines.obj"); ol.Update()
assert ol.GetOutput().GetNumberOfLines() > 0
print("tubes: %d triangles, closed (vtkFeatureEdges); OBJ read by vtkOBJReader: %d triangles, %d lines" %
      (o.GetNumberOfPolys(), ob.GetOutput().GetNumberOfPolys(), ol.GetOutput().GetNumberOfLines()))
PYEOF
# bad input, refused by name with nothing written
refused "seed outside" bad.vtp "point:900,0,0" $S --seed point:900,0,0 -o bad.vtp
refused "unknown region" bad.vtp 'no region "heart"' $S --seed region:heart:10 -o bad.vtp
refused "bad seed spec" bad.vtp "sphere:0,0,0:-3:10" $S --seed sphere:0,0,0:-3:10 -o bad.vtp
refused "frame beyond" bad.vtp "--frame 99" $THORAX streamlines sol --streamlines --frame 99 --seed density:5 -o bad.vtp
refused "not a solution" bad.vtp "solution.json" $THORAX streamlines model --streamlines --seed density:5 -o bad.vtp
"$THORAX" forward model --epicardial beat.raw -o soltorso -q
refused "no volume potentials" bad.vtp "volume" $THORAX streamlines soltorso --streamlines --seed density:5 -o bad.vtp
if $S --seed density:5 -o bad.txt 2> err.log; then fail "a .txt output accepted"; fi
grep -q "vtp" err.log && [ ! -e bad.txt ] || fail "bad extension: $(cat err.log)"
echo "my notes" > mine.vtp
refused "a file thorax did not write" /nonexistent "mine.vtp" $S --seed density:5 -o mine.vtp
[ "$(cat mine.vtp)" = "my notes" ] || fail "mine.vtp replaced"
ls | grep -q '\.tmp' && fail "temporary files left"

# a seed count bounded by memory before anything is read (issue 24: density:100000000 took 10.8 GB)
if THORAX_MAX_MEMORY=1000000 $S --seed density:100000 -o big.vtp 2> big.err; then fail "100,000 seeds in 1 MB accepted"; fi
grep -q 'at most 3906' big.err || { cat big.err; fail "the seed bound's message"; }
[ -e big.vtp ] && fail "big.vtp written"
if THORAX_MAX_MEMORY=1000000 "$THORAX" render model/torso.pts --solution sol --streamlines density:100000 -o big.png 2> big.err
then fail "render: 100,000 seeds in 1 MB accepted"; fi
grep -q 'at most 3906' big.err || { cat big.err; fail "render: the seed bound's message"; }

# ---- 2. the real Dalhousie torso, the heart meshed, record 77's epicardial potentials
if [ -z "${THORAX_QUICK:-}" ]; then # (the plain suite's; left out under the sanitizers)
D="$DATA"
"$THORAX" import -q -o dal --up -y --front -z "$D/geom/torso/daltorsoepi.geom@1" --name torso --role outer \
    "$D/geom/torso/daltorsoepi.geom@2" --name epi --role heart
"$THORAX" mesh dal --grid 20 -q
"$THORAX" forward dal --epicardial "$D/data/torso/p2_3200_77_epi.tsdf" --volume -o dsol -q
"$THORAX" streamlines dsol --streamlines --frame 40 --seed region:heart:200 -o heart.vtp -q
$PY "$HERE/streamlines_read.py" heart.vtp dal dsol 40 --heart heart --expect-lines 400 || fail "Dalhousie lines"
"$THORAX" streamlines dsol --streamlines --frame 40 --seed region:heart:60 --integrator rk45 --tubes 2 -o heart_tubes.vtp -q
fi
echo "e2e_field_streamlines: ok"
