#!/usr/bin/env python3
"""Closed triangle surfaces (.pts/.fac) -> a NIfTI label map, and contour nodes -> their distance from
the surfaces: the real-data check of label-map tracing (tests/e2e_digitize_real.sh, issue 25).

  voxelize_surfaces.py label OUT.nii.gz H FRAME PTS FAC [PTS FAC ...]
      label 1 inside the first surface, 2 inside the second (and the first), ...: a voxel centre is
      inside by the parity of the crossings of a ray along the image's z; FRAME maps model
      coordinates to RAS: "ras" (none) or "dal" (the Dalhousie torso: superior -y, anterior -z).
  voxelize_surfaces.py dist CONTOURS STEP FRAME NAME=PTS,FAC ...
      every STEP-th node of each named surface's loops: its exact distance from the original surface
      (point-triangle, Ericson), in RAS; prints max, mean and the 99th percentile.
  voxelize_surfaces.py mdist MODEL FRAME NAME=PTS,FAC ...
      every node of each named surface of the rebuilt model (MODEL/NAME.pts, RAS): the same distance.
"""
import sys
import numpy as np


def load(pts, fac, frame):
    P = np.loadtxt(pts)
    F = np.loadtxt(fac, dtype=int)
    if F.min() == 1:
        F = F - 1
    if frame == "dal":  # superior -y, anterior -z, left +x: RAS = (-x, -z, -y)
        P = np.stack([-P[:, 0], -P[:, 2], -P[:, 1]], 1)
    return P, F


def inside(P, F, xs, ys, zs):
    A, B, C = P[F[:, 0]], P[F[:, 1]], P[F[:, 2]]
    h = xs[1] - xs[0]
    X, Y = np.meshgrid(xs + 1e-4 * h * np.pi, ys + 1e-4 * h * np.e, indexing="ij")  # off every edge
    X, Y = X.ravel(), Y.ravel()
    res = np.zeros((len(X), len(zs)), bool)
    for a, b, c in zip(A, B, C):
        d = (b[1] - c[1]) * (a[0] - c[0]) + (c[0] - b[0]) * (a[1] - c[1])
        if abs(d) < 1e-12:
            continue
        l1 = ((b[1] - c[1]) * (X - c[0]) + (c[0] - b[0]) * (Y - c[1])) / d
        l2 = ((c[1] - a[1]) * (X - c[0]) + (a[0] - c[0]) * (Y - c[1])) / d
        m = (l1 >= 0) & (l2 >= 0) & (1 - l1 - l2 >= 0)
        if m.any():
            zc = l1[m] * a[2] + l2[m] * b[2] + (1 - l1[m] - l2[m]) * c[2]
            res[m] ^= zs[None, :] > zc[:, None]
    return res.reshape(len(xs), len(ys), len(zs))


def label(out, h, frame, files):
    import nibabel as nib
    surfs = [load(files[i], files[i + 1], frame) for i in range(0, len(files), 2)]
    lo = surfs[0][0].min(0) - 2 * h
    hi = surfs[0][0].max(0) + 2 * h
    n = np.ceil((hi - lo) / h).astype(int) + 1
    xs, ys, zs = (lo[c] + h * np.arange(n[c]) for c in range(3))
    lab = np.zeros((n[0], n[1], n[2]), np.uint8)
    outer = None
    for v, (P, F) in enumerate(surfs, 1):
        m = inside(P, F, xs, ys, zs)
        outer = m if outer is None else outer
        lab[m & outer] = v
    aff = np.diag([h, h, h, 1.0])
    aff[:3, 3] = lo
    nib.save(nib.Nifti1Image(lab, aff), out)


def ptri(P, a, b, c):
    ab, ac = b - a, c - a
    ap, bp, cp = P - a, P - b, P - c
    d1, d2, d3, d4, d5, d6 = ap @ ab, ap @ ac, bp @ ab, bp @ ac, cp @ ab, cp @ ac
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    den = va + vb + vc
    den = np.where(den == 0, 1e-300, den)
    Q = a + np.outer(vb / den, ab) + np.outer(vc / den, ac)
    safe = lambda x: np.where(x == 0, 1, x)
    m = (vc <= 0) & (d1 >= 0) & (d3 <= 0)
    Q[m] = a + np.outer((d1 / safe(d1 - d3))[m], ab)
    m = (vb <= 0) & (d2 >= 0) & (d6 <= 0)
    Q[m] = a + np.outer((d2 / safe(d2 - d6))[m], ac)
    m = (va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0)
    Q[m] = b + np.outer(((d4 - d3) / safe((d4 - d3) + (d5 - d6)))[m], c - b)
    Q[(d1 <= 0) & (d2 <= 0)] = a
    Q[(d3 >= 0) & (d4 <= d3)] = b
    Q[(d6 >= 0) & (d5 <= d6)] = c
    return np.linalg.norm(P - Q, axis=1)


