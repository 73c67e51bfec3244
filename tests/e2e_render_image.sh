#!/usr/bin/env bash
# thorax render --image (issue 25: the scan under the model), headless: a synthetic NIfTI written by
# nibabel (a bright square at a known RAS place in a 2 mm grid) drawn under a box surface with a
# fixed orthographic camera looking down, the pixels read back with VTK's PNG reader:
#  - the square lands where its RAS corners project, bright, and the plane elsewhere dark;
#  - the default window (a label map: its full range; Hounsfield units: 400/40) and a given
#    --image-window/--image-level give the grey values (value - L + W/2) / W computed here;
#  - an opaque surface in front hides the plane, a translucent one shows it through (dimmer);
#  - --image-labels colours each label from the categorical table;
#  - --contours draws the layer nearest the plane on it, each contour surface in its colour,
#    on the loops' edges; a coronal plane and an index plane land where they should;
#  - a plane outside the image, a file that is not an image, --contours without an axial plane:
#    a message naming the problem, exit 1, no picture written.
. "$(dirname "$0")/image_fixture.sh"

# The image (tests/image_fixture.py): 40 x 40 x 20 voxels of 2 mm, voxel centres x, y from -39 to 39
# and z from -19 to 19 (faces at +-40 and +-20); value 100, and 1000 where x in -10..10 and y in
# 0..20 (voxel faces), at every z; the box around the plane z = 0: x, y in -30..30, z in -15..15.
# ct.nii.gz: the same square at 40 HU in air (-1000), and a strip of bone (700 HU) at x in 30..40.
$PY - <<'EOF'
import numpy as np, nibabel as nib
from image_fixture import square_image, box
v, aff = square_image('sq.nii.gz')
box()
c = np.where(v == 1000, 40, -1000).astype(np.int16)
c[35:, :, :] = 700
# lab.nii.gz: a label map, 0 around, label 1 the square, label 2 the strip x in 30..40
lab = np.zeros((40, 40, 20), np.uint8); lab[15:25, 20:30, :] = 1; lab[35:, :, :] = 2
nib.save(nib.Nifti1Image(lab, aff), 'lab.nii.gz')
nib.save(nib.Nifti1Image(c, aff), 'ct.nii.gz')
# contours: surface 'outer' a square loop of half side 25 and 'inner' one of 5 about (0, -15), on
# layers z = 0.5 and 10.5 (the plane z = 0 takes the first); 'outer' at 10.5 is a larger square
open('c.txt', 'w').write('''thorax-contours 1
surface outer outer
surface inner other
layer 0.5
loop outer
-25 -25
25 -25
25 25
-25 25
loop inner
-5 -20
5 -20
5 -10
-5 -10
layer 10.5
loop outer
-35 -35
35 -35
35 35
-35 35
loop inner
-5 -20
5 -20
5 -10
-5 -10
end
''')
open('notimage.nii', 'w').write('this is not an image\n')
EOF

# looking down from +z: screen right +x, screen up +y; 400 px for 100 mm: pixel (200 + 4 x, 200 - 4 y)
CAM=(--camera 0,0,200:0,0,0:0,1,0:0:100 --size 400x400)
"$THORAX" render box.pts "${CAM[@]}" --surface box=hidden --image sq.nii.gz --image-plane z=0 -o plane.png -q
"$THORAX" render box.pts "${CAM[@]}" --surface box=hidden --image sq.nii.gz --image-plane z=0 --image-window 2000 --image-level 1000 -o wl.png -q
"$THORAX" render box.pts "${CAM[@]}" --surface box=hidden --image ct.nii.gz --image-plane z=1 -o ct.png -q
"$THORAX" render box.pts "${CAM[@]}" --surface box=flat:1:#ff0000 --image sq.nii.gz --image-plane z=0 -o opaque.png -q
"$THORAX" render box.pts "${CAM[@]}" --surface box=flat:0.4:#ff0000 --image sq.nii.gz --image-plane z=0 -o trans.png -q
"$THORAX" render box.pts "${CAM[@]}" --surface box=hidden --image sq.nii.gz --image-plane z=0 --contours c.txt -o cont.png -q
"$THORAX" render box.pts "${CAM[@]}" --surface box=hidden --image sq.nii.gz --image-plane k=10 -o index.png -q
"$THORAX" render box.pts "${CAM[@]}" --surface box=hidden --image lab.nii.gz --image-plane z=0 --image-labels -o labels.png -q
# a coronal plane through the square seen from the front (the eye at +y, anterior; up +z: screen right is -x)
"$THORAX" render box.pts --camera 0,200,0:0,0,0:0,0,1:0:100 --size 400x400 --surface box=hidden --image sq.nii.gz \
    --image-plane y=10 -o coronal.png -q
