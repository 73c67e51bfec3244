#!/usr/bin/env python3
"""Icospheres of one level (10 4^level + 2 nodes) at the given radii, as NAME.pts / NAME.fac
(0-based, counterclockwise seen from outside) in the working directory:
icosphere_shells.py LEVEL R1 NAME1 [R2 NAME2 ...] (bench/dipoles_study.sh)."""
import sys
import numpy as np
t = (1 + 5 ** 0.5) / 2
V = [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t], [0, -1, -t], [0, 1, -t], [t, 0, -1], [t, 0, 1],
     [-t, 0, -1], [-t, 0, 1]]
F = [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4], [11, 10, 2], [10, 7, 6], [7, 1, 8],
     [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]]
V = [np.array(v, float) / np.linalg.norm(v) for v in V]
for _ in range(int(sys.argv[1])):
    mid = {}

    def m(a, b):
        k = (min(a, b), max(a, b))
        if k not in mid:
            p = V[a] + V[b]
            V.append(p / np.linalg.norm(p))
            mid[k] = len(V) - 1
        return mid[k]
    F = [f for a, b, c in F for f in ([a, m(a, b), m(c, a)], [b, m(b, c), m(a, b)], [c, m(c, a), m(b, c)], [m(a, b), m(b, c), m(c, a)])]
args = sys.argv[2:]
for r, name in zip(args[0::2], args[1::2]):
    np.savetxt(name + ".pts", np.array(V) * float(r), fmt="%.6f")
    np.savetxt(name + ".fac", np.array(F), fmt="%d")
