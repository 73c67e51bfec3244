#!/usr/bin/python3
"""Reads thorax's exported surfaces with VTK's own readers and checks them.

usage: vtk_read.py DIR NAME N_POINTS N_CELLS PTS_FILE

Opens DIR/NAME.{vtk,vtp,stl,ply,obj} with vtkPolyDataReader,
vtkXMLPolyDataReader, vtkSTLReader, vtkPLYReader and vtkOBJReader and checks
the point and cell counts against N_POINTS and N_CELLS (STL stores triangles
only: its reader merges duplicate points, so only the cell count is checked,
and the point count must not exceed N_POINTS). For .vtk and .vtp the bounds
must equal those of PTS_FILE (x y z per line), and every cell must be a
triangle. Run with /usr/bin/python3 (Debian's python3-vtk9). Exits non-zero on
any mismatch and prints each check.
"""
import sys

import vtk


def pts_bounds(path):
    lo = [float("inf")] * 3
    hi = [float("-inf")] * 3
    with open(path) as f:
        for line in f:
            w = line.split()
            if not w:
                continue
            for k in range(3):
                v = float(w[k])
                lo[k] = min(lo[k], v)
                hi[k] = max(hi[k], v)
    return (lo[0], hi[0], lo[1], hi[1], lo[2], hi[2])


def main():
    if len(sys.argv) != 6:
        print(__doc__, file=sys.stderr)
        return 2
    d, name, n_pts, n_cells, pts = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), sys.argv[5]
    want_bounds = pts_bounds(pts)
    failures = 0

    def check(what, ok, detail):
        nonlocal failures
        print("%-4s %s: %s" % ("ok" if ok else "FAIL", what, detail))
        if not ok:
            failures += 1

    readers = [
        ("vtk", vtk.vtkPolyDataReader),
        ("vtp", vtk.vtkXMLPolyDataReader),
        ("stl", vtk.vtkSTLReader),
        ("ply", vtk.vtkPLYReader),
        ("obj", vtk.vtkOBJReader),
    ]
    for ext, cls in readers:
        path = "%s/%s.%s" % (d, name, ext)
        r = cls()
        r.SetFileName(path)
        r.Update()
        out = r.GetOutput()
        np_, nc = out.GetNumberOfPoints(), out.GetNumberOfCells()
        if ext == "stl":
            check(path + " cells", nc == n_cells, "%d triangles, expected %d" % (nc, n_cells))
            check(path + " points (merged)", 0 < np_ <= n_pts, "%d points, at most %d" % (np_, n_pts))
        else:
            check(path + " points", np_ == n_pts, "%d, expected %d" % (np_, n_pts))
            check(path + " cells", nc == n_cells, "%d, expected %d" % (nc, n_cells))
        tri = all(out.GetCell(i).GetNumberOfPoints() == 3 for i in range(nc))
        check(path + " triangles", nc > 0 and tri, "no cells" if nc == 0 else "every cell has 3 points" if tri else "a cell is not a triangle")
        if ext in ("vtk", "vtp"):
            b = out.GetBounds()
            ok = all(abs(b[k] - want_bounds[k]) <= 1e-9 * max(1.0, abs(want_bounds[k])) for k in range(6))
            check(path + " bounds", ok, "%s vs %s" % (tuple(round(v, 6) for v in b), want_bounds))
    print("%d check(s) failed" % failures if failures else "all checks passed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
