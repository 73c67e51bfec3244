#!/usr/bin/env bash
# thorax field end to end: equipotential surfaces and slices of forward solutions, read back by VTK
# and compared with VTK's own filters on the same volume (tests/field_read.py):
#  1. the medium phantom (tests/medium_phantom.sh): a beat, thorax forward --volume; three
#     isosurfaces (percentages), two slices with contours, one frame as .vtp; every frame as a
#     directory with a .pvd (times read back); .obj; the area of each surface equal to
#     vtkContour3DLinearGrid's / vtkCutter's on the vtu of thorax export to 1e-6, the potentials
#     exact, closed where interior;
#  2. the real Dalhousie torso and epicardium (map3d geom/torso) imported, meshed and solved
#     (an epicardial series made here: the potentials of a dipole in the heart on the real
#     epicardium's nodes), the same checks;
#  3. refusals: not a solution, a solution without volume potentials, volume potentials whose rows
#     are not the volume's nodes, a user's file in the way, bad planes / values / frames / regions;
#     nothing written;
#  4. issue 24: --isosurface 0 is the zero equipotential (a count is count:N); a slice missing the
#     volume or a value outside the potentials is refused naming why, nothing written.
set -euo pipefail
: "${THORAX:?}" "${WORK:?}" "${SRC:?}"
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
PY=/usr/bin/python3
CHK="$SRC/tests/field_read.py"
DATA="$SRC/../shared/data/map3d"
fail() { echo "e2e_field: FAIL: $*" >&2; exit 1; }
read_back() { "$PY" "$CHK" "$@" > chk.log 2>&1 || { cat chk.log >&2; fail "read back: $*"; }; cat chk.log; }
refused() { # RC WHAT PATTERN PATH CMD... : exit RC, message matching PATTERN, PATH not written
    local want=$1 what=$2 pat=$3 path=$4; shift 4
    set +e
    "$@" > out.log 2> err.log
    local rc=$?
    set -e
    [ $rc -eq "$want" ] || fail "$what: exit $rc, expected $want ($(cat err.log))"
    grep -q -- "$pat" err.log || fail "$what: message does not say '$pat': $(cat err.log)"
    [ ! -e "$path" ] || fail "$what: $path written"
    echo "refused ($what): $(head -1 err.log)"
}

# ---- 1. the medium phantom
. "$(dirname "$0")/medium_phantom.sh"
medium_phantom || fail "the medium phantom"
"$THORAX" beat model -o beat.raw --frames 12 --dt 30 -q
"$THORAX" forward model --epicardial beat.raw --volume -o sol -q
"$THORAX" forward model --epicardial beat.raw -o solt -q
"$THORAX" export model --solution sol --format vtu --frames 7,12 -o vtu -q
"$THORAX" field sol --isosurface 25%,50%,75% --slice z=150 --slice 10,20,150:1,1,0.5 --contours count:8 --frame 7 -o one.vtp -q
read_back one.vtp vtu/volume_0007.vtu z=150 10,20,150:1,1,0.5
# a list and a count, at another frame
"$THORAX" field sol --isosurface -0.02,0,0.02 --frame 12 -o list.vtp -q
read_back list.vtp vtu/volume_0012.vtu
"$THORAX" field sol --isosurface count:4 --frame 12 -o count.vtp -q
read_back count.vtp vtu/volume_0012.vtu
# every frame: a directory and its collection with the series' times; frames of constant potential
# (before the beat) have empty surfaces, with a warning
"$THORAX" field sol --isosurface 25%,75% --slice y=0 --frame all -o frames 2> all.log
grep -q "warning: the potentials are all 0" all.log || fail "no warning for a constant frame"
"$PY" - <<'EOF' || fail "the collection"
import xml.etree.ElementTree as ET, os, vtk
ds = ET.parse("frames/field.pvd").getroot().find("Collection").findall("DataSet")
times = [float(d.get("timestep")) for d in ds]
assert times == [30.0 * k for k in range(12)], times
for d in ds:
    r = vtk.vtkXMLPolyDataReader(); r.SetFileName(os.path.join("frames", d.get("file"))); r.Update()
    o = r.GetOutput()
    assert o.GetNumberOfPolys() > 0  # the slice at least
    t = o.GetFieldData().GetArray("TimeValue").GetValue(0)
    assert t == float(d.get("timestep")), (t, d.get("timestep"))
