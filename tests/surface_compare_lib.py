"""Point-to-triangle distance (Ericson), shared by the surface comparisons of the tests."""
import numpy as np


def _pairs(P, a, b, c):
    """Distance from each point P[i] to triangle (a[i], b[i], c[i]) (Ericson's region tests; a, b, c
    may also be single vertices, broadcast over P)."""
    ab, ac = b - a, c - a
    dot = lambda u, v: np.einsum('...k,...k->...', u, v)
    ap, bp, cp = P - a, P - b, P - c
    d1, d2 = dot(ap, ab), dot(ap, ac)
    d3, d4 = dot(bp, ab), dot(bp, ac)
    d5, d6 = dot(cp, ab), dot(cp, ac)
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2
    denom = va + vb + vc
    with np.errstate(divide='ignore', invalid='ignore'):
        v = vb / denom
        w = vc / denom
    Q = a + v[:, None] * ab + w[:, None] * ac  # interior
    Q = np.array(np.broadcast_to(Q, P.shape))
    full = lambda x: np.broadcast_to(x, P.shape)
    a, b, c, ab, ac = full(a), full(b), full(c), full(ab), full(ac)
    # vertex and edge regions
    m = (d1 <= 0) & (d2 <= 0); Q[m] = a[m]
    m = (d3 >= 0) & (d4 <= d3); Q[m] = b[m]
    m = (d6 >= 0) & (d5 <= d6); Q[m] = c[m]
    m = (vc <= 0) & (d1 >= 0) & (d3 <= 0)
    t = np.where(m, d1 / np.where(d1 - d3 == 0, 1, d1 - d3), 0); Q[m] = a[m] + t[m, None] * ab[m]
    m = (vb <= 0) & (d2 >= 0) & (d6 <= 0)
    t = np.where(m, d2 / np.where(d2 - d6 == 0, 1, d2 - d6), 0); Q[m] = a[m] + t[m, None] * ac[m]
    m = (va <= 0) & ((d4 - d3) >= 0) & ((d5 - d6) >= 0)
    t = np.where(m, (d4 - d3) / np.where((d4 - d3) + (d5 - d6) == 0, 1, (d4 - d3) + (d5 - d6)), 0)
    Q[m] = b[m] + t[m, None] * (c[m] - b[m])
    return np.linalg.norm(P - Q, axis=1)


def point_triangle_distance(P, a, b, c):
    """Distance from the points P (n x 3) to triangle abc."""
    return _pairs(P, a, b, c)


def point_surface_distance(P, V, F, block=512):
    """Distance from each point P (n x 3) to the nearest triangle of the surface (V, F), exact.

    Each triangle's bounding sphere (centroid, farthest corner) gives a lower bound on a point's
    distance to it; the exact distance to the 8 triangles of least bound gives an upper bound, and
    only the triangles whose lower bound is within it are measured: the nearest triangle is always
    among them, so the minimum is the one over all triangles, at a fraction of the pairs."""
    A, B, C = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    cen = (A + B + C) / 3.0
    rad = np.sqrt(np.max([((X - cen) ** 2).sum(1) for X in (A, B, C)], axis=0))
    k = min(8, len(F))
    out = np.empty(len(P))
    for s in range(0, len(P), block):
        Q = P[s:s + block]
        lb = np.sqrt(((Q[:, None, :] - cen[None]) ** 2).sum(2)) - rad[None]  # n x T
        near = np.argpartition(lb, k - 1, axis=1)[:, :k]
        rows = np.repeat(np.arange(len(Q)), k)
        tri = near.ravel()
        ub = _pairs(Q[rows], A[tri], B[tri], C[tri]).reshape(len(Q), k).min(1)
        pi, ti = np.nonzero(lb <= ub[:, None])
        d = _pairs(Q[pi], A[ti], B[ti], C[ti])
        best = np.full(len(Q), np.inf)
        np.minimum.at(best, pi, d)
        out[s:s + block] = np.minimum(best, ub)
    return out
