#!/usr/bin/env python3
"""The VTK side of bench/field_streamlines.sh: vtkStreamTracer on the same volume, the same field (J
averaged to the nodes as thorax does: the volume-weighted mean of the tetrahedra's current_density
around each node, as point data), the same seeds (the first points of thorax's lines), the same step
(mm), maximum length and terminal |J|; RK2, RK4 and RK45 timed; then the distance of every tracer's
lines (thorax's and VTK's) from a reference (thorax RK4 with a tiny step) over their common arc length.

usage: field_streamlines_vtk.py VTU THORAX_DIR STEP_MM MAX_LENGTH MIN_CURRENT_FRACTION THREADS
THORAX_DIR holds rk2.vtp rk4.vtp rk45.vtp ref.vtp (thorax streamlines, --direction both, --no-loops)
and times.txt (label seconds lines).
"""
import sys
import time
import numpy as np
import vtk
from vtk.util.numpy_support import numpy_to_vtk, vtk_to_numpy
from scipy.spatial import cKDTree

vtu, tdir, step, max_len, min_cur, threads = sys.argv[1], sys.argv[2], float(sys.argv[3]), float(sys.argv[4]), \
    float(sys.argv[5]), int(sys.argv[6])
vtk.vtkSMPTools.Initialize(threads)

r = vtk.vtkXMLUnstructuredGridReader()
r.SetFileName(vtu)
r.Update()
ug = r.GetOutput()
xyz = vtk_to_numpy(ug.GetPoints().GetData()).astype(float)
conn = vtk_to_numpy(ug.GetCells().GetConnectivityArray()).reshape(-1, 4)
Jt = vtk_to_numpy(ug.GetCellData().GetArray("current_density")).astype(float)
A = xyz[conn]
vol = np.abs(np.einsum("ij,ij->i", np.cross(A[:, 1] - A[:, 0], A[:, 2] - A[:, 0]), A[:, 3] - A[:, 0])) / 6
Jn = np.zeros_like(xyz)
w = np.zeros(len(xyz))
for k in range(4):
    np.add.at(Jn, conn[:, k], Jt * vol[:, None])
    np.add.at(w, conn[:, k], vol)
Jn[w > 0] /= w[w > 0, None]
jmax = np.sqrt((Jn ** 2).sum(1)).max()
arr = numpy_to_vtk(Jn, deep=1)
arr.SetName("J")
ug.GetPointData().AddArray(arr)
ug.GetPointData().SetActiveVectors("J")


def read_lines(path):
    rd = vtk.vtkXMLPolyDataReader()
    rd.SetFileName(path)
    rd.Update()
    o = rd.GetOutput()
    P = vtk_to_numpy(o.GetPoints().GetData()).astype(float)
    off = vtk_to_numpy(o.GetLines().GetOffsetsArray()).astype(int)
    cd = o.GetCellData()
    seed = vtk_to_numpy(cd.GetArray("seed"))
    d = vtk_to_numpy(cd.GetArray("direction"))
    return {(int(seed[l]), int(d[l])): P[off[l]:off[l + 1]] for l in range(len(off) - 1)}


thx = {k: read_lines(f"{tdir}/{k}.vtp") for k in ("rk2", "rk4", "rk45", "ref")}
seeds = np.array([thx["ref"][(s, 1)][0] for s in sorted(s for s, d in thx["ref"] if d == 1)])
n_seeds = len(seeds)
src = vtk.vtkPolyData()
pts = vtk.vtkPoints()
pts.SetData(numpy_to_vtk(seeds, deep=1))
src.SetPoints(pts)

vtk_lines, vtk_time = {}, {}
for name, kind in (("rk2", 0), ("rk4", 1), ("rk45", 2)):
    st = vtk.vtkStreamTracer()
    st.SetInputData(ug)
    st.SetSourceData(src)
    st.SetInputArrayToProcess(0, 0, 0, 0, "J")
    st.SetIntegratorType(kind)
    st.SetIntegrationStepUnit(1)  # LENGTH_UNIT: mm
    st.SetInitialIntegrationStep(step)
    st.SetMinimumIntegrationStep(step / 20)
    st.SetMaximumIntegrationStep(step * 2.5)
    st.SetMaximumError(1e-6)
    st.SetMaximumPropagation(max_len)
    st.SetMaximumNumberOfSteps(10 ** 7)
    st.SetTerminalSpeed(min_cur * jmax)
    st.SetIntegrationDirectionToBoth()
    st.SetComputeVorticity(False)
    t0 = time.perf_counter()
    st.Update()
    vtk_time[name] = time.perf_counter() - t0
    o = st.GetOutput()
    P = vtk_to_numpy(o.GetPoints().GetData()).astype(float)
    sid = vtk_to_numpy(o.GetCellData().GetArray("SeedIds"))
    lines = {}
    ca = o.GetLines()
    off = vtk_to_numpy(ca.GetOffsetsArray()).astype(int)
    cc = vtk_to_numpy(ca.GetConnectivityArray()).astype(int)
    for l in range(len(off) - 1):
        q = P[cc[off[l]:off[l + 1]]]
        # VTK's two directions of a seed are two lines starting at the seed: forward is the one along J
        d = 1
        if len(q) > 1:
            j = Jn[0]  # decided below by matching thorax's forward line's second point
        lines.setdefault(int(sid[l]), []).append(q)
    vtk_lines[name] = lines
    vtk_time[name + "_points"] = o.GetNumberOfPoints()


