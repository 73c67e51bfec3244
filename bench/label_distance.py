#!/usr/bin/env python3
"""How far a mesh's tissue interfaces lie from a label map's boundaries (bench/image.sh, issue 25 item 6):
one metric for every program.

Usage: label_distance.py LABELS.nii[.gz] NAME:PTS:A:B [NAME:PTS:A:B ...]

Each argument is one interface: PTS a text file of points `x y z` (mm, the image's RAS frame; extra
columns ignored; a thorax NAME.pts or CGAL's iface_A_B.pts), A and B comma-separated label values, B
may be `rest` (every value not in A). The label boundary of (A, B) is the set of voxel faces between a
voxel whose label is in A and its face neighbour whose label is in B (the volume padded with label 0,
so a label at the volume's border has faces there too): the staircase the label map itself draws.
For every point the distance to the nearest such face (an axis-aligned rectangle of the voxel's two
other spacings) is computed exactly: a k-d tree of the face centres gives candidates, and a point is
finished when the k-th candidate's centre lies farther than the best exact distance plus the largest
half-diagonal of a face (no face left unexamined can then be closer); the rest are done again with
all faces within that radius.

A smooth surface that follows the labels can still not lie on the staircase: where a boundary is
oblique to the grid the staircase's steps are up to about half a voxel off any smooth surface
through it, so distances of a few tenths of a voxel are the floor of a perfect reconstruction.

Prints one line per interface, `NAME points mean p95 max` (mm), then `all points mean p95 max`."""
import sys
import numpy as np
import nibabel as nib
from scipy.spatial import cKDTree


def faces(L, inA, inB, sp, origin):
    """Centres (mm) and normal axes of the voxel faces between an A voxel and a B voxel."""
    C, ax = [], []
    for a in range(3):
        lo = [slice(None)] * 3
        hi = [slice(None)] * 3
        lo[a] = slice(0, -1)
        hi[a] = slice(1, None)
        m = (inA[tuple(lo)] & inB[tuple(hi)]) | (inB[tuple(lo)] & inA[tuple(hi)])
        idx = np.argwhere(m).astype(np.float64)
        idx[:, a] += 0.5
        idx -= 1.0                    # the padding
        C.append(origin + idx * sp)
        ax.append(np.full(len(idx), a, dtype=np.int8))
    return np.concatenate(C), np.concatenate(ax)


def rect_distance(P, C, A, sp):
    """Distance from points P (n x 3) to faces with centres C (n x 3) and normal axes A (n,)."""
    half = np.tile(sp / 2.0, (len(P), 1))
    half[np.arange(len(P)), A] = 0.0
    d = np.maximum(np.abs(P - C) - half, 0.0)
    return np.sqrt((d * d).sum(axis=1))


def distances(P, C, A, sp, k=8):
    tree = cKDTree(C)
    hd = 0.5 * np.sqrt(max(sp[0] ** 2 + sp[1] ** 2, sp[0] ** 2 + sp[2] ** 2, sp[1] ** 2 + sp[2] ** 2))
    k = min(k, len(C))
    dc, ic = tree.query(P, k=k)
    dc, ic = dc.reshape(len(P), k), ic.reshape(len(P), k)
    best = np.full(len(P), np.inf)
    for j in range(k):
        best = np.minimum(best, rect_distance(P, C[ic[:, j]], A[ic[:, j]], sp))
    todo = np.nonzero((dc[:, -1] < best + hd) & (k < len(C)))[0]
    for i in todo:
        cand = tree.query_ball_point(P[i], best[i] + hd)
        best[i] = rect_distance(np.repeat(P[i:i + 1], len(cand), 0), C[cand], A[cand], sp).min()
    return best


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    img = nib.load(sys.argv[1])
    aff = img.affine
    if np.abs(aff[:3, :3] - np.diag(np.diag(aff[:3, :3]))).max() > 1e-9 or (np.diag(aff)[:3] <= 0).any():
        sys.exit("%s: only a diagonal affine with positive spacing is measured here" % sys.argv[1])
    sp = np.diag(aff)[:3].copy()
    origin = aff[:3, 3].copy()
    L = np.pad(np.asarray(img.dataobj), 1)
    allv = []
    for arg in sys.argv[2:]:
        name, path, a, b = arg.rsplit(":", 3)
        A = [int(v) for v in a.split(",")]
        inA = np.isin(L, A)
        inB = ~inA if b == "rest" else np.isin(L, [int(v) for v in b.split(",")])
        C, ax = faces(L, inA, inB, sp, origin)
        P = np.loadtxt(path, ndmin=2)[:, :3]
        if len(C) == 0 or len(P) == 0:
            print("%s %d - - -   (no %s)" % (name, len(P), "boundary faces" if len(C) == 0 else "points"))
            continue
        d = distances(P, C, ax, sp)
        allv.append(d)
        print("%s %d %.3f %.3f %.3f" % (name, len(d), d.mean(), np.percentile(d, 95), d.max()))
    if allv:
        d = np.concatenate(allv)
        print("all %d %.3f %.3f %.3f" % (len(d), d.mean(), np.percentile(d, 95), d.max()))


if __name__ == "__main__":
    main()