# a sagittal plane x = 0 seen from the subject's right (eye at +x, up +z: screen right is +y)
"$THORAX" render box.pts --camera 200,0,0:0,0,0:0,0,1:0:100 --size 400x400 --surface box=hidden --image sq.nii.gz \
    --image-plane x=0 -o sagittal.png -q

$PY - <<'EOF'
import numpy as np
from image_fixture import png
px = lambda x, y: (int(round(200 - 4 * y)), int(round(200 + 4 * x)))   # (row, column) of RAS (x, y)
def grey(v, W, L): return round(255 * min(max((v - (L - W / 2)) / W, 0), 1))

a = png('plane.png'); bg = a[0, 0]
assert tuple(bg) == (24, 24, 28), bg
# default window of a label-like image (two integer values): its full range 100..1000
sq = a[px(0, 10)]; out = a[px(-20, -20)]
assert (sq == 255).all() and (out == 0).all(), (sq, out)
# the square's edges: 2 px inside bright, 2 px outside dark, on every side
for (x, y, bright) in ((-9.5, 10, 1), (-10.5, 10, 0), (9.5, 10, 1), (10.5, 10, 0), (0, 0.5, 1), (0, -0.5, 0),
                       (0, 19.5, 1), (0, 20.5, 0)):
    v = a[px(x, y)][0]
    assert (v > 200) if bright else (v < 50), ((x, y), v)
# the plane ends at the image's faces (x, y = +-40): background beyond
assert (a[px(-39.5, 0)] == 0).all() and (a[px(-40.5, 0)] == bg).all(), (a[px(-39.5, 0)], a[px(-40.5, 0)])
m = (a == 255).all(axis=2)
ys, xs = m.nonzero()
print('plane: the square %d px, columns %d..%d, rows %d..%d (expected 160..239, 120..199)' % (m.sum(), xs.min(), xs.max(), ys.min(), ys.max()))
assert abs(xs.min() - 160) <= 1 and abs(xs.max() - 239) <= 1 and abs(ys.min() - 120) <= 1 and abs(ys.max() - 199) <= 1
# --image-window 2000 --image-level 1000
b = png('wl.png')
for (x, y, v) in ((0, 10, 1000), (-20, -20, 100)):
    g = b[px(x, y)]
    assert (abs(g - grey(v, 2000, 1000)) <= 1).all(), ((x, y), g, grey(v, 2000, 1000))
print('--image-window 2000 --image-level 1000: square %d (computed %d), around %d (computed %d)' % (b[px(0, 10)][0], grey(1000, 2000, 1000), b[px(-20, -20)][0], grey(100, 2000, 1000)))
# Hounsfield units: soft-tissue window 400 / 40 by default
c = png('ct.png')
assert (abs(c[px(0, 10)] - grey(40, 400, 40)) <= 1).all() and (c[px(-20, -20)] == 0).all(), (c[px(0, 10)], c[px(-20, -20)])
assert (c[px(35, 0)] == 255).all(), c[px(35, 0)]
print('CT default window: 40 HU -> %d (computed %d), air -> %d' % (c[px(0, 10)][0], grey(40, 400, 40), c[px(-20, -20)][0]))
# an opaque box hides the plane inside it (red everywhere over the box), the plane shows beyond the box
o = png('opaque.png')
inside = o[px(0, 10)]
assert inside[0] > 100 and inside[1] < 40 and inside[2] < 40, inside
assert (o[px(35, 0)] == 0).all() and (o[px(0, 35)] == a[px(0, 35)]).all(), (o[px(35, 0)], o[px(0, 35)])
# a translucent box shows it through: the square brighter than the dark plane beneath the same box
t = png('trans.png')
ts, tb = t[px(0, 10)], t[px(-20, -20)]
# over the plane only the box's top face blends (its bottom lies behind the plane, depth-tested
# away): 0.4 of the box's red (flat, facing the eye: 255, 0, 0, as in the opaque picture) over 0.6
# of the plane beneath
for p, under in ((ts, 255), (tb, 0)):
    want = np.array([0.4 * inside[0] + 0.6 * under, 0.6 * under, 0.6 * under])
    assert (abs(p - want) <= 2).all(), (p, want)
