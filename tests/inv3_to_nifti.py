"""InVesalius project (.inv3) -> NIfTI, for tests/e2e_cranium.sh.

An .inv3 file is a gzipped tar holding main.plist (the project: 'matrix' = {'filename', 'dtype',
'shape'}, 'spacing' = [sx, sy, sz] in mm) and the CT volume as raw bytes in C order with shape
(slices, rows, columns). The NIfTI written has i = column, j = row, k = slice, the voxel sizes
as its affine's diagonal (origin 0) and units mm; so that it reads back voxel for voxel.

usage: inv3_to_nifti.py IN.inv3 OUT.nii.gz [--zmin MM] [--zmax MM]
--zmin/--zmax keep the slices whose centre z = k * sz lies in the range (the affine's origin moved
so that the kept voxels keep their coordinates).
"""
import argparse
import plistlib
import sys
import tarfile

import nibabel as nib
import numpy as np


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("src")
    ap.add_argument("dst")
    ap.add_argument("--zmin", type=float, default=-np.inf)
    ap.add_argument("--zmax", type=float, default=np.inf)
    a = ap.parse_args()
    with tarfile.open(a.src, "r:gz") as t:
        files = {m.name.rsplit("/", 1)[-1]: m for m in t.getmembers() if m.isfile()}
        if "main.plist" not in files:
            sys.exit("%s: no main.plist: not an InVesalius project" % a.src)
        main_pl = plistlib.load(t.extractfile(files["main.plist"]))
        mat = main_pl["matrix"]
        raw = t.extractfile(files[mat["filename"]]).read()
    shape = tuple(int(s) for s in mat["shape"])
    dt = np.dtype(mat["dtype"])
    if len(raw) != int(np.prod(shape)) * dt.itemsize:
        sys.exit("%s: %s holds %d bytes, not %s x %d" % (a.src, mat["filename"], len(raw), shape, dt.itemsize))
    vol = np.frombuffer(raw, dtype=dt).reshape(shape).transpose(2, 1, 0)  # (columns, rows, slices)
    sx, sy, sz = (float(v) for v in main_pl["spacing"])
    z = np.arange(vol.shape[2]) * sz
    keep = np.nonzero((z >= a.zmin) & (z <= a.zmax))[0]
    if keep.size == 0:
        sys.exit("no slice between z = %g and %g mm" % (a.zmin, a.zmax))
    vol = np.ascontiguousarray(vol[:, :, keep[0]:keep[-1] + 1])
    aff = np.diag([sx, sy, sz, 1.0])
    aff[2, 3] = keep[0] * sz
    img = nib.Nifti1Image(vol, aff)
    img.header.set_xyzt_units("mm")
    nib.save(img, a.dst)
    print("%s: %s %s, %g x %g x %g mm, z = %g .. %g mm, %d .. %d" % (a.dst, vol.shape, vol.dtype, sx, sy, sz,
          keep[0] * sz, keep[-1] * sz, vol.min(), vol.max()))


if __name__ == "__main__":
    main()
