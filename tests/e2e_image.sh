#!/bin/bash
# End-to-end: `thorax image info|convert` against files other programs write and read.
#  - nibabel writes NIfTI-1 and NIfTI-2 files: sform only, qform only, neither (pixdim: the standard's
#    method 1, x = pixdim * i, no offset), scl_slope/scl_inter, int8, uint16, float64, a 4-D file with
#    one volume (read) and one with several (refused); `info --json` gives each one's affine as
#    nibabel computes it (sform, else qform), and the voxels (converted to .nii by thorax, read back
#    by nibabel) equal nibabel's scaled data;
#  - convert between every format (.nii, .nii.gz, .nrrd, .mha) in a chain: identical voxels and
#    geometry at every step, nibabel reading the last one;
#  - pynrrd's NRRD test files (tests/data/pynrrd: raw, gzip, detached, line and byte skips, ascii)
#    read as the ball of the NIfTI file beside them, voxel for voxel and affine for affine; the
#    variants thorax does not read (bzip2, 4-D, 1-D, a negative byte skip) refused by name;
#  - VTK (python3-vtk9's vtkNrrdReader and vtkMetaImageReader) reads thorax's .nrrd and .mha: the same
#    voxels, spacing and origin (NRRD: RAS as written; MetaImage: ITK's LPS, x and y negated);
#  - VTK's vtkMetaImageWriter (MetaIO) writes a compressed .mha and a .mhd + .raw: thorax reads its
#    voxels and spacing, and its Offset as LPS;
#  - info's text: the superior/anterior/left axes and their cosines of an oblique grid against numpy,
#    the label counts and volumes of a label map against numpy;
#  - bad images exit 1 with a message naming the file, and convert writes nothing: truncated data, a
#    NaN voxel, a zero spacing, a skewed sform, an NRRD file named .nii, a non-image; usage errors exit 2.
# Env: THORAX (built CLI), SRC (source dir), WORK (scratch dir, created here).
set -eu
: "${THORAX:?}" "${SRC:?}" "${WORK:?}"
PY=/usr/bin/python3
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK"
fail() { echo "e2e_image: FAIL: $*" >&2; exit 1; }
. "$SRC/tests/expect_rc.sh"

# ---- usage
expect_rc 2 "$THORAX" image
expect_rc 2 "$THORAX" image frobnicate x.nii
expect_rc 2 "$THORAX" image info
expect_rc 2 "$THORAX" image convert x.nii
expect_rc 2 "$THORAX" image info x.nii -o y.nii
expect_rc 1 "$THORAX" image info missing.nii
grep -q "missing.nii" err.txt || fail "missing file: no name in the message"

# ---- nibabel's NIfTI files
$PY - <<'EOF'
import nibabel as nib, numpy as np
rng = np.random.default_rng(5)
A = np.array([[0.9, 0.1, 0.0, -40.0], [-0.1, 0.9, 0.2, 12.5], [0.0, -0.2, 0.9, 80.0], [0, 0, 0, 1]])
# an orthonormal rotation scaled by the spacing
q, _ = np.linalg.qr(A[:3, :3])
q = q @ np.diag(np.sign(np.diag(q)))
sp = np.array([0.8, 1.2, 2.5])
aff = np.eye(4); aff[:3, :3] = q * sp; aff[:3, 3] = [-40, 12.5, 80]
data = rng.integers(-50, 200, size=(12, 9, 7)).astype(np.int16)
def save(img, name):
    nib.save(img, name)
img = nib.Nifti1Image(data, None); img.set_sform(aff, code=1); img.set_qform(None, code=0); save(img, 'sform.nii.gz')
img = nib.Nifti1Image(data, None); img.set_qform(aff, code=1); img.set_sform(None, code=0); save(img, 'qform.nii')
img = nib.Nifti1Image(data, None); img.set_qform(None, code=0); img.set_sform(None, code=0)
img.header.set_zooms((0.7, 0.9, 3.0)); save(img, 'pixdim.nii')
img = nib.Nifti2Image(data, aff); save(img, 'nifti2.nii')
img = nib.Nifti1Image(data, aff); img.header.set_slope_inter(0.5, -3.0); save(img, 'scaled.nii')
for t in ('int8', 'uint16', 'float64'):
    d = (data % 100).astype(t) if t != 'float64' else data.astype(t) * 0.25
    nib.save(nib.Nifti1Image(d, aff), 'type_%s.nii.gz' % t)