print('opaque box: %s over the square; translucent box: %s over it, %s over the dark plane' % (inside, ts, tb))
# contours: outer (orange 230,159,0) on the square loop of half side 25; inner (sky blue 86,180,233)
k = png('cont.png')
orange = lambda p: abs(p[0] - 230) < 40 and abs(p[1] - 159) < 40 and p[2] < 60
blue = lambda p: abs(p[0] - 86) < 40 and abs(p[1] - 180) < 40 and p[2] > 190
for (x, y) in ((0, -25), (0, 25), (-25, 0), (25, 0), (12, 25), (-25, -12)):
    assert orange(k[px(x, y)]), ((x, y), k[px(x, y)])
for (x, y) in ((0, -20), (0, -10), (-5, -15), (5, -15)):
    assert blue(k[px(x, y)]), ((x, y), k[px(x, y)])
# the other layer's loop (half side 35) is not drawn; the plane is unchanged away from the lines
assert not orange(k[px(0, 35)]) and (k[px(0, 35)] == a[px(0, 35)]).all(), k[px(0, 35)]
assert (k[px(0, 10)] == 255).all() and (k[px(-15, 5)] == 0).all()
no = sum(orange(k[r, c]) for r in range(400) for c in range(0, 400, 2))
print('contours: outer and inner loops on the plane (%d orange pixels in every other column)' % no)
# --image-labels: label 1 orange (230,159,0), label 2 sky blue (86,180,233), 0 black
g = png('labels.png')
assert tuple(g[px(0, 10)]) == (230, 159, 0) and tuple(g[px(35, 0)]) == (86, 180, 233) and tuple(g[px(-20, -20)]) == (0, 0, 0), (g[px(0, 10)], g[px(35, 0)], g[px(-20, -20)])
print('labels: 1 -> %s, 2 -> %s, 0 -> %s' % (tuple(g[px(0, 10)]), tuple(g[px(35, 0)]), tuple(g[px(-20, -20)])))
# the image's own plane k = 10 (z = 1): the same picture as z = 1 (exact voxel values) where no
# interpolation differs: the square and the dark around it
i = png('index.png')
assert (i[px(0, 10)] == 255).all() and (i[px(-20, -20)] == 0).all()
# coronal plane y = 10 seen from the front: screen right = -x... eye at +y, up +z: right = (-1, 0, 0)
q = png('coronal.png')
cx = lambda x, z: (int(round(200 - 4 * z)), int(round(200 - 4 * x)))
assert (q[cx(0, 0)] == 255).all() and (q[cx(15, 0)] == 0).all() and (q[cx(0, 19.5)] == 255).all(), (q[cx(0, 0)], q[cx(15, 0)])
assert (q[cx(0, 20.5)] == bg).all(), q[cx(0, 20.5)]
print('coronal y=10: the square spans z -20..20 in the plane, bright; dark beside it')
v = png('sagittal.png')
sx = lambda y, z: (int(round(200 - 4 * z)), int(round(200 + 4 * y)))
assert (v[sx(10, 0)] == 255).all() and (v[sx(-10, 0)] == 0).all() and (v[sx(35, 15)] == 0).all(), (v[sx(10, 0)], v[sx(-10, 0)])
assert (v[sx(0, 20.5)] == bg).all() and (v[sx(39.5, 0)] == 0).all() and (v[sx(40.5, 0)] == bg).all()
print('sagittal x=0: the square at y 0..20, the plane y -40..40, z -20..20')
EOF

# bad input: a named message, exit 1, nothing written
expect_fail() { # PATTERN ARGS...
    local pat="$1"; shift
    if "$THORAX" render box.pts "${CAM[@]}" -o bad.png "$@" 2>err.txt; then fail "accepted: $*"; fi
    grep -q -- "$pat" err.txt || { cat err.txt; fail "no '$pat' for: $*"; }
    [ ! -e bad.png ] || fail "a picture written for: $*"
    echo "refused ($*): $(head -1 err.txt)"
}
expect_fail "z=25 is outside sq.nii.gz: z from -20 to 20 mm" --image sq.nii.gz --image-plane z=25
expect_fail "k=20 is outside" --image sq.nii.gz --image-plane k=20
expect_fail "not a plane" --image sq.nii.gz --image-plane w=3
expect_fail "notimage.nii" --image notimage.nii
expect_fail "needs --image" --image-plane z=0
expect_fail "give an axial --image-plane" --image sq.nii.gz --image-plane y=0 --contours c.txt
echo "e2e_render_image: OK"
