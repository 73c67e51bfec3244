#!/usr/bin/env python3
"""Quality of a tetrahedral mesh, measured the same way for every program (bench/mesh.sh):
smallest dihedral angle, share below 5 and 10 degrees, largest and mean radius-edge ratio.
Usage: tet_quality.py thorax MODEL_DIR | tetgen PREFIX   (PREFIX.node / PREFIX.ele)
Prints one line: tets min_dihedral below5 below10 max_radius_edge mean_radius_edge."""
import sys
import numpy as np

def load(kind, path):
    if kind == "thorax":
        P = np.loadtxt(path + "/volume.pts", ndmin=2)
        T = np.loadtxt(path + "/volume.tet", dtype=np.int64, ndmin=2)[:, :4] - 1
    else:
        with open(path + ".node") as f:
            n = int(f.readline().split()[0])
        P = np.loadtxt(path + ".node", skiprows=1, max_rows=n, ndmin=2)[:, 1:4]
        with open(path + ".ele") as f:
            m = int(f.readline().split()[0])
        E = np.loadtxt(path + ".ele", skiprows=1, max_rows=m, dtype=np.int64, ndmin=2)
        T = E[:, 1:5] - 1
    return P, T

def quality(P, T):
    a = P[T]
    fv = [(1, 2, 3), (0, 3, 2), (0, 1, 3), (0, 2, 1)]
    N = []
    for f, (x, y, z) in enumerate(fv):
        v = np.cross(a[:, y] - a[:, x], a[:, z] - a[:, x])
        v /= np.linalg.norm(v, axis=1)[:, None]
        s = np.sign(np.einsum("ij,ij->i", v, a[:, f] - a[:, x]))
        N.append(v * -s[:, None])
    dmin = np.full(len(T), 180.0)
    for i in range(4):
        for j in range(i + 1, 4):
            c = np.clip(np.einsum("ij,ij->i", N[i], N[j]), -1, 1)
            dmin = np.minimum(dmin, 180 - np.degrees(np.arccos(c)))
    u, v, w = a[:, 1] - a[:, 0], a[:, 2] - a[:, 0], a[:, 3] - a[:, 0]
    det = 2 * np.einsum("ij,ij->i", u, np.cross(v, w))
    num = (np.einsum("ij,ij->i", u, u)[:, None] * np.cross(v, w) + np.einsum("ij,ij->i", v, v)[:, None] * np.cross(w, u)
           + np.einsum("ij,ij->i", w, w)[:, None] * np.cross(u, v))
    r = np.linalg.norm(num / det[:, None], axis=1)
    e = np.min(np.stack([np.linalg.norm(a[:, i] - a[:, j], axis=1) for i in range(4) for j in range(i + 1, 4)]), axis=0)
    re = r / e
    return len(T), dmin.min(), int((dmin < 5).sum()), int((dmin < 10).sum()), re.max(), re.mean()

if __name__ == "__main__":
    n, dm, b5, b10, remax, remean = quality(*load(sys.argv[1], sys.argv[2]))
    print("%d %.2f %d %d %.2f %.3f" % (n, dm, b5, b10, remax, remean))