nib.save(nib.Nifti1Image(data[..., None], aff), 'four1.nii.gz')
nib.save(nib.Nifti1Image(np.stack([data, data], axis=3), aff), 'four2.nii.gz')
EOF
NIFTIS="sform.nii.gz qform.nii pixdim.nii nifti2.nii scaled.nii type_int8.nii.gz type_uint16.nii.gz type_float64.nii.gz four1.nii.gz"
for f in $NIFTIS; do
    "$THORAX" image info "$f" --json > "$f.json" || fail "info $f"
    "$THORAX" image convert "$f" -o "$f.back.nii" --type float32 -q || fail "convert $f"
done
# info's affine = nibabel's (sform > qform > pixdim), our voxels = nibabel's scaled data
$PY - $NIFTIS <<'EOF' || fail "nibabel disagrees"
import json, sys, numpy as np, nibabel as nib
for f in sys.argv[1:]:
    j = json.load(open(f + '.json'))
    img = nib.load(f)
    h = img.header
    if int(h['sform_code']) > 0: want = h.get_sform()
    elif int(h['qform_code']) > 0: want = h.get_qform()
    else: want = np.diag(list(h.get_zooms()[:3]) + [1.0])
    D = np.array(j['direction_rows']); sp = np.array(j['spacing_mm']); o = np.array(j['origin_ras_mm'])
    got = np.eye(4); got[:3, :3] = D * sp; got[:3, 3] = o
    if not np.allclose(got, want, atol=2e-5):
        sys.exit('%s: affine\n%s\nnibabel\n%s' % (f, got, want))
    data = np.asanyarray(img.dataobj).astype(np.float64)
    if data.ndim == 4: data = data[..., 0]
    back = nib.load(f + '.back.nii')
    mine = np.asanyarray(back.dataobj).astype(np.float64)
    if mine.shape != data.shape or not np.array_equal(mine, data.astype(np.float32).astype(np.float64)):
        sys.exit('%s: voxels differ' % f)
    if not np.allclose(back.affine, want, atol=2e-5): sys.exit('%s: our .nii affine differs' % f)
    if abs(j['min'] - data.min()) > 1e-6 or abs(j['max'] - data.max()) > 1e-6: sys.exit('%s: range' % f)
EOF
grep -q '"format":	"nifti2"' <("$THORAX" image info nifti2.nii --json) || fail "nifti2 not reported"
"$THORAX" image info pixdim.nii | grep -q "pixdim" || fail "pixdim frame not reported"
expect_rc 1 "$THORAX" image info four2.nii.gz
grep -q "four2.nii.gz: a 4-D image" err.txt || fail "4-D: $(cat err.txt)"

# ---- convert between every format: identical voxels and geometry
prev=sform.nii.gz
"$THORAX" image info "$prev" --json > chain0.json
k=0
for out in a.nrrd b.mha c.nii d.nii.gz e.nrrd f.mha g.nii; do
    "$THORAX" image convert "$prev" -o "$out" -q || fail "convert $prev -> $out"
    k=$((k + 1))
    "$THORAX" image info "$out" --json > "chain$k.json"
    prev=$out
done
$PY - <<'EOF' || fail "a conversion changed the image"
import json, numpy as np
ja = json.load(open('chain0.json'))
for k in range(1, 8):
    jb = json.load(open('chain%d.json' % k))
    for key in ('dimensions', 'labels', 'min', 'max'):
        assert ja[key] == jb[key], (k, key, ja[key], jb[key])
    for key in ('spacing_mm', 'origin_ras_mm', 'direction_rows'):
        assert np.allclose(ja[key], jb[key], atol=1e-6), (k, key, ja[key], jb[key])
