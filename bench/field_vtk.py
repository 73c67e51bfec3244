#!/usr/bin/python3
"""bench/field.sh's VTK side: vtkContour3DLinearGrid (and vtkContourFilter) on the same volume and
potentials (a thorax export --solution ... --format vtu file), the same values, timed in memory
(the filter's Update alone, best of REPEATS), with triangle counts and areas.

usage: field_vtk.py VOLUME.vtu VALUES REPEATS      (VALUES: comma-separated numbers)
"""
import sys, time
import numpy as np
import vtk
from vtk.util.numpy_support import vtk_to_numpy as v2n

path, values, reps = sys.argv[1], [float(x) for x in sys.argv[2].split(",")], int(sys.argv[3])
r = vtk.vtkXMLUnstructuredGridReader()
r.SetFileName(path)
r.Update()
ug = r.GetOutput()
ug.GetPointData().SetActiveScalars("potential")


def areas(pd):
    pts = v2n(pd.GetPoints().GetData())
    c = v2n(pd.GetPolys().GetConnectivityArray()).reshape(-1, 3)
    s = v2n(pd.GetPointData().GetArray("potential"))
    out = []
    vals = np.array(values)
    near = np.abs(s[c].mean(axis=1)[:, None] - vals[None, :]).argmin(axis=1)  # scalars may be float32
    for k, v in enumerate(values):
        t = c[near == k]
        a, b, d = pts[t[:, 0]], pts[t[:, 1]], pts[t[:, 2]]
        out.append((len(t), 0.5 * np.linalg.norm(np.cross(b - a, d - a), axis=1).sum()))
    return out


for name, make in (("vtkContour3DLinearGrid", vtk.vtkContour3DLinearGrid), ("vtkContourFilter", vtk.vtkContourFilter)):
    best, out = float("inf"), None
    for _ in range(reps):
        f = make()
        f.SetInputData(ug)
        f.SetInputArrayToProcess(0, 0, 0, vtk.vtkDataObject.FIELD_ASSOCIATION_POINTS, "potential")
        if name == "vtkContour3DLinearGrid":
            f.SetMergePoints(True)
            f.SetInterpolateAttributes(True)
            f.SetComputeScalars(True)
        for k, v in enumerate(values):
            f.SetValue(k, v)
        t0 = time.perf_counter()
        f.Update()
        best = min(best, time.perf_counter() - t0)
        out = f.GetOutput()
    n = out.GetNumberOfPolys()
    print("vtk %s: %d values: best of %d %.4f s, %d triangles, %d points" % (name, len(values), reps, best, n,
                                                                           out.GetNumberOfPoints()))
    if name == "vtkContour3DLinearGrid":
        for v, (nt, a) in zip(values, areas(out)):
            print("vtk value %.17g: %d triangles, area %.15g mm^2" % (v, nt, a))
