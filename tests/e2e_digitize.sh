#!/usr/bin/env bash
# Label maps -> contours -> model (issue 25 item 2): a NIfTI label map written by nibabel (a body,
# two lungs of one label, a heart, and a stray voxel), at 3 mm voxels with a mirrored x axis:
#  - thorax digitize: the report (the stray voxel removed, two loops per lung plane), the contour
#    file's frame and image line (the SHA-256 sha256sum prints), every node within 0.61 voxel of its
#    analytic sphere (the label map's own voxel faces reach 0.6 voxel) in RAS, computed here;
#  - thorax surfaces on the contours, thorax check, thorax mesh;
#  - thorax surfaces LABELS.nii --label ... straight from the image: the same surfaces, model.json's
#    provenance names the image (file, SHA-256, format, identity model-to-RAS) and the frame;
#  - refusals: bad --label syntax, an unknown role, a value absent from the image (a warning) and a
#    surface with no voxel (refused), a non-integral image, --edits with an image: a named message,
#    a non-zero exit, nothing written.
set -euo pipefail
: "${THORAX:?}" "${SRC:?}" "${WORK:?}"
PY=/usr/bin/python3
rm -rf "$WORK" && mkdir -p "$WORK" && cd "$WORK"
fail() { echo "e2e_digitize: FAIL: $*" >&2; exit 1; }
$PY -c "import nibabel" 2>/dev/null || { echo "skip: python3-nibabel not installed"; exit 0; }

$PY - <<'EOF'
import numpy as np, nibabel as nib
h = 3.0; n = 46
# voxel centres: x mirrored (i runs toward the subject's left), centred on 0
ax = (np.arange(n) - (n - 1) / 2) * h
balls = [((0, 0, 0), 60, 1), ((28, 0, 5), 18, 2), ((-28, 0, 5), 18, 2), ((0, 25, -5), 10, 3)]
sub = (np.arange(4) + 0.5) / 4 - 0.5
votes = np.zeros((4, n, n, n))
for a in sub:
    for b in sub:
        for d in sub:
            X, Y, Z = np.meshgrid(-(ax + a * h), ax + b * h, ax + d * h, indexing='ij')
            lab = np.zeros((n, n, n), int)
            for c, r, v in balls:
                lab[(X - c[0])**2 + (Y - c[1])**2 + (Z - c[2])**2 <= r * r] = v
            for v in range(1, 4): votes[v] += lab == v
lab = np.zeros((n, n, n), np.int16)
for v in range(1, 4): lab[votes[v] > 32] = v
lab[2, 2, 2] = 1  # a stray voxel outside the body
aff = np.diag([-h, h, h, 1.0]); aff[:3, 3] = [-ax[0], ax[0], ax[0]]
nib.save(nib.Nifti1Image(lab, aff), 'labels.nii.gz')
f = lab.astype(np.float32) + 0.5
nib.save(nib.Nifti1Image(f, aff), 'float.nii.gz')
EOF

"$THORAX" digitize labels.nii.gz --label 1=torso:outer --label 2=lungs:lung --label 3=heart:heart -o c.txt >rep.txt
cat rep.txt
grep -q "46 planes across index axis k (superior), 3 mm apart" rep.txt || fail "report planes"
grep -q "^torso: removed 1 component of 1 voxel in all (sizes: 1)" rep.txt || fail "the stray voxel not reported"
sha=$(sha256sum labels.nii.gz | cut -d' ' -f1)
grep -qx "image sha256:$sha labels.nii.gz" c.txt || fail "image line: $(grep '^image' c.txt)"
grep -qx "frame +z +y" c.txt || fail "frame line"
grep -q "^lungs: 2 components (6-connected in 3D), a surface each, right to left: lungs_right .* lungs_left" rep.txt ||
    fail "components not reported"
$PY - <<'EOF' || fail "contour nodes"
import math
balls = {'torso': [((0, 0, 0), 60)], 'lungs_right': [((28, 0, 5), 18)], 'lungs_left': [((-28, 0, 5), 18)],
         'heart': [((0, 25, -5), 10)]}
