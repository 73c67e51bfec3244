#!/usr/bin/python3
"""Compares a rebuilt surface with a reference surface (both .pts/.fac, 1-based).

Prints the enclosed volumes and their relative difference, and the distance
from every rebuilt node to the reference surface (max, mean, 99th percentile).
Exits 1 if the volume differs by more than --vol (relative) or any node lies
farther than --dist mm (nodes within --cap-band mm of the lowest or highest
rebuilt layer, the flat end caps, are reported separately and bounded by
--cap-dist).
usage: surface_compare.py REF.pts REF.fac NEW.pts NEW.fac --vol V --dist D --cap-band B --cap-dist C
"""
import os
import sys
import numpy as np

# the point-to-triangle distance, shared with tests/digitized_compare.py
sys.dont_write_bytecode = True  # nothing written into the source tree
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from surface_compare_lib import point_surface_distance  # noqa: E402

def read(pts, fac):
    p = np.loadtxt(pts, ndmin=2)
    f = np.loadtxt(fac, dtype=np.int64, ndmin=2) - 1
    return p, f

def volume(p, f):
    a, b, c = p[f[:, 0]], p[f[:, 1]], p[f[:, 2]]
    return np.einsum('ij,ij->i', a, np.cross(b, c)).sum() / 6.0

def main():
    a = sys.argv[1:]
    opt = {a[i]: float(a[i + 1]) for i in range(4, len(a), 2)}
    rp, rf = read(a[0], a[1])
    npnt, nf = read(a[2], a[3])
    v0, v1 = volume(rp, rf), volume(npnt, nf)
    d = point_surface_distance(npnt, rp, rf)
    z = npnt[:, 2]
    cap = (z <= z.min() + opt['--cap-band']) | (z >= z.max() - opt['--cap-band'])
    side = ~cap
    print("volume: reference %.1f mm^3, rebuilt %.1f mm^3, difference %+.3f%%" % (v0, v1, 100 * (v1 - v0) / v0))
    print("node distance to the reference surface: sides max %.3f mean %.3f p99 %.3f mm (%d nodes); end layers max %.3f mm (%d nodes)"
          % (d[side].max(), d[side].mean(), np.percentile(d[side], 99), side.sum(), d[cap].max() if cap.any() else 0, cap.sum()))
    bad = abs(v1 - v0) / abs(v0) > opt['--vol'] or d[side].max() > opt['--dist'] or (cap.any() and d[cap].max() > opt['--cap-dist'])
    sys.exit(1 if bad else 0)

main()
