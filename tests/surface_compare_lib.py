"""Point-to-triangle distance (Ericson), shared by the surface comparisons of the tests."""
import numpy as np


def point_triangle_distance(P, a, b, c):
    """Distance from the points P (n x 3) to triangle abc (Ericson's region tests, vectorized)."""
    ab, ac, ap = b - a, c - a, P - a
    d1, d2 = ap @ ab, ap @ ac
    bp = P - b
    d3, d4 = bp @ ab, bp @ ac
    cp = P - c
    d5, d6 = cp @ ab, cp @ ac
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2
    denom = va + vb + vc
    with np.errstate(divide='ignore', invalid='ignore'):
        v = vb / denom
        w = vc / denom
    Q = a + np.outer(v, ab) + np.outer(w, ac)  # interior
    # vertex and edge regions
    m = (d1 <= 0) & (d2 <= 0); Q[m] = a
    m = (d3 >= 0) & (d4 <= d3); Q[m] = b
    m = (d6 >= 0) & (d5 <= d6); Q[m] = c
    m = (vc <= 0) & (d1 >= 0) & (d3 <= 0)
    t = np.where(m, d1 / np.where(d1 - d3 == 0, 1, d1 - d3), 0); Q[m] = a + np.outer(t[m], ab)
    m = (vb <= 0) & (d2 >= 0) & (d6 <= 0)
    t = np.where(m, d2 / np.where(d2 - d6 == 0, 1, d2 - d6), 0); Q[m] = a + np.outer(t[m], ac)
    m = (va <= 0) & ((d4 - d3) >= 0) & ((d5 - d6) >= 0)
    t = np.where(m, (d4 - d3) / np.where((d4 - d3) + (d5 - d6) == 0, 1, (d4 - d3) + (d5 - d6)), 0)
    Q[m] = b + np.outer(t[m], c - b)
    return np.linalg.norm(P - Q, axis=1)