z = None; cur = None; worst = {}; loops = {}
for line in open('c.txt'):
    w = line.split('#')[0].split()
    if not w: continue
    if w[0] == 'layer': z = float(w[1])
    elif w[0] == 'loop':
        cur = w[1]; loops.setdefault(cur, {}).setdefault(z, 0); loops[cur][z] += 1
    elif len(w) == 2 and cur:
        x, y = map(float, w)
        d = min(abs(math.dist((x, y, z), c) - r) for c, r in balls[cur])
        worst[cur] = max(worst.get(cur, 0), d)
print('max distance from the spheres (mm):', {k: round(v, 3) for k, v in worst.items()})
assert set(worst) == set(balls), worst
assert all(v <= 0.61 * 3 for v in worst.values()), worst
# the lungs (one label, two 3D components): a surface each, one loop per plane, named by side
# (+x the subject's right: the image's i runs toward the subject's left here)
for s in ('lungs_right', 'lungs_left'):
    assert len(loops[s]) >= 8 and all(v == 1 for v in loops[s].values()), loops[s]
assert all(v == 1 for v in loops['torso'].values())
EOF

"$THORAX" surfaces c.txt -o m -q
"$THORAX" check m >chk.txt || { cat chk.txt; fail "thorax check on the digitized model"; }
"$THORAX" mesh m -o mm -q || fail "thorax mesh"
[ -f mm/volume.tet ] || fail "no volume mesh"

# straight from the image
"$THORAX" surfaces labels.nii.gz --label 1=torso:outer --label 2=lungs:lung --label 3=heart:heart -o m2 >s2.txt
"$THORAX" check m2 >chk2.txt || { cat chk2.txt; fail "thorax check on the model from the image"; }
$PY - "$sha" <<'EOF' || fail "model.json from the image"
import json, sys
m = json.load(open('m2/model.json')); m1 = json.load(open('m/model.json'))
im = m['provenance']['image']
assert im['file'] == 'labels.nii.gz' and im['sha256'] == sys.argv[1] and im['format'] == 'nifti1', im
assert im['model_to_ras'] == [1, 0, 0, 0, 1, 0, 0, 0, 1], im
assert m['frame'] == {'superior': '+z', 'anterior': '+y', 'left': '-x'}, m['frame']
assert m1['provenance']['image']['sha256'] == sys.argv[1]  # recorded from the contour file's line
for s, s1 in zip(m['surfaces'], m1['surfaces']):
    assert s['name'] == s1['name'] and s['n_nodes'] == s1['n_nodes'], (s, s1)
    a = [list(map(float, l.split())) for l in open('m2/' + s['pts'])]
    b = [list(map(float, l.split())) for l in open('m/' + s1['pts'])]
    assert max(abs(p - q) for u, v in zip(a, b) for p, q in zip(u, v)) < 1e-4
EOF

# topology, computed here independently: a random pattern (many saddle cells) extruded over 4
# planes, traced with --min-size 0 --holes keep. The loops of a plane are the boundaries of the
# superlevel set {f > 0.5} of the bilinear interpolant of the smoothed indicator f: every
# component holds a grid node (a bilinear cell takes its maximum at a corner), so the components
# are the inside nodes joined along cell edges and across the saddle cells whose saddle value is
# above 0.5 (the asymptotic decider); holes are the bounded components of the rest, joined across
# the other saddle cells. Counted by a union-find here and compared with the file's counterclockwise
# and clockwise loops on every layer.
$PY - <<'EOF'
import numpy as np, nibabel as nib
rng = np.random.default_rng(7)
n = 30
pat = (rng.random((n, n)) < 0.5).astype(np.uint8)
lab = np.repeat(pat[:, :, None], 4, axis=2)
nib.save(nib.Nifti1Image(lab, np.diag([2.0, 2.0, 2.0, 1.0])), 'random.nii.gz')
from scipy.ndimage import convolve1d
w = np.exp(-0.5 * np.arange(-2, 3) ** 2 / 0.25); w /= w.sum()
f = np.pad(pat.astype(np.float64), 3)
f = convolve1d(f, w, axis=0, mode='constant').astype(np.float32)
f = convolve1d(f.astype(np.float64), w, axis=1, mode='constant').astype(np.float32).astype(np.float64)
f[f == np.float32(0.5)] = np.nextafter(np.float32(0.5), np.float32(0))
W, H = f.shape
parent = list(range(W * H))
def find(a):
    while parent[a] != a:
        parent[a] = parent[parent[a]]; a = parent[a]
    return a
