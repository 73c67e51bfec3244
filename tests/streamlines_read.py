#!/usr/bin/env python3
"""Reads a thorax streamline VTP with VTK (vtkXMLPolyDataReader) and checks it against the model:
every point inside the tetrahedron its `tet` point data names (barycentric coordinates >= -1e-9:
the last point of a "boundary" line lies on a face, to rounding), the arc length increasing to the
line's length, the stop reasons and directions in range, the potential the solution's frame
interpolated there (to 1e-9 of the largest) — and prints what the lines do (with --heart: where the
lines from the heart's surface end).

usage: streamlines_read.py FILE.vtp MODEL SOLUTION FRAME [--heart REGION] [--expect-lines N]
"""
import sys
import numpy as np
import vtk
from vtk.util.numpy_support import vtk_to_numpy

args = sys.argv[1:]
path, model, sol, frame = args[0], args[1], args[2], int(args[3])
heart = args[args.index("--heart") + 1] if "--heart" in args else None
expect = int(args[args.index("--expect-lines") + 1]) if "--expect-lines" in args else None

r = vtk.vtkXMLPolyDataReader()
r.SetFileName(path)
r.Update()
pd = r.GetOutput()
n_lines = pd.GetNumberOfLines()
assert pd.GetNumberOfPoints() > 0 and n_lines > 0, "no lines read"
if expect is not None:
    assert n_lines == expect, (n_lines, expect)
P = vtk_to_numpy(pd.GetPoints().GetData()).astype(float)
pdat, cdat = pd.GetPointData(), pd.GetCellData()
cur = vtk_to_numpy(pdat.GetArray("current_magnitude"))
pot = vtk_to_numpy(pdat.GetArray("potential"))
arc = vtk_to_numpy(pdat.GetArray("arc_length"))
tet = vtk_to_numpy(pdat.GetArray("tet")).astype(int)
stop = vtk_to_numpy(cdat.GetArray("stop_reason"))
direc = vtk_to_numpy(cdat.GetArray("direction"))
length = vtk_to_numpy(cdat.GetArray("length"))
offs = vtk_to_numpy(pd.GetLines().GetOffsetsArray()).astype(int)
conn = vtk_to_numpy(pd.GetLines().GetConnectivityArray()).astype(int)
assert np.array_equal(conn, np.arange(len(P))), "lines are not consecutive runs of points"
assert set(np.unique(stop)) <= {0, 1, 2, 3, 4} and set(np.unique(direc)) <= {-1, 1}

xyz = np.loadtxt(f"{model}/volume.pts")
T = np.loadtxt(f"{model}/volume.tet", dtype=np.int64)
reg = T[:, 4]
T = T[:, :4] - 1
import json
names = {r["id"]: r["name"] for r in json.load(open(f"{model}/model.json"))["regions"]}
# the frame's potentials (thorax's raw series: 'THXSER01', rows, frames, 200-byte header, times, values)
b = open(f"{sol}/volume.raw", "rb").read()
assert b[:8] == b"THXSER01"
rows, frames = np.frombuffer(b[8:24], dtype="<u8")
vals = np.frombuffer(b[200:], dtype="<f8")[frames:].reshape(frames, rows).T
phi = vals[:, frame - 1]

A = xyz[T[tet]]                                  # the point's tetrahedron's corners
M = np.stack([A[:, 1] - A[:, 0], A[:, 2] - A[:, 0], A[:, 3] - A[:, 0]], axis=2)
lam123 = np.linalg.solve(M, (P - A[:, 0])[:, :, None])[:, :, 0]
lam = np.column_stack([1 - lam123.sum(1), lam123])
worst = lam.min(1)
assert worst.min() > -1e-9, ("a point outside its tetrahedron", worst.min(), int(np.argmin(worst)))
# the potential there: linear interpolation of the frame's values
phi_i = (lam * phi[T[tet]]).sum(1)
scale = np.abs(phi).max()
assert np.abs(phi_i - pot).max() <= 1e-9 * scale, ("potential", np.abs(phi_i - pot).max())
# the points' tetrahedra are in the domain (no current in the heart of an epicardial solution)
if heart:
    assert not np.any(np.array([names[x] for x in reg[tet]]) == heart), "a point in the heart"

ends = {"boundary": 0, "low_current": 0, "max_length": 0, "max_steps": 0, "loop": 0}
names_stop = list(ends)
ret_heart = 0
for l in range(n_lines):
    a, e = offs[l], offs[l + 1]
    assert np.all(np.diff(arc[a:e]) >= -1e-9), "arc length decreasing"
    assert abs(arc[e - 1] - length[l]) < 1e-6 * max(1, length[l]), ("length", l, arc[e - 1], length[l])
    ends[names_stop[stop[l]]] += 1
print(f"{path}: {n_lines} lines, {len(P)} points read by vtkXMLPolyDataReader; every point inside its tetrahedron "
      f"(min barycentric {worst.min():.2e}); potential = the frame's interpolated (max diff {np.abs(phi_i - pot).max():.2e})")
print("  stops:", ", ".join(f"{k} {v}" for k, v in ends.items()))
print(f"  length (mm): median {np.median(length):.1f}, max {length.max():.1f}; |J| along the lines {cur.min():.3g} .. {cur.max():.3g}")

if heart:
    # where the forward lines from the heart's surface end: back on the heart (a current loop through the torso) or
    # on the torso's surface (the outer boundary)
    hnodes = np.unique(T[np.array([names[x] for x in reg]) == heart])
    from scipy.spatial import cKDTree
    kd = cKDTree(xyz[hnodes])
    back = far = 0
    reach, lens = [], []
    for l in range(n_lines):
        a, e = offs[l], offs[l + 1]
        if stop[l] != 0 or length[l] < 5:  # the other direction of a seed: straight into the heart
            continue
        d_end = kd.query(P[e - 1])[0]
        reach.append(kd.query(P[a:e])[0].max())
        lens.append(length[l])
        if d_end < 5:
            back += 1
        else:
            far += 1
    reach = np.array(reach)
    print(f"  lines longer than 5 mm that leave the domain: {back} end back on the heart's surface (current loops out "
          f"of the heart, through the torso and back), {far} on the torso's surface; their length median "
          f"{np.median(lens):.1f} mm; farthest from the heart: median {np.median(reach):.1f} mm, max {reach.max():.1f} mm")
    assert back > 0, "no line returns to the heart"
