#!/bin/bash
# End-to-end on a real CT (issue 25, 5(c)): InVesalius' example Cranium.inv3 (Debian package
# invesalius-examples; 256 x 256 x 108 voxels, 0.957 x 0.957 x 1.5 mm, slice 0 inferior) read by
# tests/inv3_to_nifti.py (tarfile + plistlib + nibabel), labelled by thorax image label (soft
# tissue -400 HU up, bone 120 HU up, largest components, holes filled in the planes), built into
# a two-surface head (scalp = soft tissue and bone, skull = bone with the cranial cavity filled),
# checked, meshed, and solved for dipoles inside the skull by the BEM and the FEM.
#
# Cropped at z = 90 mm (the planes above the skull base, 48 of them): below it the skull base's
# loops (foramina, orbits, sinuses: 114 end caps) still lace with crossing triangles on 3 slice
# groups and the scalp on 1 (docs/design/geom.md, "Filled pockets"); the crop keeps the case this
# test is about: through z = 91.5 .. 112.5 the skull's loop runs in through the frontal sinus's
# notch and around the whole cranial cavity, on the plane above it is the outside only, and the
# lacing fanned the cavity across the skull (1,658 crossing pairs; now the cavity is cut in its
# plane first).
#
# The BEM (thorax bem --dipoles, symmetric Galerkin) and the FEM (thorax forward --dipoles,
# linear tetrahedra) are independent solutions of the same problem on the same surfaces; on the
# scalp's nodes they must agree (relative difference measure and magnitude ratio of the
# zero-mean potentials), as tests/e2e_bem.sh checks on the Dalhousie torso.
# Env: THORAX (built CLI), SRC (source dir), WORK (scratch dir, created here).
set -eu
: "${THORAX:?}" "${SRC:?}" "${WORK:?}"
PY=/usr/bin/python3
INV=/usr/share/doc/invesalius-examples/examples/Cranium.inv3
if [ ! -f "$INV" ]; then echo "e2e_cranium: $INV missing (Debian package invesalius-examples); skipped"; exit 77; fi
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK"
fail() { echo "e2e_cranium: FAIL: $*" >&2; exit 1; }

"$PY" -B "$SRC/tests/inv3_to_nifti.py" "$INV" ct.nii.gz --zmin 90 > conv.log || fail "inv3_to_nifti: $(cat conv.log)"
# the converter against the project's own description of the volume, read back by nibabel
"$PY" - <<'EOF' || fail "converted CT"
import nibabel as nib, numpy as np
im = nib.load("ct.nii.gz")
assert im.shape == (256, 256, 48), im.shape
assert np.allclose(im.header.get_zooms(), (0.9570312, 0.9570312, 1.5), atol=1e-6), im.header.get_zooms()
assert abs(im.affine[2, 3] - 90.0) < 1e-9, im.affine
a = np.asarray(im.dataobj)
assert a.dtype == np.int16 and a.min() == -1024, (a.dtype, a.min())
EOF

"$THORAX" image label ct.nii.gz --tissue -400:=1/2 --tissue 120:=2/10 --largest --fill-planes -o labels.nii.gz -q ||
    fail "image label"

# 1. the whole resolution (every plane, nodes 1.5 mm apart): the failing case. The lacing no longer
#    crosses (1,658 pairs before), and the cavity it cuts in the notch's plane is given grid nodes
#    (build step 3b), but the slice between z = 99 and 100.5 keeps a fan of ~440 triangles across
#    the skull (edges ~115 mm long, angles under the check's 1-degree floor: what thorax mesh can
#    take), so `surfaces` refuses the model by that name alone and every other check passes. Open
#    (docs/design/geom.md, "The cut's triangles"). The 6 mm model below passes the whole check and is
#    meshed and solved.
"$THORAX" surfaces labels.nii.gz --label 1,2=scalp:outer --label 2=skull:other -o full -v > full.log 2>&1 &&
    fail "surfaces at 1.5 mm passed the check: the in-plane cut's thin triangles are gone? then check it whole"
grep -q 'surface "skull" fails the check: quality: triangle [0-9]* has a [0-9.]* deg angle (< 1 deg' full.log ||
    fail "surfaces at 1.5 mm: not refused for the in-plane cut's angles alone: $(grep -v '^thorax: surface' full.log | head -5)"
"$THORAX" surfaces labels.nii.gz --label 1,2=scalp:outer --label 2=skull:other -o full -v --unchecked > full.log 2>&1 ||
    fail "surfaces --unchecked at 1.5 mm: $(head -5 full.log)"
