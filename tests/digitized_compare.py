#!/usr/bin/python3
"""How far the rebuilt layer nodes of a surface lie from the digitized polygons they came from.

usage: digitized_compare.py CONTOURS.txt SURFACE MODEL/SURFACE.pts MODEL/SURFACE.fac [--max MM]
                            [--ref REF.pts REF.fac --ref-max MM]
For every node on a layer loop (a node of a triangle that joins two layers: the nodes away from
the caps; cap nodes, at the surface's ends and where a loop starts or ends mid-surface, are left
out, and so are the nodes the build put on a straight in-plane edge, see split_nodes), the 2D distance to the nearest edge of that surface's digitized loops on the node's layer,
and with --ref the 3D distance to the reference (true) triangulated surface. Prints max / mean /
p99; exits 1 when a max exceeds --max / --ref-max.
"""
import os
import sys
import numpy as np

sys.dont_write_bytecode = True  # nothing written into the source tree
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from surface_compare_lib import point_surface_distance  # noqa: E402


def loops(path, surf):
    out, z, cur, scale = {}, None, None, 1.0
    for line in open(path):
        f = line.split("#")[0].split()
        if not f:
            continue
        if f[0] == "units":
            scale = {"mm": 1.0, "cm": 10.0, "m": 1000.0}[f[1]]
        elif f[0] == "layer":
            z, cur = float(f[1]) * scale, None
        elif f[0] == "loop":
            cur = [] if f[1] == surf else None
            if cur is not None:
                out.setdefault(z, []).append(cur)
        elif cur is not None and len(f) == 2 and f[0][0] in "+-.0123456789":
            cur.append((float(f[0]) * scale, float(f[1]) * scale))
    return out


def split_nodes(p, f):
    """Nodes the build put on a straight in-plane edge: a long chord of a pocket cut in its plane split in
    pieces (step 3b, src/geom/inplane.c), two crossing chords split where they cross (step 3c,
    src/geom/inplane_resolve.c). No loop's node, so left out. Such a node lies strictly between two of
    its neighbours in its plane on a straight line (to the precision of the .pts file), and has at least three neighbours there (the grid
    nodes of the region cut, the other chord's pieces). A loop's node on a straight run (the tank's flat
    sides) with another neighbour in its plane is left out too; a displaced straight run would still show
    at its ends."""
    nb = {}
    for t in f:
        for k in range(3):
            a, b = int(t[k]), int(t[(k + 1) % 3])
            if p[a, 2] == p[b, 2]:
                nb.setdefault(a, set()).add(b)
                nb.setdefault(b, set()).add(a)
    out = []
    for x, ns in nb.items():
        if len(ns) < 3:
            continue
        ns = sorted(ns)
        through = False
        for i in range(len(ns)):
            for j in range(i + 1, len(ns)):
                u, v = p[ns[i], :2] - p[x, :2], p[ns[j], :2] - p[x, :2]
                scale = np.linalg.norm(u) * np.linalg.norm(v)
                through |= bool(scale > 0 and abs(u[0] * v[1] - u[1] * v[0]) < 1e-6 * scale and u @ v < 0)
        if through:
            out.append(x)
    return np.array(out, dtype=np.int64)


def main():
    a = sys.argv[1:]
    L = loops(a[0], a[1])
    p = np.loadtxt(a[2], ndmin=2)
    f = np.loadtxt(a[3], dtype=np.int64, ndmin=2) - 1
    zt = p[f, 2]
    joins = (zt.max(axis=1) - zt.min(axis=1)) > 0
    on = np.zeros(len(p), bool)
    on[f[joins].ravel()] = True
    on[split_nodes(p, f)] = False
    zs = np.array(sorted(L))
    d = np.full(len(p), np.nan)
    for z in zs:
        m = on & (np.abs(p[:, 2] - z) < 1e-6 * max(1.0, abs(z)))
        if not m.any():
            continue
        P = p[m, :2]
        segs = np.concatenate([np.stack([np.array(lp), np.roll(np.array(lp), -1, axis=0)], axis=1) for lp in L[z]])
        best = np.full(len(P), np.inf)
        for k in range(0, len(segs), 256):  # nodes x segments, in blocks
            s0, s1 = segs[k:k + 256, 0], segs[k:k + 256, 1]
            ab = s1 - s0
            t = np.clip(np.einsum('nsk,sk->ns', P[:, None, :] - s0[None], ab) / np.maximum((ab * ab).sum(1), 1e-300), 0, 1)
            q = s0[None] + t[..., None] * ab[None]
            best = np.minimum(best, np.linalg.norm(P[:, None, :] - q, axis=2).min(axis=1))
        d[m] = best
    d = d[~np.isnan(d)]
    bad = False
    print("layer nodes to the digitized polygon: max %.3f mean %.3f p99 %.3f mm (%d nodes)"
          % (d.max(), d.mean(), np.percentile(d, 99), len(d)))
    if "--max" in a and d.max() > float(a[a.index("--max") + 1]):
        bad = True
    if "--ref" in a:
        i = a.index("--ref")
        rp = np.loadtxt(a[i + 1], ndmin=2)
        rf = np.loadtxt(a[i + 2], dtype=np.int64, ndmin=2) - 1
        e = point_surface_distance(p[on], rp, rf)
        print("layer nodes to the true surface: max %.3f mean %.3f p99 %.3f mm (%d nodes)"
              % (e.max(), e.mean(), np.percentile(e, 99), len(e)))
        if "--ref-max" in a and e.max() > float(a[a.index("--ref-max") + 1]):
            bad = True
    sys.exit(1 if bad else 0)


main()
