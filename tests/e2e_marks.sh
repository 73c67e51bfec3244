#!/usr/bin/env bash
# Marks over pictures, on map3d's real files (the Utah tank's sock, its landmarks and recording):
# landmark tubes and spheres drawn where the file puts them (red artery pixels only with
# --landmarks, and where the arteries project), node labels only on nodes the camera sees, extrema
# marks, and the errors of each option.
set -euo pipefail
: "${THORAX:?}" "${WORK:?}" "${SRC:?}"
D=${MAP3D_DATA:-$SRC/../shared/data/map3d}
if [ ! -f "$D/geom/tank/25feb97_sock.lmarks" ]; then echo "no map3d data at $D: skipped"; exit 0; fi
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK"
PY=/usr/bin/python3
fail() { echo "FAIL: $*"; exit 1; }
S=$D/geom/tank/25feb97_sock.pts
REC=(--data "$D/data/tank/cool1-atdr-run1.mat" --channels "$D/geom/tank/sock128.channels" --frame 185 --scope frame)
CAM=(--up +z --front +y --size 500x500)

# landmarks: the grey sock alone, then with its arteries
"$THORAX" render "$S" "${CAM[@]}" --surface 25feb97_sock=flat:1:#808080 -o plain.png -q
"$THORAX" render "$S" "${CAM[@]}" --surface 25feb97_sock=flat:1:#808080 --landmarks "$D/geom/tank/25feb97_sock.lmarks" -o lm.png -q
# node labels on the sock with its recording; the same picture without them
"$THORAX" render "$S" "${CAM[@]}" "${REC[@]}" -o data.png -q
"$THORAX" render "$S" "${CAM[@]}" "${REC[@]}" --node-labels 25feb97_sock=channel -o labels.png -q
"$THORAX" render "$S" "${CAM[@]}" "${REC[@]}" --extrema -o extrema.png -q
$PY - "$D" <<'EOF'
import sys, numpy as np, vtk
from vtk.util.numpy_support import vtk_to_numpy
D = sys.argv[1]
def png(p):
    r = vtk.vtkPNGReader(); r.SetFileName(p); r.Update()
    d = r.GetOutput(); w, h, _ = d.GetDimensions()
    return vtk_to_numpy(d.GetPointData().GetScalars()).reshape(h, w, -1)[::-1, :, :3].astype(int)
plain, lm = png('plain.png'), png('lm.png')
red = lambda a: (a[..., 0] > 150) & (a[..., 1] < 80) & (a[..., 2] < 80)
print('landmarks: red pixels %d without, %d with' % (red(plain).sum(), red(lm).sum()))
assert red(plain).sum() == 0 and red(lm).sum() > 500
data, lab, ext = png('data.png'), png('labels.png'), png('extrema.png')
white = lambda a: (a.min(axis=2) > 235)
print('labels: %d white pixels more than the plain picture; extrema marks: %d pixels changed' % (white(lab).sum() - white(data).sum(), (np.abs(ext - data).max(axis=2) > 60).sum()))
assert white(lab).sum() - white(data).sum() > 300
assert (np.abs(ext - data).max(axis=2) > 60).sum() > 50
EOF

# errors: a label kind without its data, a bad landmark file, an unknown surface; nothing written
refused() { local what=$1 pat=$2; shift 2
    if "$@" -o bad.png -q > out.log 2> err.log; then fail "$what: accepted"; fi
    grep -q "$pat" err.log || { cat err.log; fail "$what: message"; }
    [ ! -e bad.png ] || fail "$what: bad.png written"
}
refused "labels by channel without --channels" "has no channels" "$THORAX" render "$S" "${CAM[@]}" --node-labels 25feb97_sock=channel
refused "labels of an unknown kind" "index, channel or value" "$THORAX" render "$S" "${CAM[@]}" --node-labels 25feb97_sock=colour
refused "labels on an unknown surface" "no surface 'heart'" "$THORAX" render "$S" "${CAM[@]}" --node-labels heart=index
printf '2 segment\n1 coronary 2\n0 0 0 1\n1 1 1 1\n' > short.lmarks
refused "a landmark file short of a segment" "short.lmarks:" "$THORAX" render "$S" "${CAM[@]}" --landmarks short.lmarks
printf '1\n1 coronary 2\n0 0 0 1\n1 1 zz 1\n' > badnum.lmarks
refused "a landmark file with a bad number" "badnum.lmarks:4" "$THORAX" render "$S" "${CAM[@]}" --landmarks badnum.lmarks
echo "marks checks passed"
