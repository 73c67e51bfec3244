#!/usr/bin/env bash
# Equipotential surfaces and slices in pictures (thorax render/animate --isosurface, --slice,
# --slice-current, --streamlines; src/picture/field_layers.c), on the medium phantom's forward solution with its
# volume potentials. Pixel facts read back with VTK's PNG reader:
#  - one positive equipotential alone is drawn in red shades only, one negative in blue only, the
#    two together in both (the value's colour under the scale);
#  - a horizontal slice seen from above covers most of the torso's silhouette and no pixel outside
#    it; by potential it has red and blue, by |J| (viridis) no red;
#  - current streamlines seen from above stay inside the torso's silhouette, coloured by |J| (no red);
#  - the frames of an animation of equipotentials differ; the viewer draws them too;
# and refusals: no --solution, a solution without volume potentials, a bad plane, bad values, bad
# seeds, an unknown region, a slice missing the volume, a value outside every frame (issue 24);
# --isosurface 0 draws the zero equipotential.
set -euo pipefail
: "${THORAX:?}" "${WORK:?}" "${SRC:?}"
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK"
PY=/usr/bin/python3
fail() { echo "FAIL: $*"; exit 1; }

. "$(dirname "$0")/medium_phantom.sh"
medium_phantom || fail "the medium phantom"
"$THORAX" beat model -o beat.raw --frames 300 -q
"$THORAX" forward model --epicardial beat.raw --volume -o sol -q
# a solution without volume potentials: the same one with its volume file left out of solution.json
cp -r sol plain && rm plain/volume.* && $PY - <<'PYEOF'
import json
j = json.load(open("plain/solution.json")); del j["files"]["volume"]
json.dump(j, open("plain/solution.json", "w"))
PYEOF

R=(--solution sol --frame 193 --size 300x300)
"$THORAX" render "${R[@]}" --only equipotentials --surface equipotentials=phong:1 --isosurface 1.0 -o iso_pos.png -q
"$THORAX" render "${R[@]}" --only equipotentials --surface equipotentials=phong:1 --isosurface -1.0 -o iso_neg.png -q
"$THORAX" render "${R[@]}" --only equipotentials --surface equipotentials=phong:1 --isosurface -1.0,1.0 -o iso_both.png -q
"$THORAX" render "${R[@]}" --isosurface 20%,80% --colorbar -o iso_all.png -q
"$THORAX" render "${R[@]}" --view superior --only torso --surface torso=flat:1 -o torso_top.png -q
"$THORAX" render "${R[@]}" --view superior --only slices --slice z=110 -o slice_phi.png -q
"$THORAX" render "${R[@]}" --view superior --only slices --slice z=110 --slice-current -o slice_j.png -q
"$THORAX" render "${R[@]}" --view superior --slice z=110 --slice 0,0,140:0,1,0 --style bands+contours --colorbar -o slices.png -q
"$THORAX" render "${R[@]}" --view superior --only streamlines --streamlines density:120 -o stream_top.png -q
"$THORAX" render "${R[@]}" --only streamlines --only heart --streamlines density:120 --streamlines sphere:-30,12,110:65:40 --colorbar -o stream.png -q
"$THORAX" animate --solution sol --frames 180:182 --size 200x200 --isosurface count:3 --mp4 none -o anim -q

$PY - <<'PYEOF'
import vtk
import numpy as np
from vtk.util.numpy_support import vtk_to_numpy
def png(p):
    r = vtk.vtkPNGReader(); r.SetFileName(p); r.Update()
    im = r.GetOutput(); w, h, _ = im.GetDimensions()
    return vtk_to_numpy(im.GetPointData().GetScalars()).reshape(h, w, -1)[:, :, :3].astype(float)
def drawn(a):
    bg = a[0, 0]
    return np.abs(a - bg).sum(axis=2) > 30
def reds_blues(a):
    m = drawn(a)
    r, g, b = a[:, :, 0], a[:, :, 1], a[:, :, 2]
    red = m & (r > b + 25)
    blue = m & (b > r + 25)
    return int(m.sum()), int(red.sum()), int(blue.sum())
n, red, blue = reds_blues(png("iso_pos.png"))
print("positive equipotential: %d pixels, %d red, %d blue" % (n, red, blue))
assert n > 200 and red > 0.5 * n and blue == 0
n, red, blue = reds_blues(png("iso_neg.png"))
print("negative equipotential: %d pixels, %d red, %d blue" % (n, red, blue))
assert n > 200 and blue > 0.5 * n and red == 0
n, red, blue = reds_blues(png("iso_both.png"))
print("both: %d pixels, %d red, %d blue" % (n, red, blue))
assert red > 100 and blue > 100
torso = drawn(png("torso_top.png"))
sp = png("slice_phi.png"); s = drawn(sp)
print("slice z=110 from above: %d pixels; torso silhouette %d; outside it %d" % (s.sum(), torso.sum(), (s & ~torso).sum()))
assert s.sum() > 0.6 * torso.sum() and (s & ~torso).sum() < 0.01 * s.sum()
n, red, blue = reds_blues(sp)
print("slice by potential: %d red, %d blue" % (red, blue))
assert red > 50 and blue > 50
sj = png("slice_j.png"); m = drawn(sj)
r, g, b = sj[:, :, 0], sj[:, :, 1], sj[:, :, 2]
reddish = m & (r > 1.3 * g) & (r > 1.3 * b) & (r > 90)
print("slice by |J|: %d pixels, %d red (viridis has none)" % (m.sum(), reddish.sum()))
assert m.sum() > 0.6 * torso.sum() and reddish.sum() == 0
st = png("stream_top.png"); m = drawn(st)
r, g, b = st[:, :, 0], st[:, :, 1], st[:, :, 2]
reddish = m & (r > 1.3 * g) & (r > 1.3 * b) & (r > 90)
print("streamlines from above: %d pixels, %d outside the torso's silhouette, %d red" % (m.sum(), (m & ~torso).sum(), reddish.sum()))
assert m.sum() > 2000 and (m & ~torso).sum() < 0.01 * m.sum() and reddish.sum() == 0
import glob
frames = sorted(glob.glob("anim/frame_*.png"))
print("animation:", len(frames), "pictures")
assert len(frames) == 3
a, b = png(frames[0]), png(frames[-1])  # frames 180 and 182
assert np.abs(a - b).sum() > 1000, "the equipotentials do not change between frames"
PYEOF