def union(a, b): parent[find(a)] = find(b)
inside = f > 0.5
idx = lambda i, j: i * H + j
for i in range(W):
    for j in range(H):
        if i + 1 < W and inside[i, j] == inside[i + 1, j]: union(idx(i, j), idx(i + 1, j))
        if j + 1 < H and inside[i, j] == inside[i, j + 1]: union(idx(i, j), idx(i, j + 1))
        if i + 1 < W and j + 1 < H:
            c = [f[i, j], f[i + 1, j], f[i + 1, j + 1], f[i, j + 1]]
            ins = [v > 0.5 for v in c]
            if sum(ins) == 2 and ins[0] == ins[2]:
                den = c[0] + c[2] - c[1] - c[3]
                sv = (c[0] * c[2] - c[1] * c[3]) / den if den != 0 else sum(c) / 4
                if ins[0] == (sv > 0.5): union(idx(i, j), idx(i + 1, j + 1))  # the 0-2 diagonal joined
                else: union(idx(i + 1, j), idx(i, j + 1))                     # the 1-3 diagonal joined
roots_in = {find(idx(i, j)) for i in range(W) for j in range(H) if inside[i, j]}
roots_out = {find(idx(i, j)) for i in range(W) for j in range(H) if not inside[i, j]} - {find(0)}
open('topology.txt', 'w').write(f"{len(roots_in)} {len(roots_out)}\n")
EOF
"$THORAX" digitize random.nii.gz --label 1=blobs:other --min-size 0 --holes keep -o rnd.txt -q
$PY - <<'EOF' || fail "topology of the random pattern"
want = tuple(map(int, open('topology.txt').read().split()))
layers = {}; z = None; pts = None
def close():
    if pts:
        a = 0.5 * sum(pts[i - 1][0] * pts[i][1] - pts[i][0] * pts[i - 1][1] for i in range(len(pts)))
        layers[z][0 if a > 0 else 1] += 1
for line in open('rnd.txt'):
    w = line.split('#')[0].split()
    if not w: continue
    if w[0] in ('layer', 'loop', 'end'):
        close(); pts = [] if w[0] == 'loop' else None
        if w[0] == 'layer': z = float(w[1]); layers[z] = [0, 0]
    elif pts is not None and len(w) == 2: pts.append(tuple(map(float, w)))
print('random pattern: components and holes (union-find)', want, 'traced per layer', sorted(layers.values()))
assert len(layers) == 4 and all(tuple(v) == want for v in layers.values()), (want, layers)
assert want[0] > 20 and want[1] > 0
EOF

# an oblique image (rotated 15 degrees about x): the model's axes are the image's, a warning says so,
# model.json's model_to_ras is the rotation, and the nodes carried to RAS lie on the ball
$PY - <<'EOF'
import numpy as np, nibabel as nib
a = np.radians(15); R = np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])
h = 3.0; n = 20
aff = np.eye(4); aff[:3, :3] = R * h; aff[:3, 3] = -R @ np.full(3, (n - 1) / 2 * h)
ijk = np.stack(np.meshgrid(*[np.arange(n)] * 3, indexing='ij'), -1).reshape(-1, 3)
sub = np.stack(np.meshgrid(*[(np.arange(4) + 0.5) / 4 - 0.5] * 3, indexing='ij'), -1).reshape(-1, 3)
votes = np.zeros(len(ijk))
for s in sub:
    p = (ijk + s) @ aff[:3, :3].T + aff[:3, 3]
    votes += ((p - [2, -1, 3]) ** 2).sum(1) <= 22 ** 2