EOF
$PY - <<'EOF' || fail "the chain's .nii.gz or .nii differs from the first (nibabel)"
import nibabel as nib, numpy as np
a = nib.load('sform.nii.gz')
for name in ('d.nii.gz', 'g.nii'):
    b = nib.load(name)
    assert np.array_equal(np.asanyarray(a.dataobj), np.asanyarray(b.dataobj)), name
    assert np.allclose(a.affine, b.affine, atol=1e-5), name
    assert b.header['descrip'].tobytes().startswith(b'thorax-image'), name
EOF
head -c 300 a.nrrd | grep -q "^# thorax-image" || fail "no marker in the NRRD header"
head -c 300 b.mha | grep -q "^Comment = thorax-image" || fail "no marker in the MetaImage header"
# ... and over a file thorax did not write: refused, the file untouched
cp sform.nii.gz theirs.nii.gz
expect_rc 1 "$THORAX" image convert a.nrrd -o theirs.nii.gz
cmp -s sform.nii.gz theirs.nii.gz || fail "convert replaced a file thorax did not write"

# ---- VTK reads our NRRD and MetaImage files (axis-aligned: VTK 9.1's readers keep no direction)
$PY - <<'EOF'
import nibabel as nib, numpy as np
d = (np.arange(14 * 11 * 5) % 23).astype(np.int16).reshape(14, 11, 5, order='F') - 5
aff = np.diag([0.75, 1.5, 2.0, 1.0]); aff[:3, 3] = [-20.0, 31.5, 7.25]
nib.save(nib.Nifti1Image(d, aff), 'plain.nii.gz')
EOF
"$THORAX" image convert plain.nii.gz -o plain.nrrd -q
"$THORAX" image convert plain.nii.gz -o plain.mha -q
$PY - <<'EOF' || fail "VTK reads our NRRD/MetaImage differently"
import numpy as np, nibabel as nib
from vtkmodules.vtkIOImage import vtkNrrdReader, vtkMetaImageReader
from vtkmodules.util.numpy_support import vtk_to_numpy
d = np.asanyarray(nib.load('plain.nii.gz').dataobj)
for R, f, o in ((vtkNrrdReader, 'plain.nrrd', (-20, 31.5, 7.25)), (vtkMetaImageReader, 'plain.mha', (20, -31.5, 7.25))):
    r = R(); r.SetFileName(f); r.Update(); img = r.GetOutput()
    dims = img.GetDimensions()
    assert dims == d.shape, (f, dims)
    v = vtk_to_numpy(img.GetPointData().GetScalars()).reshape(dims[::-1]).transpose(2, 1, 0)
    assert np.array_equal(v, d), f
    assert np.allclose(img.GetSpacing(), (0.75, 1.5, 2.0)), (f, img.GetSpacing())
    assert np.allclose(img.GetOrigin(), o), (f, img.GetOrigin())
EOF

# ---- pynrrd's test files (tests/data/pynrrd, written by ITK/teem-style writers): every readable
# variant gives the ball of the NIfTI file beside them, voxel for voxel, with the same RAS affine
# (their LPS identity = RAS diag(-1, -1, 1)); the ones thorax does not read are refused by name
P=$SRC/tests/data/pynrrd
for f in BallBinary30x30x30.nrrd BallBinary30x30x30.nhdr BallBinary30x30x30_gz.nrrd BallBinary30x30x30_gz_lineskip.nrrd \
         BallBinary30x30x30_gz_byteskip_minus_one.nrrd BallBinary30x30x30_byteskip_minus_one.nhdr \
         BallBinary30x30x30_byteskip_minus_one_nifti.nhdr test2d_ascii.nrrd; do
    "$THORAX" image convert "$P/$f" -o "pynrrd_$f.nii" -q || fail "pynrrd's $f"
done
$PY - "$P" <<'EOF' || fail "pynrrd's files read differently from their NIfTI twin"
import sys, glob, numpy as np, nibabel as nib
P = sys.argv[1]
ref = nib.load(P + '/BallBinary30x30x30.nii.gz')
want = np.asanyarray(ref.dataobj)
assert np.allclose(ref.affine, np.diag([-1.0, -1, 1, 1]))
names = sorted(glob.glob('pynrrd_Ball*.nii'))
assert len(names) == 7, names
for name in names:
    img = nib.load(name)
    assert np.array_equal(np.asanyarray(img.dataobj), want), name
    assert np.allclose(img.affine, ref.affine), (name, img.affine)