grep -q "keep crossing" full.log && fail "crossing lacing left: $(grep 'keep crossing' full.log)"
grep -q "surface skull:.*[1-9][0-9]* filled pockets" full.log || fail "no filled pocket cut: $(grep 'surface skull' full.log)"
"$THORAX" check full --min-angle 0 -q || fail "thorax check full --min-angle 0 (closed, no crossing, no meeting)"

# 2. a coarse model for the volume mesh and the solvers (planes and nodes 6 mm apart: the
#    sinus's notch is still a filled pocket there), two compartments: scalp 0.33 S/m, the inside
#    of the skull surface (bone and the cavity it holds, one region here) 0.0825 S/m
"$THORAX" surfaces labels.nii.gz --label 1,2=scalp:outer --label 2=skull:other --plane-spacing 6 --spacing 6 \
    -o head -v > head.log 2>&1 || fail "surfaces at 6 mm: $(grep -v '^thorax: surface' head.log | head -5)"
grep -q "surface skull:.*[1-9][0-9]* filled pockets" head.log || fail "no filled pocket at 6 mm: $(grep 'surface skull' head.log)"
"$THORAX" check head -q || fail "thorax check head"
"$THORAX" mesh head --grid 12 --region mean_thorax=scalp:0.33 --region skull=inner:0.0825 -q > mesh.log 2>&1 ||
    fail "mesh: $(cat mesh.log)"
"$THORAX" check head -q || fail "thorax check of the meshed head"

# dipoles inside the skull surface, in the upper part of the cavity (34 mm or more above the
# skull's lowest plane): three orientations and an oblique one
"$PY" - <<'EOF' || fail "dipoles"
import numpy as np
s = np.loadtxt("head/skull.pts"); c = s.mean(0); lo = s.min(0); x = s.max(0) - lo
z = lo[2] + 0.7 * x[2]
P = [[c[0], c[1], z], [c[0] + 0.2 * x[0], c[1], z], [c[0], c[1] + 0.2 * x[1], z],
     [c[0] - 0.15 * x[0], c[1] - 0.15 * x[1], z - 0.1 * x[2]]]
Q = [[0, 0, 1], [1, 0, 0], [0, 1, 0], [0.5, 0.5, 0.7]]
open("head.dip", "w").write("".join("%.6f %.6f %.6f %g %g %g\n" % (*p, *q) for p, q in zip(P, Q)))
EOF
"$THORAX" forward head --dipoles head.dip -o fem --format text -q > fem.log 2>&1 || fail "forward: $(cat fem.log)"
"$THORAX" bem head --dipoles head.dip -o bem --format text -q > bem.log 2>&1 || fail "bem: $(cat bem.log)"
"$PY" - <<'EOF' || fail "BEM against FEM on the Cranium head"
import json
import numpy as np
def read(p):
    L = open(p).read().split("\n")
    i = [k for k, l in enumerate(L) if l.startswith("dt")][0]
    return np.loadtxt([l for l in L[i + 1:] if l.strip() and l != "end"])
j = json.load(open("bem/bem.json"))
assert j["unit"] == "mV" and j["method"].startswith("symmetric"), j
n = len(np.loadtxt("head/scalp.pts"))
F, B = read("fem/torso.txt"), read("bem/outer.txt")
assert F.shape == B.shape == (n, 4), (F.shape, B.shape, n)
# Two discretizations 6 mm apart of a scalp 4 to 7 mm thick: measured RDM 0.04 .. 0.11 and MAG
# 0.97 .. 1.00 on every scalp node, the worst on the flat bottom cap (the crop plane z = 90), which
# runs 6 mm below the skull's lowest plane with 6 mm triangles; above z = 100 mm RDM 0.04 .. 0.07.
# The bounds are 1.5 times those. A cavity left open or fanned across the skull (the fault this
# test is about) fails thorax check above; a wrong conductivity or orientation moves MAG or RDM
# far beyond them.
P = np.loadtxt("head/scalp.pts"); up = P[:, 2] >= 100
for d in range(4):
    for sel, what, rmax in ((slice(None), "every scalp node", 0.16), (up, "z >= 100 mm", 0.10)):
        x = F[sel, d] - F[sel, d].mean(); y = B[sel, d] - B[sel, d].mean()
        rdm = np.linalg.norm(x / np.linalg.norm(x) - y / np.linalg.norm(y)); mag = np.linalg.norm(y) / np.linalg.norm(x)
        print("Cranium head, dipole %d, %s: BEM against FEM RDM %.4f MAG %.4f" % (d + 1, what, rdm, mag))
        assert rdm < rmax and abs(1 - mag) < 0.05, (d, what, rdm, mag)
EOF
echo "e2e_cranium: ok"