print("ok collection: 12 frames, times 0..330 ms, each read by VTK")
EOF
# the same run again replaces its own files; the same frame as .obj
"$THORAX" field sol --isosurface 25%,75% --slice y=0 --frame all -o frames -q
"$THORAX" field sol --isosurface 25%,50%,75% --frame 7 -o one.obj -q
"$PY" - <<'EOF' || fail "obj"
import vtk
r = vtk.vtkOBJReader(); r.SetFileName("one.obj"); r.Update()
x = vtk.vtkXMLPolyDataReader(); x.SetFileName("one.vtp"); x.Update()
o = x.GetOutput()
iso = o.GetCellData().GetArray("iso_value")
n_iso = sum(1 for i in range(o.GetNumberOfLines(), o.GetNumberOfCells()) if iso.GetValue(i) == iso.GetValue(i))
assert r.GetOutput().GetNumberOfPolys() == n_iso, (r.GetOutput().GetNumberOfPolys(), n_iso)
print("ok obj: %d triangles read by vtkOBJReader, as the vtp's isosurfaces" % n_iso)
EOF
# the same output for 1 and 2 threads
OMP_NUM_THREADS=1 "$THORAX" field sol --isosurface count:10 --slice x=5 --frame 7 -o t1.vtp -q
OMP_NUM_THREADS=2 "$THORAX" field sol --isosurface count:10 --slice x=5 --frame 7 -o t2.vtp -q
cmp t1.vtp t2.vtp || fail "output depends on the thread count"
# a region alone: the cut stays in its tetrahedra
"$THORAX" field sol --isosurface 50% --frame 7 --region lung_l -o lung.vtp -q
"$PY" - <<'EOF' || fail "region"
import vtk
r = vtk.vtkXMLPolyDataReader(); r.SetFileName("lung.vtp"); r.Update()
u = vtk.vtkXMLUnstructuredGridReader(); u.SetFileName("vtu/volume_0007.vtu"); u.Update()
names = u.GetOutput().GetFieldData().GetAbstractArray("region_name")
lung = [i + 1 for i in range(names.GetNumberOfValues()) if names.GetValue(i) == "lung_l"][0]
reg = u.GetOutput().GetCellData().GetArray("region")
tet = r.GetOutput().GetCellData().GetArray("tetrahedron")
n = tet.GetNumberOfTuples()
assert n > 0 and all(reg.GetValue(int(tet.GetValue(i))) == lung for i in range(n))
print("ok region lung_l: %d triangles, all in its tetrahedra" % n)
EOF