# the viewer (the same picture code in a window): a scripted session with streamlines and
# equipotentials, its screenshot against one without them (xvfb-run; skipped without it, and
# under the sanitizers, THORAX_QUICK: e2e_view covers the viewer there)
if command -v xvfb-run > /dev/null && [ -z "${THORAX_QUICK:-}" ]; then
    for with in 0 1; do
        {
            echo "--solution sol"; echo "--size 300x320"; echo "--frame 193"; echo "--only heart"
            if [ $with = 1 ]; then echo "--streamlines density:60"; echo "--isosurface 15%,85%"
                echo "--only streamlines"; echo "--only equipotentials"; fi
            echo "action screenshot $PWD/view$with.png"; echo "quit"
        } > view$with.txt
        # one retry: xvfb-run -a can lose the race for a display number to another test
        xvfb-run -a "$THORAX" view --script view$with.txt > view$with.out 2>&1 ||
            xvfb-run -a "$THORAX" view --script view$with.txt > view$with.out 2>&1 || { cat view$with.out; fail "viewer session $with"; }
    done
    $PY - <<'PYEOF'
import vtk
import numpy as np
from vtk.util.numpy_support import vtk_to_numpy
def png(p):
    r = vtk.vtkPNGReader(); r.SetFileName(p); r.Update()
    im = r.GetOutput(); w, h, _ = im.GetDimensions()
    return vtk_to_numpy(im.GetPointData().GetScalars()).reshape(h, w, -1)[:, :, :3].astype(float)
a, b = png("view0.png"), png("view1.png")
changed = (np.abs(a - b).sum(axis=2) > 30).sum()
print("viewer: %d pixels changed by the streamlines and equipotentials" % changed)
assert changed > 3000
PYEOF
fi

expect_fail() { # WHAT NEEDLE ARGS...
    local what=$1 needle=$2; shift 2
    if "$THORAX" render "$@" -o bad.png > out.txt 2>&1; then fail "$what: accepted"; fi
    grep -q -- "$needle" out.txt || { cat out.txt; fail "$what: message lacks '$needle'"; }
    [ ! -e bad.png ] || fail "$what: wrote bad.png"
    echo "ok: $what: $(head -n 1 out.txt)"
}
expect_fail "no solution" "needs --solution" model --isosurface 0
expect_fail "no volume potentials" "thorax forward ... --volume" --solution plain --slice z=100
expect_fail "bad plane" "z=" --solution sol --slice z=abc
expect_fail "bad values" "isosurface" --solution sol --isosurface 1,,x
cp -r sol odd && sed -i 's/"problem":[^,]*/"problem": "nonsense"/' odd/solution.json
expect_fail "unknown problem" "unknown problem" --solution odd --slice z=100
expect_fail "bad seeds" "streamlines" --solution sol --streamlines cube:1
expect_fail "no region" "lung_x" --solution sol --streamlines region:lung_x:10
# issue 24: a cut that cannot cut anything is refused, as thorax field refuses it; 0 is the zero
# equipotential (it was a count of none); a value outside one frame's potentials is said once
expect_fail "a slice missing the volume" "misses the volume" --solution sol --slice z=5000
expect_fail "a value outside every frame" "outside the volume potentials" --solution sol --isosurface 1000
"$THORAX" render "${R[@]}" --only equipotentials --surface equipotentials=phong:1 --isosurface 0 -o iso_zero.png -q
"$THORAX" render --solution sol --frame 1 --size 100x100 --isosurface 1.0 -o iso_f1.png 2> iso_f1.err
grep -q "warning: --isosurface 1.0: no equipotential surface in frame 1" iso_f1.err || { cat iso_f1.err; fail "no warning for a frame without the value"; }
$PY - <<'PYEOF'
import numpy as np, vtk
from vtk.util.numpy_support import vtk_to_numpy
r = vtk.vtkPNGReader(); r.SetFileName("iso_zero.png"); r.Update()
d = r.GetOutput(); w, h, _ = d.GetDimensions()
a = vtk_to_numpy(d.GetPointData().GetScalars()).reshape(h, w, -1)[:, :, :3].astype(int)
n = (np.abs(a - a[0, 0]).max(axis=2) > 20).sum()
print("ok: --isosurface 0 draws the zero equipotential: %d pixels" % n)
assert n > 2000
PYEOF
echo "all passed"