def dist(contours, step, frame, specs):
    pts, z, cur = {}, None, None
    for line in open(contours):
        w = line.split("#")[0].split()
        if not w:
            continue
        if w[0] == "layer":
            z = float(w[1])
        elif w[0] == "loop":
            cur = w[1]
        elif len(w) == 2 and cur:
            pts.setdefault(cur, []).append((float(w[0]), float(w[1]), z))
    worst = 0.0
    for spec in specs:
        name, files = spec.split("=")
        V, F = load(*files.split(","), frame)
        P = np.array(pts[name])[::step]
        d = np.full(len(P), np.inf)
        for f in F:
            d = np.minimum(d, ptri(P, V[f[0]], V[f[1]], V[f[2]]))
        print(f"{name}: {len(P)} contour nodes: distance to the original surface max {d.max():.3f} mm, "
              f"mean {d.mean():.3f}, 99% {np.percentile(d, 99):.3f}")
        worst = max(worst, d.max())
    print(f"worst {worst:.3f}")


def ptri_rows(P, a, b, c):
    """ptri with one triangle per point (a, b, c: arrays of the points' shape)."""
    dot = lambda u, v: (u * v).sum(1)
    ab, ac = b - a, c - a
    ap, bp, cp = P - a, P - b, P - c
    d1, d2, d3, d4, d5, d6 = dot(ap, ab), dot(ap, ac), dot(bp, ab), dot(bp, ac), dot(cp, ab), dot(cp, ac)
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    den = va + vb + vc
    den = np.where(den == 0, 1e-300, den)
    Q = a + (vb / den)[:, None] * ab + (vc / den)[:, None] * ac
    safe = lambda x: np.where(x == 0, 1, x)
    m = (vc <= 0) & (d1 >= 0) & (d3 <= 0)
    Q[m] = (a + (d1 / safe(d1 - d3))[:, None] * ab)[m]
    m = (vb <= 0) & (d2 >= 0) & (d6 <= 0)
    Q[m] = (a + (d2 / safe(d2 - d6))[:, None] * ac)[m]
    m = (va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0)
    Q[m] = (b + ((d4 - d3) / safe((d4 - d3) + (d5 - d6)))[:, None] * (c - b))[m]
    m = (d1 <= 0) & (d2 <= 0)
    Q[m] = a[m]
    m = (d3 >= 0) & (d4 <= d3)
    Q[m] = b[m]
    m = (d6 >= 0) & (d5 <= d6)
    Q[m] = c[m]
    return np.linalg.norm(P - Q, axis=1)


def mdist(model, frame, specs):
    """The distance to the nearest of the K triangles whose centroids are nearest: an upper bound of the
    exact distance (equal to it wherever the nearest triangle is among them), so a bound it meets holds."""
    from scipy.spatial import cKDTree
    worst = 0.0
    for spec in specs:
        name, files = spec.split("=")
        V, F = load(*files.split(","), frame)
        P = np.loadtxt(f"{model}/{name}.pts")
        K = min(96, len(F))
        _, near = cKDTree(V[F].mean(1)).query(P, k=K)
        near = near.reshape(len(P), K)
        d = np.full(len(P), np.inf)
        for j in range(K):
            f = F[near[:, j]]
            d = np.minimum(d, ptri_rows(P, V[f[:, 0]], V[f[:, 1]], V[f[:, 2]]))
        print(f"{name}: {len(P)} surface nodes of the rebuilt model: distance to the original surface max "
              f"{d.max():.3f} mm, mean {d.mean():.3f}, 99% {np.percentile(d, 99):.3f}")
        worst = max(worst, d.max())
    print(f"worst {worst:.3f}")


if __name__ == "__main__":
    a = sys.argv[1:]
    if a[0] == "label":
        label(a[1], float(a[2]), a[3], a[4:])
    elif a[0] == "mdist":
        mdist(a[1], a[2], a[3:])
    else:
        dist(a[1], int(a[2]), a[3], a[4:])
