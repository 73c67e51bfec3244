#!/usr/bin/env python3
"""Conformity of a thorax volume mesh to its model's surfaces, judged from the files alone and
independently of the mesher (numpy/scipy; no thorax code):

- the interface faces (on the mesh's boundary, or between two tetrahedra of different regions)
  each lie on one surface triangle: all three corners within TOL of its plane and inside it;
- per surface triangle, the areas of the interface faces on it add up to its own area
  (relative 1e-6): every triangle is covered, exactly;
- every original surface node is a volume node (the .vmap tables), within 1e-6 mm;
- each region's volume equals the volume its surfaces enclose: the region of tetrahedra whose
  centroid lies inside surface S and inside no surface nested in S is V(S) - sum V(children),
  the region outside every inner surface V(outer) - sum V(its children) (relative 1e-6).

Usage: conformity.py MODEL_DIR   Prints a summary; exits 1 on any failure."""
import json
import os
import sys

import itertools
import numpy as np
from scipy.spatial import cKDTree

TOL = 1e-5  # mm: node coordinates are on a 2^-20 mm grid, surfaces are written with 6 decimals


def load_model(d):
    m = json.load(open(os.path.join(d, "model.json")))
    surfs = []
    for s in m["surfaces"]:
        P = np.loadtxt(os.path.join(d, s["pts"]), ndmin=2)
        F = np.loadtxt(os.path.join(d, s["fac"]), dtype=np.int64, ndmin=2)
        if F.min() == 1 and F.max() == len(P):
            F = F - 1
        vm = np.loadtxt(os.path.join(d, s["vmap"]), dtype=np.int64, ndmin=1) - 1
        surfs.append((s["name"], P, F, vm))
    X = np.loadtxt(os.path.join(d, m["volume"]["pts"]), ndmin=2)
    TR = np.loadtxt(os.path.join(d, m["volume"]["tet"]), dtype=np.int64, ndmin=2)
    regions = [r["name"] for r in m["regions"]]
    return surfs, X, TR[:, :4] - 1, TR[:, 4] - 1, regions


def tri_area(A, B, C):
    return 0.5 * np.linalg.norm(np.cross(B - A, C - A), axis=-1)


def interface_faces(T, reg):
    f = np.concatenate([T[:, [1, 2, 3]], T[:, [0, 2, 3]], T[:, [0, 1, 3]], T[:, [0, 1, 2]]])
    owner = np.tile(np.arange(len(T)), 4)
    key = np.sort(f, axis=1)
    order = np.lexsort(key.T[::-1])
    key, owner = key[order], owner[order]
    same = np.all(key[1:] == key[:-1], axis=1)
    keep = np.ones(len(key), bool)
    pair_first = np.where(same)[0]
    # interior faces: pairs; interface when the regions differ
    interface_pair = reg[owner[pair_first]] != reg[owner[pair_first + 1]]
    keep[pair_first] = interface_pair
    keep[pair_first + 1] = False
    return key[keep]


def inside(P, F, q):
    """Solid angle sum (winding number) of points q w.r.t. the closed surface (P, F)."""
    w = np.zeros(len(q))
    A, B, C = P[F[:, 0]], P[F[:, 1]], P[F[:, 2]]
    for i in range(0, len(q), 2000):
        a = A[None] - q[i:i + 2000, None]
        b = B[None] - q[i:i + 2000, None]
        c = C[None] - q[i:i + 2000, None]
        la, lb, lc = (np.linalg.norm(x, axis=2) for x in (a, b, c))
        num = np.einsum("ijk,ijk->ij", a, np.cross(b, c))
        den = la * lb * lc + np.einsum("ijk,ijk->ij", a, b) * lc + np.einsum("ijk,ijk->ij", b, c) * la + np.einsum("ijk,ijk->ij", c, a) * lb
        w[i:i + 2000] = (2 * np.arctan2(num, den)).sum(axis=1)
    return w > 2 * np.pi


def volume(P, F):
    A, B, C = P[F[:, 0]], P[F[:, 1]], P[F[:, 2]]
    return np.einsum("ij,ij->i", A, np.cross(B, C)).sum() / 6


