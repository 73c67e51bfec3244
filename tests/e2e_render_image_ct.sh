#!/usr/bin/env bash
# thorax render --image on a real CT no one here made: InVesalius's "Cranium" example (Debian's
# invesalius-examples; its .inv3 is a gzip tar whose matrix.dat holds the int16 volume, main.plist
# its shape and spacing) with the bone surface InVesalius itself extracted from it (surface_0.vtp).
#  - the volume written as NIfTI by nibabel in InVesalius's world frame (x = i sx, y = -j sy,
#    z = k sz, where its surfaces lie); thorax picks the soft-tissue window (400 / 40) for values in
#    Hounsfield units;
#  - the bone surface cut by the plane z = 90 (VTK's vtkCutter), written as a contour layer, drawn
#    with --contours over the axial plane: the line pixels lie within 2 px of the CT's bone in the
#    same picture without the lines (bright under the window); inside the skull every pixel is the
#    CT's value there (bilinear, scipy) under 400 / 40;
#  - the plane drawn with the opaque bone surface above it (seen from above) is hidden where the
#    skull covers it.
INV=/usr/share/doc/invesalius-examples/examples/Cranium.inv3
[ -r "$INV" ] || { echo "SKIP: $INV (Debian package invesalius-examples) is not installed"; exit 0; }
. "$(dirname "$0")/image_fixture.sh"

tar xzf "$INV"
D=$(dirname "$(find . -name main.plist | head -1)")
$PY - "$D" <<'EOF'
import sys, plistlib, numpy as np, nibabel as nib, vtk
from vtk.util.numpy_support import vtk_to_numpy
d = sys.argv[1]
meta = plistlib.load(open(d + '/main.plist', 'rb'))
mx = meta['matrix']
shape, sp = mx['shape'], meta['spacing']
v = np.fromfile(d + '/' + mx['filename'], mx['dtype']).reshape(shape).transpose(2, 1, 0)   # (i, j, k)
aff = np.diag([sp[0], -sp[1], sp[2], 1.0])
nib.save(nib.Nifti1Image(np.ascontiguousarray(v), aff), 'cranium.nii')
r = vtk.vtkXMLPolyDataReader(); r.SetFileName(d + '/surface_0.vtp'); r.Update()
pl = vtk.vtkPlane(); pl.SetOrigin(0, 0, 90); pl.SetNormal(0, 0, 1)
cut = vtk.vtkCutter(); cut.SetInputConnection(r.GetOutputPort()); cut.SetCutFunction(pl)
cl = vtk.vtkCleanPolyData(); cl.SetInputConnection(cut.GetOutputPort())
st = vtk.vtkStripper(); st.SetInputConnection(cl.GetOutputPort()); st.JoinContiguousSegmentsOn(); st.Update()
o = st.GetOutput(); P = vtk_to_numpy(o.GetPoints().GetData()); lines = o.GetLines(); lines.InitTraversal()
ids = vtk.vtkIdList(); loops = []
while lines.GetNextCell(ids):
    q = [P[ids.GetId(i)][:2] for i in range(ids.GetNumberOfIds())]
    keep = [q[0]] + [b for a, b in zip(q, q[1:]) if np.hypot(*(b - a)) > 1e-6]
    if len(keep) > 1 and np.hypot(*(keep[-1] - keep[0])) <= 1e-6: keep = keep[:-1]
    if len(keep) < 8: continue
    # InVesalius's surface is not watertight: the cut gives open curves as well as closed ones. A
    # loop of the contour format closes itself, so an open curve goes out and back along itself
    # (p0 .. pn .. p1): drawn, it is the curve alone, without a chord between its ends.
    loops.append(keep + keep[-2:0:-1])
with open('bone.txt', 'w') as f:
    f.write('thorax-contours 1\nsurface bone other\nlayer 90\n')
    for q in loops:
        f.write('loop bone\n' + ''.join('%.5f %.5f\n' % tuple(p) for p in q))
    f.write('end\n')
print('Cranium: %s voxels of %.4g x %.4g x %.4g mm, HU %d..%d; the bone surface cut at z = 90: %d curves, %d points'
      % (tuple(v.shape), sp[0], sp[1], sp[2], v.min(), v.max(), len(loops), sum(map(len, loops))))
