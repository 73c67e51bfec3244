#!/usr/bin/env python3
"""Nested icospheres (radii 100, 80, 50 mm; 642 vertices each) as ico_out, ico_mid, ico_in .pts/.fac
in the working directory (tests/e2e_mesh_real.sh, bench/mesh.sh). `icosphere(levels)` gives the unit
sphere's vertices and 0-based triangles (outward, counterclockwise) to other tests (e2e_bounds)."""
import numpy as np


def icosphere(levels):
    """The icosahedron subdivided `levels` times, projected on the unit sphere: (V (n x 3), F list)."""
    t = (1 + 5 ** 0.5) / 2
    V = [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t], [0, -1, -t], [0, 1, -t], [t, 0, -1],
         [t, 0, 1], [-t, 0, -1], [-t, 0, 1]]
    F = [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4], [11, 10, 2], [10, 7, 6],
         [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10],
         [8, 6, 7], [9, 8, 1]]
    V = [np.array(v, float) / np.linalg.norm(v) for v in V]
    for _ in range(levels):
        mid = {}

        def m(a, b):
            k = (min(a, b), max(a, b))
            if k not in mid:
                p = V[a] + V[b]
                V.append(p / np.linalg.norm(p))
                mid[k] = len(V) - 1
            return mid[k]
        F = [f for a, b, c in F
             for f in ([a, m(a, b), m(c, a)], [b, m(b, c), m(a, b)], [c, m(c, a), m(b, c)], [m(a, b), m(b, c), m(c, a)])]
    return np.array(V), F


if __name__ == "__main__":
    V, F = icosphere(3)
    for name, r in (("ico_out", 100), ("ico_mid", 80), ("ico_in", 50)):
        np.savetxt(name + ".pts", V * r, fmt="%.6f")
        np.savetxt(name + ".fac", np.array(F), fmt="%d")
