#!/usr/bin/env python3
"""RDM and |1 - MAG| per column between a thorax series (text, rows x frames) and a reference
matrix (rows x columns, whitespace text), as OpenMEEG's compare_matrix computes them (its
tests/test_compare_matrix.cpp): each column minus its mean, then RDM = || u/|u| - v/|v| || and
MAG = |u| / |v|. Usage: dipole_compare.py SERIES.txt REFERENCE.txt [SCALE [COLUMNS]]
(SCALE multiplies the reference; COLUMNS like 1-5, 1-based). Prints `column rdm mag1` lines."""
import sys
import numpy as np


def read_series(path):
    L = open(path).read().split("\n")
    assert L[0].startswith("thorax-series"), path + ": not a thorax text series"
    rows = frames = None
    k = 1
    while True:
        w = L[k].split()
        if w and w[0] == "rows": rows = int(w[1])
        if w and w[0] == "frames": frames = int(w[1])
        k += 1
        try:
            float(L[k].split()[0]); break
        except (ValueError, IndexError):
            continue
    v = np.array([[float(x) for x in l.split()] for l in L[k:k + rows]])
    assert v.shape == (rows, frames), (path, v.shape, rows, frames)
    return v


def rdm_mag(u, v):
    u = u - u.mean(); v = v - v.mean()
    return np.linalg.norm(u / np.linalg.norm(u) - v / np.linalg.norm(v)), abs(1 - np.linalg.norm(u) / np.linalg.norm(v))


if __name__ == "__main__":
    u = read_series(sys.argv[1])
    ref = np.loadtxt(sys.argv[2]) * (float(sys.argv[3]) if len(sys.argv) > 3 else 1.0)
    cols = range(1, u.shape[1] + 1)
    if len(sys.argv) > 4:
        a, b = sys.argv[4].split("-"); cols = range(int(a), int(b) + 1)
    for c in cols:
        r, m = rdm_mag(u[:, c - 1], ref[:, c - 1])
        print(c, "%.4e" % r, "%.4e" % m)
