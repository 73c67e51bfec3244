#!/usr/bin/python3
"""Peer run for bench/surfaces.sh: VTK builds surfaces from the same contours.

Reads a thorax contour file (docs/formats.md) and, per surface, runs VTK's two
contour-to-surface methods on its loops:
  - vtkRuledSurfaceFilter: laces each pair of adjacent loops (resampled to the
    same node spacing, 'PointWalk' mode) -- the lacing step alone, no caps, no
    concave handling, no orientation;
  - vtkVoxelContoursToSurfaceFilter: scan-converts the loops into a voxel grid
    and extracts a closed surface (its own resampling; the standard VTK route).
Prints wall time, nodes and triangles of each, for comparison with thorax.
"""
import sys, time
import vtk

def read_contours(path):
    surf, order, z, cur = {}, [], None, None
    for line in open(path):
        line = line.split('#')[0].strip()
        if not line: continue
        t = line.split()
        if t[0] == 'surface': surf[t[1]] = []; order.append(t[1])
        elif t[0] == 'layer': z = float(t[1])
        elif t[0] == 'loop': cur = []; surf[t[1]].append((z, cur))
        elif t[0] in ('thorax-contours', 'units', 'spacing', 'end'): cur = None
        elif cur is not None: cur.append((float(t[0]), float(t[1])))
    return order, surf

def polydata(loops, scale=1.0, zindex=False, dz=1.0, z0=0.0, polys=False):
    pts, lines = vtk.vtkPoints(), vtk.vtkCellArray()
    for z, loop in loops:
        ids = []
        zz = round((z - z0) / dz) if zindex else z
        for x, y in loop:
            ids.append(pts.InsertNextPoint(x * scale, y * scale, zz))
        lines.InsertNextCell(len(ids) + (0 if polys else 1))
        closing = [] if polys else [ids[0]]
        for i in ids + closing: lines.InsertCellPoint(i)
    pd = vtk.vtkPolyData(); pd.SetPoints(pts)
    if polys: pd.SetPolys(lines)
    else: pd.SetLines(lines)
    return pd

def main():
    path, spacing = sys.argv[1], float(sys.argv[2])
    order, surf = read_contours(path)
    tot = {'ruled': [0.0, 0, 0], 'voxel': [0.0, 0, 0]}
    for name in order:
        loops = surf[name]
        pd = polydata(loops)
        t0 = time.perf_counter()
        ruled = vtk.vtkRuledSurfaceFilter()
        ruled.SetInputData(pd)
        ruled.SetRuledModeToPointWalk()
        ruled.SetResolution(1, 1)
        ruled.SetOnRatio(1)
        ruled.CloseSurfaceOn()
        ruled.Update()
        t1 = time.perf_counter()
        out = ruled.GetOutput()
        tot['ruled'][0] += t1 - t0; tot['ruled'][1] += out.GetNumberOfPoints(); tot['ruled'][2] += out.GetNumberOfPolys()
        t0 = time.perf_counter()
        # this filter wants the contours on the integer planes z = 0, 1, 2 ...; x, y are scaled
        # alike, so its voxels are one layer gap wide
        zs = sorted(set(z for z, _ in loops))
        dz = zs[1] - zs[0] if len(zs) > 1 else 1.0
        vox = vtk.vtkVoxelContoursToSurfaceFilter()
        vox.SetInputData(polydata(loops, 1.0 / dz, True, dz, zs[0], polys=True))
        vox.SetMemoryLimitInBytes(1 << 30)
        vox.Update()
        t1 = time.perf_counter()
        # the filter works in units of the slice spacing; it outputs in its voxel frame
        out = vox.GetOutput()
        tot['voxel'][0] += t1 - t0; tot['voxel'][1] += out.GetNumberOfPoints(); tot['voxel'][2] += out.GetNumberOfPolys()
    for k, label in (('ruled', 'VTK vtkRuledSurfaceFilter (lacing only)'), ('voxel', 'VTK vtkVoxelContoursToSurfaceFilter')):
        t, n, p = tot[k]
        print("peer  %-42s %8.3f s  %8d nodes  %8d polygons" % (label, t, n, p))

main()
