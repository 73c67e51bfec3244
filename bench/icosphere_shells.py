#!/usr/bin/env python3
"""Icospheres of one level (10 4^level + 2 nodes) at the given radii, as NAME.pts / NAME.fac
(0-based, counterclockwise seen from outside) in the working directory:
icosphere_shells.py LEVEL R1 NAME1 [R2 NAME2 ...] (bench/dipoles_study.sh). The sphere is
tests/icospheres.py's icosphere(levels)."""
import os
import sys
import numpy as np
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests"))
from icospheres import icosphere  # noqa: E402

V, F = icosphere(int(sys.argv[1]))
args = sys.argv[2:]
for r, name in zip(args[0::2], args[1::2]):
    np.savetxt(name + ".pts", V * float(r), fmt="%.6f")
    np.savetxt(name + ".fac", np.array(F), fmt="%d")