nib.save(nib.Nifti1Image((votes > 32).reshape(n, n, n).astype(np.uint8), aff), 'oblique.nii.gz')
np.savetxt('R.txt', R)
EOF
"$THORAX" surfaces oblique.nii.gz --label 1=ball:other -o mo >/dev/null 2>err.txt
grep -q "the image is oblique (its superior axis 15 deg from RAS superior)" err.txt || fail "oblique warning: $(cat err.txt)"
"$THORAX" digitize oblique.nii.gz --label 1=ball:other -o co.txt -q 2>/dev/null
"$THORAX" check mo >/dev/null || fail "thorax check on the oblique model"
$PY - <<'EOF' || fail "oblique model_to_ras"
import json, numpy as np
R = np.loadtxt('R.txt'); m = json.load(open('mo/model.json'))
Q = np.array(m['provenance']['image']['model_to_ras']).reshape(3, 3)
assert np.abs(Q - R).max() < 1e-6, Q
# the contour nodes (the surfaces' caps are flat, so their grid nodes are not on the ball)
z = None; d = 0
for line in open('co.txt'):
    w = line.split('#')[0].split()
    if w and w[0] == 'layer': z = float(w[1])
    elif len(w) == 2 and z is not None and w[0] != 'loop':
        p = Q @ [float(w[0]), float(w[1]), z]
        d = max(d, abs(np.linalg.norm(p - [2, -1, 3]) - 22))
# the surface's volume (divergence theorem over its outward triangles)
P = np.loadtxt('mo/ball.pts'); F = np.loadtxt('mo/ball.fac', dtype=int) - 1
vol = np.einsum('ij,ij->i', P[F[:, 0]], np.cross(P[F[:, 1]], P[F[:, 2]])).sum() / 6
true = 4 / 3 * np.pi * 22 ** 3
print('oblique: contour nodes in RAS within %.3f mm of the ball; surface volume %+.2f%%' % (d, 100 * (vol / true - 1)))
assert d <= 0.61 * 3, d
# a small ball (7 voxels' radius): the surface stops at its first and last layers (flat caps; the
# caps beyond them hold about 2% of the ball) and its nodes are 3 mm apart: -4.6% measured
assert abs(vol / true - 1) < 0.06, vol / true
EOF

# planes resampled 5 mm apart (--spacing; --plane-spacing for surfaces)
"$THORAX" digitize labels.nii.gz --label 1=torso:outer --label 3=heart:heart --spacing 5 -o c5.txt -q
$PY -c "
z = [float(l.split()[1]) for l in open('c5.txt') if l.startswith('layer ')]
assert len(z) > 20 and all(abs(b - a - 5) < 1e-9 for a, b in zip(z, z[1:])), z" || fail "--spacing 5: layers"
"$THORAX" surfaces labels.nii.gz --label 1=torso:outer --label 3=heart:heart --plane-spacing 5 -o m5 -q
"$THORAX" check m5 >/dev/null || fail "check of the model from planes 5 mm apart"

# refusals: a named message, a non-zero exit, nothing written
bad() { # CODE PATTERN ARGS...
    local want=$1 pat=$2; shift 2
    set +e
    "$@" >out.txt 2>err.txt
    local rc=$?
    set -e
    [ $rc -eq "$want" ] || fail "exit $rc, expected $want: $* ($(cat err.txt))"
    grep -q -- "$pat" err.txt || fail "message for $*: $(cat err.txt)"
    [ ! -e out_c.txt ] && [ ! -e out_m ] || fail "something written: $*"
}
bad 2 "expected VALUE\[,VALUE...\]=NAME:ROLE" "$THORAX" digitize labels.nii.gz --label 1torso -o out_c.txt
bad 2 "label value 'x' is not an integer" "$THORAX" digitize labels.nii.gz --label 1,x=torso:outer -o out_c.txt
bad 2 "unknown role 'skin'" "$THORAX" digitize labels.nii.gz --label 1=torso:skin -o out_c.txt
bad 2 "no --label given" "$THORAX" digitize labels.nii.gz -o out_c.txt
bad 1 'tissue "nothing": none of its label values is in the image' \
    "$THORAX" digitize labels.nii.gz --label 1=torso:outer --label 9=nothing:other -o out_c.txt