def pair_vtk(lines, s):
    """VTK's lines of seed s as {+1: forward, -1: backward}: each matched to the thorax reference's direction by
    its second point."""
    out = {}
    for q in lines.get(s, []):
        if len(q) < 2:
            continue
        best = None
        for d in (1, -1):
            ref = thx["ref"].get((s, d))
            if ref is None or len(ref) < 2:
                continue
            u, v = q[1] - q[0], ref[min(len(ref) - 1, 3)] - ref[0]
            c = np.dot(u, v) / (np.linalg.norm(u) * np.linalg.norm(v) + 1e-300)
            if best is None or c > best[0]:
                best = (c, d)
        if best:
            out[best[1]] = q
    return out


def arclen(q):
    return np.concatenate([[0], np.cumsum(np.linalg.norm(np.diff(q, axis=0), axis=1))])


def resample(q, ds):
    s = arclen(q)
    if s[-1] <= 0:
        return q[:1]
    t = np.arange(0, s[-1], ds)
    return np.column_stack([np.interp(t, s, q[:, c]) for c in range(3)])


def dist(q, ref, common):
    """the largest distance from the points of q within `common` mm of arc, the last END mm left out, to the
    polyline ref. Near the end a line grazes the boundary (J is tangent to the torso's surface), where the point
    it leaves by is ill-conditioned: a hundredth of a millimetre across the line moves it millimetres along."""
    s = arclen(q)
    q = q[s <= common - END]
    rr = resample(ref[arclen(ref) <= common + 5], 0.02)
    return cKDTree(rr).query(q)[0].max() if len(q) else 0.0


def errors(get):
    """median and 95th percentile over lines of the largest distance to the reference (first 100 mm)"""
    e = []
    for (s, d), ref in thx["ref"].items():
        q = get(s, d)
        if q is None or len(q) < 2 or len(ref) < 2:
            continue
        common = min(arclen(q)[-1], arclen(ref)[-1], 100.0)
        if common < END + 1:
            continue
        e.append(dist(q, ref, common))
    e = np.array(e)
    return np.median(e), np.percentile(e, 95), len(e)


END = 2.0
times = {}
for line in open(f"{tdir}/times.txt"):
    k, v, *rest = line.split()
    times[k] = (float(v), rest)
print(f"{n_seeds} seeds, both directions, step {step} mm, max length {max_len} mm, terminal |J| {min_cur} x max; "
      f"VTK {vtk.vtkVersion.GetVTKVersion()} on {threads} thread(s)")
print(f"accuracy: per line the largest distance (mm) from the reference over the first 100 mm of arc both lines have, "
      f"the last {END:g} mm before a line's end left out; median and 95th percentile over the lines (count)")
print("%-6s %12s %12s %8s | %-28s %-28s | %s" % ("", "thorax s", "VTK s", "VTK/thx", "thorax vs ref: median, p95 mm",
                                              "VTK vs ref: median, p95 mm", "thorax vs VTK: median, p95 mm"))
for name in ("rk2", "rk4", "rk45"):
    vl = {s: pair_vtk(vtk_lines[name], s) for s in range(n_seeds)}
    et = errors(lambda s, d: thx[name].get((s, d)))
    ev = errors(lambda s, d: vl[s].get(d))
    # the two tracers against each other
    e = []
    for (s, d), q in thx[name].items():
        w_ = vl[s].get(d)
        if w_ is None or len(q) < 2 or len(w_) < 2:
            continue
        common = min(arclen(q)[-1], arclen(w_)[-1], 100.0)
        if common >= END + 1:
            e.append(dist(q, w_, common))
    e = np.array(e)
    tt = times[name][0]
    print("%-6s %12.3f %12.3f %8.2f | %10.2e %10.2e (%d) | %10.2e %10.2e (%d) | %10.2e %10.2e (%d)" %
          (name, tt, vtk_time[name], vtk_time[name] / tt, et[0], et[1], et[2], ev[0], ev[1], ev[2],
           np.median(e), np.percentile(e, 95), len(e)))
    print("       thorax points %s; VTK points %d" % (" ".join(times[name][1]), vtk_time[name + "_points"]))