a = nib.load('pynrrd_test2d_ascii.nrrd.nii')
assert a.shape == (3, 9, 1)
assert np.array_equal(np.asanyarray(a.dataobj)[:, :, 0], np.arange(1, 28).reshape(9, 3).T)
assert np.allclose(a.header.get_zooms(), (1.0458, 2, 1))
EOF
for bad in "BallBinary30x30x30_bz2.nrrd:encoding \"bzip2\" is not supported" \
           "test_simple4d_raw.nrrd:dimension 4" "test_customFields.nrrd:dimension 1" \
           "BallBinary30x30x30_byteskip_minus_five.nhdr:byte skip \"-5\"" \
           "BallBinary30x30x30_nifti.nhdr:hold more than the header's 54000 bytes"; do
    f=${bad%%:*} want=${bad#*:}
    expect_rc 1 "$THORAX" image info "$P/$f"
    grep -qF "$want" err.txt || fail "pynrrd's $f: expected \"$want\", got: $(cat err.txt)"
done

# ---- VTK writes MetaImage (vtkMetaImageWriter, MetaIO inside): a compressed .mha and a .mhd with its
# .raw; thorax reads VTK's voxels, spacing, and its Offset as LPS (RAS: x and y negated)
$PY - <<'EOF'
import numpy as np
from vtkmodules.vtkIOImage import vtkMetaImageWriter
from vtkmodules.vtkCommonDataModel import vtkImageData
from vtkmodules.util.numpy_support import numpy_to_vtk
d = (np.arange(13 * 7 * 5) % 17).astype(np.int16) - 3   # i fastest
img = vtkImageData(); img.SetDimensions(13, 7, 5); img.SetSpacing(0.5, 1.25, 3.0); img.SetOrigin(-7.5, 12, 30)
img.GetPointData().SetScalars(numpy_to_vtk(d, deep=1))
for comp, name in ((1, 'vtk_z.mha'), (0, 'vtk_raw.mhd')):
    w = vtkMetaImageWriter(); w.SetInputData(img); w.SetFileName(name); w.SetCompression(comp); w.Write()
EOF
for f in vtk_z.mha vtk_raw.mhd; do
    "$THORAX" image info "$f" --json > "$f.json" || fail "VTK's $f"
    "$THORAX" image convert "$f" -o "$f.nii" -q || fail "VTK's $f"
done
$PY - <<'EOF' || fail "VTK's MetaImage files read wrongly"
import json, numpy as np, nibabel as nib
d = (np.arange(13 * 7 * 5) % 17).astype(np.int16) - 3
for f in ('vtk_z.mha', 'vtk_raw.mhd'):
    j = json.load(open(f + '.json'))
    assert j['dimensions'] == [13, 7, 5] and np.allclose(j['spacing_mm'], (0.5, 1.25, 3.0)), f
    assert np.allclose(j['origin_ras_mm'], (7.5, -12, 30)), (f, j['origin_ras_mm'])
    assert np.allclose(j['direction_rows'], np.diag([-1.0, -1, 1])), f
    v = np.asanyarray(nib.load(f + '.nii').dataobj)
    assert np.array_equal(v.ravel(order='F'), d), f
EOF

# ---- info's text: the meaning of an oblique grid; a label map's counts and volumes
"$THORAX" image info sform.nii.gz > info.txt
$PY - <<'EOF' || fail "info's axes or labels disagree with numpy: $(cat info.txt)"
import re, numpy as np, nibabel as nib
t = open('info.txt').read()
img = nib.load('sform.nii.gz'); a = img.affine[:3, :3]; D = a / np.linalg.norm(a, axis=0)
sup = int(np.argmax(abs(D[2]))); sgn = '+' if D[2, sup] > 0 else '-'
m = re.search(r'^superior\s+([+-])([ijk]) \(cos ([0-9.]+)\)', t, re.M)
assert m and m.group(1) == sgn and 'ijk'.index(m.group(2)) == sup, m
assert abs(float(m.group(3)) - abs(D[2, sup])) < 1e-6
assert re.search(r'^planes\s+oblique, nearest axial', t, re.M)
vals, cnt = np.unique(np.asanyarray(img.dataobj), return_counts=True)
ml = np.prod(np.linalg.norm(a, axis=0)) / 1000  # the sform's spacing (pixdim is not set here)
assert 'labels      %d distinct values' % len(vals) in t
for v, c in zip(vals, cnt):
    m = re.search(r'^\s+%d: (\d+) voxels, ([0-9.e+-]+) mL' % v, t, re.M)
    assert m and int(m.group(1)) == c and abs(float(m.group(2)) - c * ml) <= 1e-5 * c * ml, (v, m)
EOF
grep -q "^sha256      $(sha256sum sform.nii.gz | cut -d' ' -f1)" info.txt || fail "sha256 differs from sha256sum"

# ---- bad images: exit 1, the file named, nothing written
$PY - <<'EOF'
import nibabel as nib, numpy as np
d = np.ones((6, 5, 4), np.float32)
img = nib.Nifti1Image(d, np.eye(4)); nib.save(img, 'good.nii')
b = open('good.nii', 'rb').read(); open('cut.nii', 'wb').write(b[:-10])
d2 = d.copy(); d2[2, 1, 3] = np.nan; nib.save(nib.Nifti1Image(d2, np.eye(4)), 'nan.nii.gz')
z = np.eye(4); z[1, 1] = 0; img = nib.Nifti1Image(d, None); img.set_sform(z, 1); img.set_qform(None, 0); nib.save(img, 'zero.nii.gz')
s = np.eye(4); s[0, 1] = 0.5; img = nib.Nifti1Image(d, None); img.set_sform(s, 1); img.set_qform(None, 0); nib.save(img, 'skew.nii.gz')
open('really.nii', 'w').write('NRRD0004\ntype: short\ndimension: 3\nsizes: 2 2 2\nencoding: raw\nendian: little\n\n' + 'x' * 16)
open('words.nrrd', 'w').write('hello\n')
# headers claiming more voxels than their files hold (4 x 4 x 4 int16 = 128 bytes; 100 there)
open('short.nrrd', 'wb').write(b'NRRD0004\ntype: short\ndimension: 3\nsizes: 4 4 4\nendian: little\nencoding: raw\n\n' + bytes(100))
open('short.mha', 'wb').write(b'ObjectType = Image\nNDims = 3\nDimSize = 4 4 4\nElementType = MET_SHORT\nElementDataFile = LOCAL\n' + bytes(100))
EOF
for bad in "cut.nii:truncated" "nan.nii.gz:is NaN" "zero.nii.gz:spacing along axis 2 is 0" \
           "skew.nii.gz:not orthonormal" "really.nii:named as NIfTI but the file is a NRRD file" \
           "words.nrrd:not an NRRD file" "short.nrrd:(128 bytes) but the data hold 100 bytes: truncated" \
           "short.mha:(128 bytes) but the data hold 100 bytes: truncated"; do
    f=${bad%%:*} want=${bad#*:}
    expect_rc 1 "$THORAX" image info "$f"
    grep -q "$f" err.txt && grep -q "$want" err.txt || fail "$f: expected \"$want\", got: $(cat err.txt)"
    for o in out.nii.gz out.nrrd out.mha; do
        expect_rc 1 "$THORAX" image convert "$f" -o "$o"
        [ ! -e "$o" ] || fail "convert of $f wrote $o"
    done
done
ls -a | grep -q '\.tmp' && fail "temporary files left: $(ls -a | grep '\.tmp')"
expect_rc 1 "$THORAX" image convert good.nii -o out.nhdr
grep -q ".nrrd" err.txt || fail ".nhdr writing: $(cat err.txt)"
[ ! -e out.nhdr ] || fail ".nhdr written"
echo "e2e_image: ok"