def main(d):
    surfs, X, T, reg, regions = load_model(d)
    errors = []
    # surface nodes are volume nodes
    for name, P, F, vm in surfs:
        dmax = np.abs(X[vm] - P).max()
        if dmax > 1e-6:
            errors.append("%s: a surface node is %.3g mm from its volume node" % (name, dmax))
    faces = interface_faces(T, reg)
    fa, fb, fc = X[faces[:, 0]], X[faces[:, 1]], X[faces[:, 2]]
    fcen = (fa + fb + fc) / 3
    farea = tri_area(fa, fb, fc)
    # candidate triangles by centroid distance, then the exact-enough test
    allA, allB, allC, owner_s, owner_t = [], [], [], [], []
    for si, (name, P, F, vm) in enumerate(surfs):
        allA.append(P[F[:, 0]]); allB.append(P[F[:, 1]]); allC.append(P[F[:, 2]])
        owner_s.append(np.full(len(F), si)); owner_t.append(np.arange(len(F)))
    A, B, C = np.concatenate(allA), np.concatenate(allB), np.concatenate(allC)
    os_, ot = np.concatenate(owner_s), np.concatenate(owner_t)
    tcen = (A + B + C) / 3
    trad = np.max(np.stack([np.linalg.norm(A - tcen, axis=1), np.linalg.norm(B - tcen, axis=1),
                            np.linalg.norm(C - tcen, axis=1)]), axis=0)
    nrm = np.cross(B - A, C - A)
    nrm /= np.linalg.norm(nrm, axis=1)[:, None]
    # every (face, triangle) pair within reach: the face's centroid within the triangle's own radius
    # of its centroid (each triangle's ball searched among the face centroids: a search with the
    # largest radius for every face made 50 times as many pairs on the phantom), ordered by face,
    # then triangle; tested in chunks (vectorized); each face goes to the first triangle of its list
    # that holds it (in its plane, its centroid inside)
    cand = cKDTree(fcen).query_ball_point(tcen, r=trad + TOL)
    lens = np.fromiter(map(len, cand), dtype=np.int64, count=len(cand))
    J = np.repeat(np.arange(len(cand)), lens)
    I = np.fromiter(itertools.chain.from_iterable(cand), dtype=np.int64, count=int(lens.sum()))
    order = np.lexsort((J, I))
    I, J = I[order], J[order]
    ok = np.zeros(len(I), dtype=bool)
    for lo in range(0, len(I), 1 << 20):
        i, j = I[lo:lo + (1 << 20)], J[lo:lo + (1 << 20)]
        near = np.linalg.norm(fcen[i] - tcen[j], axis=1) <= trad[j] + TOL
        dev = np.maximum.reduce([np.abs(np.einsum("ij,ij->i", q[i] - A[j], nrm[j])) for q in (fa, fb, fc)])
        v0, v1, v2 = B[j] - A[j], C[j] - A[j], fcen[i] - A[j]
        d00, d01, d11 = (np.einsum("ij,ij->i", x, y) for x, y in ((v0, v0), (v0, v1), (v1, v1)))
        d20, d21 = np.einsum("ij,ij->i", v2, v0), np.einsum("ij,ij->i", v2, v1)
        den = d00 * d11 - d01 * d01
        su, tv = (d11 * d20 - d01 * d21) / den, (d00 * d21 - d01 * d20) / den
        ok[lo:lo + len(i)] = near & (dev <= TOL) & (su >= -1e-9) & (tv >= -1e-9) & (su + tv <= 1 + 1e-9)
    fi, first = np.unique(I[ok], return_index=True)
    covered = np.zeros(len(A))
    np.add.at(covered, J[ok][first], farea[fi])
    off = len(fcen) - len(fi)
    tarea = tri_area(A, B, C)
    rel = np.abs(covered - tarea) / tarea
    bad = np.where(rel > 1e-6)[0]
    if off:
        errors.append("%d interface faces lie on no surface triangle" % off)
    if len(bad):
        j = bad[0]
        errors.append("%d surface triangles not covered (first: %s triangle %d, %.3g of its area)" %
                      (len(bad), surfs[os_[j]][0], ot[j] + 1, covered[j] / tarea[j]))
    print("%d interface faces; %d of %d surface triangles covered (100%% = %s)" %
          (len(faces), len(A) - len(bad), len(A), "yes" if len(bad) == 0 else "no"))
    # region volumes against the nesting of the surfaces
    vols = [abs(volume(P, F)) for _, P, F, _ in surfs]
    # parent of each surface: the smallest other surface containing one of its nodes
    parent = []
    for si, (name, P, F, vm) in enumerate(surfs):
        best, bv = -1, np.inf
        for sj, (n2, P2, F2, _) in enumerate(surfs):
            if sj != si and vols[sj] > vols[si] and vols[sj] < bv and inside(P2, F2, P[:1])[0]:
                best, bv = sj, vols[sj]
        parent.append(best)
    cell_volume = [vols[s] - sum(vols[c] for c in range(len(surfs)) if parent[c] == s) for s in range(len(surfs))]
    tv = np.abs(np.einsum("ij,ij->i", X[T[:, 1]] - X[T[:, 0]], np.cross(X[T[:, 2]] - X[T[:, 0]], X[T[:, 3]] - X[T[:, 0]]))) / 6
    cen = X[T].mean(axis=1)
    # the cell of each region: the innermost surface containing its first tetrahedron's centroid
    for r, rname in enumerate(regions):
        idx = np.where(reg == r)[0]
        if len(idx) == 0:
            continue
        c = cen[idx[:1]]
        cell, cv = -1, np.inf
        for s, (name, P, F, _) in enumerate(surfs):
            if vols[s] < cv and inside(P, F, c)[0]:
                cell, cv = s, vols[s]
        rv = tv[idx].sum()
        want = cell_volume[cell]
        d_rel = (rv - want) / want
        print("  region %-12s %8d tetrahedra, %.6g mm^3, inside %s: expected %.6g (%+.2e)" %
              (rname, len(idx), rv, surfs[cell][0], want, d_rel))
        if abs(d_rel) > 1e-6:
            errors.append("region %s: volume %+.3g relative to its surfaces'" % (rname, d_rel))
    for e in errors:
        print("FAIL:", e)
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