# the bone surface as map3d .pts/.fac (the model drawn with the plane)
t = vtk.vtkTriangleFilter(); t.SetInputConnection(r.GetOutputPort())
dec = vtk.vtkQuadricDecimation(); dec.SetInputConnection(t.GetOutputPort()); dec.SetTargetReduction(0.9)
c = vtk.vtkCleanPolyData(); c.SetInputConnection(dec.GetOutputPort()); c.Update(); p = c.GetOutput()
Q = vtk_to_numpy(p.GetPoints().GetData()); F = vtk_to_numpy(p.GetPolys().GetData()).reshape(-1, 4)[:, 1:]
open('bone.pts', 'w').write(''.join('%.4f %.4f %.4f\n' % tuple(x) for x in Q))
open('bone.fac', 'w').write(''.join('%d %d %d\n' % tuple(x + 1) for x in F))
EOF

# seen from above: RAS (x, y) at pixel (row 250 - (y + 110) * 500 / 260, column 250 + (x - 125) * 500 / 260)
CAM=(--camera 125,-110,500:125,-110,80:0,1,0:0:260 --size 500x500)
"$THORAX" render bone.pts "${CAM[@]}" --surface bone=hidden --image cranium.nii --image-plane z=90 -o ct.png -q
"$THORAX" render bone.pts "${CAM[@]}" --surface bone=hidden --image cranium.nii --image-plane z=90 --contours bone.txt -o ct_lines.png -q
"$THORAX" render bone.pts "${CAM[@]}" --surface bone=flat:1:#00ff00 --image cranium.nii --image-plane z=90 -o ct_bone.png -q

$PY - <<'EOF'
import numpy as np
from image_fixture import png
a, b, c = png('ct.png'), png('ct_lines.png'), png('ct_bone.png')
# the lines: bone's colour (orange 230,159,0) where the picture without them is grey
line = (abs(b[:, :, 0] - 230) < 40) & (abs(b[:, :, 1] - 159) < 40) & (b[:, :, 2] < 60)
grey = (a[:, :, 0] == a[:, :, 1]) & (a[:, :, 1] == a[:, :, 2])
n = line.sum()
assert n > 1500, n
# bone (>= 226 HU: grey >= 246 under 400/40) within 2 px of every line pixel: the surface
# InVesalius extracted lies on the CT's bone boundary as thorax draws it; the same lines moved by
# 12 px (a plane drawn in the wrong place) mostly do not
bone = np.zeros(a.shape[:2], bool)
B = (a[:, :, 0] >= 240) & grey
for dy in range(-2, 3):
    for dx in range(-2, 3):
        bone |= np.roll(np.roll(B, dy, 0), dx, 1)
near = bone[line].mean()
moved = np.roll(line, 12, 1)
near_moved = bone[moved].mean()
print('the bone surface cut at z=90 drawn: %d line pixels, %.1f%% within 2 px of CT bone (the lines moved 12 px: %.1f%%)'
      % (n, 100 * near, 100 * near_moved))
assert near > 0.95 and near_moved < near - 0.3, (near, near_moved)
# inside the skull, the brain: each pixel the CT at its RAS place (bilinear in the plane k = 60,
# scipy) under the soft-tissue window 400 / 40, computed here
import nibabel as nib, scipy.ndimage as ndi
img = nib.load('cranium.nii'); v = np.asarray(img.dataobj, float); sx, sy, sz = img.header.get_zooms()
rows, cols = np.mgrid[200:300, 200:300]
x = 125 + (cols + 0.5 - 250) * 260 / 500; y = -110 - (rows + 0.5 - 250) * 260 / 500
hu = ndi.map_coordinates(v[:, :, int(round(90 / sz))], [x / sx, -y / sy], order=1)
want = np.clip((hu - (40 - 200)) / 400, 0, 1) * 255
err = abs(a[200:300, 200:300, 0] - want)
print('brain (the picture\'s middle): median grey %d; |picture - CT under 400/40| median %.1f, 99th percentile %.1f'
      % (np.median(a[200:300, 200:300, 0]), np.median(err), np.percentile(err, 99)))
assert np.median(err) <= 2 and np.percentile(err, 99) <= 12, (np.median(err), np.percentile(err, 99))
# the opaque bone above the plane hides it where the skull covers it: green there, the CT beside
green = (c[:, :, 1] > 100) & (c[:, :, 0] < 60) & (c[:, :, 2] < 60)
print('opaque bone over the plane: %d green pixels; the brain area %.0f%% green' % (green.sum(), 100 * green[200:300, 200:300].mean()))
assert green[200:300, 200:300].mean() > 0.95
EOF
echo "e2e_render_image_ct: OK"