# ---- 3. refusals, nothing written
echo "my notes" > mine.vtp
refused 1 "a user's file" "mine.vtp" nothing "$THORAX" field sol --isosurface 50% --frame 7 -o mine.vtp
[ "$(cat mine.vtp)" = "my notes" ] || fail "a user's file changed"
refused 1 "not a solution" "solution.json" r1.vtp "$THORAX" field model --isosurface 50% -o r1.vtp
refused 1 "no volume potentials" "volume" r2.vtp "$THORAX" field solt --isosurface 50% -o r2.vtp
cp -r sol solbad
cp solt/torso.raw solbad/volume.raw
refused 1 "rows not the volume's nodes" "rows" r3.vtp "$THORAX" field solbad --isosurface 50% -o r3.vtp
cp -r sol solmiss
rm solmiss/volume.raw
refused 1 "the volume file missing" "volume.raw" r3b.vtp "$THORAX" field solmiss --isosurface 50% -o r3b.vtp
# several frames into a directory holding a user's file of one frame's name: nothing written at all
mkdir ufr
echo "mine" > ufr/field_0007.vtp
refused 1 "a user's file among the frames" "field_0007.vtp" ufr/field_0001.vtp "$THORAX" field sol --isosurface 50% --frame all -o ufr
[ "$(ls ufr)" = "field_0007.vtp" ] && [ "$(cat ufr/field_0007.vtp)" = "mine" ] || fail "files written beside a user's: $(ls ufr)"
refused 2 "a bad plane" "plane" r4.vtp "$THORAX" field sol --slice w=3 -o r4.vtp
refused 2 "bad values" "isosurface" r5.vtp "$THORAX" field sol --isosurface 5,abc -o r5.vtp
refused 2 "a frame out of range" "frame" r6.vtp "$THORAX" field sol --isosurface 50% --frame 13 -o r6.vtp
refused 1 "an unknown region" "no region" r7.vtp "$THORAX" field sol --isosurface 50% --region liver -o r7.vtp
refused 2 "several frames into one file" "directory" r8.vtp "$THORAX" field sol --isosurface 50% --frame 7,8 -o r8.vtp
refused 2 "contours without slices" "slice" r9.vtp "$THORAX" field sol --isosurface 50% --contours 3 -o r9.vtp
# ---- 4. what a user types (issue 24): "0" is the zero equipotential (it was refused as a count of
#      none), a count is count:N; an empty result is refused, naming why, and nothing is written
#      (a slice missing the volume, a value outside the potentials of every frame asked for); a value
#      outside some frames' range only is a warning for each, the series written whole
"$THORAX" field sol --isosurface 0 --frame 12 -o zero.vtp -q || fail "--isosurface 0 refused"
"$PY" - <<'EOF' || fail "the zero equipotential"
import vtk
from vtk.util.numpy_support import vtk_to_numpy
r = vtk.vtkXMLPolyDataReader(); r.SetFileName("zero.vtp"); r.Update()
o = r.GetOutput()
phi = vtk_to_numpy(o.GetPointData().GetArray("potential"))
iso = vtk_to_numpy(o.GetCellData().GetArray("iso_value"))
assert o.GetNumberOfPolys() > 100 and abs(phi).max() < 1e-9 and (iso == 0).all(), (o.GetNumberOfPolys(), abs(phi).max())
print("ok --isosurface 0: %d triangles, every vertex at potential 0 (max |phi| %.2g)" % (o.GetNumberOfPolys(), abs(phi).max()))
EOF
refused 2 "a count of none" "count:N" c0.vtp "$THORAX" field sol --isosurface count:0 --frame 12 -o c0.vtp
refused 1 "a slice missing the volume" "misses the regions cut" miss.vtp "$THORAX" field sol --slice z=5000 --frame 7 -o miss.vtp
refused 1 "a value outside the range" "outside the potentials" far.vtp "$THORAX" field sol --isosurface 1000 --frame 7 -o far.vtp
refused 1 "contours outside the range" "outside the potentials" farc.vtp "$THORAX" field sol --slice z=150 --contours -1000 --frame 7 -o farc.vtp
refused 1 "a value outside every frame" "outside the potentials" farall "$THORAX" field sol --isosurface 1000 --frame all -o farall
"$THORAX" field sol --isosurface 0.01 --frame 1,12 -o part 2> part.log || { cat part.log; fail "a value inside one frame of two"; }
grep -q "warning: --isosurface value 0.01 is outside the potentials of 1 of the 2 frames (frame 1)" part.log || { cat part.log; fail "no warning for the frame without the value"; }
[ -s part/field_0001.vtp ] && [ -s part/field_0012.vtp ] || fail "the series of two frames"
echo "ok empty results: refused with the reason, nothing written; a frame without the value warned"
if ls -a | grep -q '\.tmp'; then fail "a temporary file left: $(ls -a | grep '\.tmp')"; fi

# ---- 2. the real Dalhousie torso (map3d)
if [ -z "${THORAX_QUICK:-}" ]; then # (the plain suite's; left out under the sanitizers)
G="$DATA/geom/torso"
"$THORAX" import -o dal "$G/daltorso.pts" --name torso --role outer "$G/dalepi.pts" --name heart --role heart -q
"$THORAX" mesh dal --grid 25 --no-heart -q
# the epicardial potentials of a current dipole (along x, then along y + z/2) at the heart's
# centroid, on the real epicardium's nodes: two frames
"$PY" - "$G/dalepi.pts" <<'EOF'
import sys, numpy as np
x = np.loadtxt(sys.argv[1]); d = x - x.mean(axis=0)
r = np.linalg.norm(d, axis=1)
with open("epi.txt", "w") as f:
    f.write("thorax-series 1\nrows %d\nframes 2\nunit mV\ntime 0 5\n" % len(x))
    for p, q in zip(d, r):
        f.write("%r %r\n" % (1e4 * p[0] / q**3, 1e4 * (p[1] + 0.5 * p[2]) / q**3))
    f.write("end\n")
EOF
"$THORAX" forward dal --epicardial epi.txt --volume -o dsol -q
"$THORAX" export dal --solution dsol --format vtu -o dvtu -q
c=$("$PY" -c "import numpy as np; x=np.loadtxt('$G/daltorso.pts'); print('%.3f,%.3f,%.3f' % tuple(x.mean(axis=0)))")
"$THORAX" field dsol --isosurface 20%,40%,60%,80% --slice "$c:0,0,1" --slice "$c:1,0.3,0" --contours count:9 --frame 1 -o dal1.vtp -q
read_back dal1.vtp dvtu/volume_0001.vtu "$c:0,0,1" "$c:1,0.3,0"
"$THORAX" field dsol --isosurface count:5 --frame 2 -o dal2.vtp -q
read_back dal2.vtp dvtu/volume_0002.vtu
fi
echo "e2e_field: ok"