bad 1 "not a label map" "$THORAX" digitize float.nii.gz --label 1=torso:outer -o out_c.txt
bad 1 "not a label map" "$THORAX" surfaces float.nii.gz --label 1=torso:outer -o out_m
bad 2 "digitize the label map first" "$THORAX" surfaces labels.nii.gz --label 1=torso:outer --edits x.txt -o out_m
bad 2 "labels.nii.gz is an image: give the surfaces' labels" "$THORAX" surfaces labels.nii.gz -o out_m
bad 2 "are for a label map: give --label" "$THORAX" surfaces c.txt --min-size 3 -o out_m
bad 1 "no_such.nii" "$THORAX" digitize no_such.nii --label 1=torso:outer -o out_c.txt
# a value absent from the image: a warning, the surface traced from the others
"$THORAX" digitize labels.nii.gz --label 1,7=torso:outer -o c7.txt >/dev/null 2>err.txt
grep -q "label value 7 (--label) is not in the image" err.txt || fail "absent value warning: $(cat err.txt)"
grep -q "^loop torso" c7.txt || fail "absent value: no contours"
# a path with '#' and '%' (the image line escapes them as %XX; the reader gives the path back)
cp labels.nii.gz 'we#ird%20.nii.gz'
"$THORAX" digitize 'we#ird%20.nii.gz' --label 1=torso:outer -o cw.txt -q
grep -qx "image sha256:$sha we%23ird%2520.nii.gz" cw.txt || fail "escaped image line: $(grep '^image' cw.txt)"
"$THORAX" surfaces cw.txt -o mw -q
$PY -c "
import json; im = json.load(open('mw/model.json'))['provenance']['image']
assert im == {'file': 'we#ird%20.nii.gz', 'sha256': '$sha'}, im" || fail "the escaped path read back"
# siblings that touch (a segmentation's map: no voxel between the lung and the heart, face contact on
# many planes): the surfaces keep a gap, pass thorax check and mesh
$PY - <<'EOF'
import numpy as np, nibabel as nib
h = 2.0; n = 40
ax = (np.arange(n) - (n - 1) / 2) * h
X, Y, Z = np.meshgrid(ax, ax, ax, indexing='ij')
lab = np.zeros((n, n, n), np.uint8)
lab[X**2 + Y**2 + Z**2 <= 36**2] = 1
lab[(X + 9)**2 + Y**2 + Z**2 <= 14**2] = 2
lab[(X - 9)**2 + Y**2 + Z**2 <= 12**2] = 3
faces = ((lab[:-1] == 2) & (lab[1:] == 3)).sum()
planes = np.unique(np.nonzero((lab[:-1] == 2) & (lab[1:] == 3))[2]).size
assert faces > 50 and planes >= 8, (faces, planes)
aff = np.diag([h, h, h, 1.0]); aff[:3, 3] = ax[0]
nib.save(nib.Nifti1Image(lab, aff), 'touch.nii.gz')
EOF
"$THORAX" digitize touch.nii.gz --label 1,2,3=torso:outer --label 2=lung:lung --label 3=heart:heart -o ct.txt >rt.txt
grep -q "^heart: .* voxels face a sibling tissue's" rt.txt || fail "contact not reported: $(cat rt.txt)"
$PY - <<'EOF' || fail "sibling gap"
import numpy as np
z = None; cur = None; L = {}
for line in open('ct.txt'):
    w = line.split('#')[0].split()
    if not w: continue
    if w[0] == 'layer': z = float(w[1])
    elif w[0] == 'loop': cur = w[1]; L.setdefault((cur, z), []).append([])
    elif len(w) == 2 and cur: L[(cur, z)][-1].append((float(w[0]), float(w[1])))
def gap(P, Q):
    Q2 = np.roll(Q, -1, 0); d = Q2 - Q
    t = np.clip(((P[:, None] - Q[None]) * d[None]).sum(2) / (d * d).sum(1)[None], 0, 1)
    return np.hypot(*(Q[None] + t[..., None] * d[None] - P[:, None]).transpose(2, 0, 1)).min()
g = [min(gap(np.array(a), np.array(b)), gap(np.array(b), np.array(a)))
     for (s, zz), A in L.items() if s == 'lung' and ('heart', zz) in L for a in A for b in L[('heart', zz)]]
print('lung-heart: %d planes, least gap %.3f mm' % (len(g), min(g)))
assert len(g) >= 8 and min(g) > 0.8, g
EOF
"$THORAX" surfaces ct.txt -o mt -q || fail "thorax surfaces on touching siblings"
"$THORAX" check mt >chkt.txt || { cat chkt.txt; fail "thorax check on touching siblings"; }
"$THORAX" mesh mt -o mmt -q || fail "thorax mesh on touching siblings"
[ -f mmt/volume.tet ] || fail "no volume mesh (touching siblings)"

echo "e2e_digitize: ok"
