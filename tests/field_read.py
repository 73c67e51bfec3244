#!/usr/bin/python3
"""Reads a `thorax field` .vtp back with VTK and checks it against VTK's own filters on the same
volume (`thorax export --solution --format vtu`): e2e_field.sh.

usage: field_read.py OURS.vtp VOLUME.vtu [PLANE ...]   (PLANE as --slice: x=MM or PX,PY,PZ:NX,NY,NZ,
in --slice order)

Checks, per equipotential surface (cell data iso_value):
  - every vertex's potential is the value (exactly) and the volume's interpolated potential there
    (barycentric in the tetrahedron the triangle names) is the value to 1e-9 of the range;
  - no edge is used by more than two triangles, none twice the same way (consistent orientation);
    every edge used once (the surface's border) lies on the volume's boundary surface;
  - the area equals that of vtkContour3DLinearGrid's surface at the same value to 1e-6 relative;
per slice (cell data plane): the area equals vtkCutter's, the potentials the volume's probed;
contour lines: their points' potential is contour_value; current_magnitude = |current_density| of
the volume's tetrahedron (cell data tetrahedron).
"""
import sys
import numpy as np
import vtk
from vtk.util.numpy_support import vtk_to_numpy as v2n, numpy_to_vtk as n2v


def tri_area(pts, tris):
    a, b, c = pts[tris[:, 0]], pts[tris[:, 1]], pts[tris[:, 2]]
    return 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1).sum()


def polys_of(pd):
    """triangles of a vtkPolyData (all cells triangles) as an n x 3 array"""
    tf = vtk.vtkTriangleFilter()
    tf.SetInputData(pd)
    tf.Update()
    o = tf.GetOutput()
    c = v2n(o.GetPolys().GetConnectivityArray()) if o.GetNumberOfPolys() else np.zeros(0, int)
    return v2n(o.GetPoints().GetData()) if o.GetNumberOfPoints() else np.zeros((0, 3)), c.reshape(-1, 3)


def plane_of(spec):
    if spec[0] in "xyz" and spec[1] == "=":
        n = np.zeros(3)
        n["xyz".index(spec[0])] = 1
        p = n * float(spec[2:])
        return p, n
    a, b = spec.split(":")
    return np.array([float(x) for x in a.split(",")]), np.array([float(x) for x in b.split(",")])


def main():
    ours, vol = sys.argv[1], sys.argv[2]
    planes = [plane_of(s) for s in sys.argv[3:]]
    r = vtk.vtkXMLPolyDataReader()
    r.SetFileName(ours)
    r.Update()
    pd = r.GetOutput()
    assert pd.GetNumberOfPoints() > 0, "no points read"
    pts = v2n(pd.GetPoints().GetData())
    pot = v2n(pd.GetPointData().GetArray("potential"))
    cd = pd.GetCellData()
    nl, npoly = pd.GetNumberOfLines(), pd.GetNumberOfPolys()
    polys = v2n(pd.GetPolys().GetConnectivityArray()).reshape(-1, 3)
    iso = v2n(cd.GetArray("iso_value"))[nl:]
    plane = v2n(cd.GetArray("plane"))[nl:]
    tet = v2n(cd.GetArray("tetrahedron"))
    jmag = v2n(cd.GetArray("current_magnitude"))
    assert len(polys) == npoly and len(iso) == npoly

    vr = vtk.vtkXMLUnstructuredGridReader()
    vr.SetFileName(vol)
    vr.Update()
    ug = vr.GetOutput()
    ug.GetPointData().SetActiveScalars("potential")
    vpot = v2n(ug.GetPointData().GetArray("potential"))
    rng = vpot.max() - vpot.min()
    # |J| of the tetrahedron
    jd = v2n(ug.GetCellData().GetArray("current_density"))
    jerr = np.abs(np.linalg.norm(jd[tet], axis=1) - jmag).max() if len(tet) else 0
    assert jerr <= 1e-12 * max(1e-300, np.abs(jmag).max()), "current_magnitude differs from |current_density|: %g" % jerr
    # the volume's boundary surface, for the surfaces' borders
    gf = vtk.vtkGeometryFilter()
    gf.SetInputData(ug)
    gf.Update()
    loc = vtk.vtkCellLocator()
    loc.SetDataSet(gf.GetOutput())
    loc.BuildLocator()
    scale = np.abs(v2n(ug.GetPoints().GetData())).max()

    vxyz = v2n(ug.GetPoints().GetData())
    vtet = v2n(ug.GetCells().GetConnectivityArray()).reshape(-1, 4)

    def interp(p, t):
        """the volume's piecewise-linear potential at points p inside tetrahedra t (barycentric)"""
        q = vxyz[vtet[t]]
        m = np.stack([q[:, 1] - q[:, 0], q[:, 2] - q[:, 0], q[:, 3] - q[:, 0]], axis=2)
        l = np.linalg.solve(m, (p - q[:, 0])[:, :, None])[:, :, 0]
        w = np.column_stack([1 - l.sum(axis=1), l])
        inside = w.min() >= -1e-9
        return (w * vpot[vtet[t]]).sum(axis=1), inside

    nchk = 0
    for v in sorted(set(iso[~np.isnan(iso)])):
        sel = polys[iso == v]
        used = np.unique(sel)
        assert len(sel), "iso %g: no triangle" % v
        assert np.all(pot[used] == v), "iso %g: a vertex potential is not the value" % v
        tt = np.repeat(tet[nl:][iso == v], 3)
        pv, inside = interp(pts[sel.ravel()], tt)
        assert inside, "iso %g: a vertex outside its tetrahedron" % v
        perr = np.abs(pv - v).max()
        assert perr <= 1e-9 * rng, "iso %g: the volume's potential at the vertices is off by %g" % (v, perr)
        # edges
        e = np.concatenate([sel[:, [0, 1]], sel[:, [1, 2]], sel[:, [2, 0]]])
        key = np.sort(e, axis=1)
        uk, inv, cnt = np.unique(key, axis=0, return_inverse=True, return_counts=True)
        inv = inv.ravel()
        assert cnt.max() <= 2, "iso %g: an edge in %d triangles" % (v, cnt.max())
        fw = (e[:, 0] < e[:, 1]).astype(int)
        s = np.zeros(len(uk), int)
        np.add.at(s, inv, fw)
        assert np.all(s[cnt == 2] == 1), "iso %g: triangles of opposite orientation meet" % v
        border = uk[cnt == 1]
        worst = 0.0
        for a, b in border:
            m = 0.5 * (pts[a] + pts[b])
            cp = [0.0, 0.0, 0.0]
            cid, sid, d2 = vtk.reference(0), vtk.reference(0), vtk.reference(0.0)
            loc.FindClosestPoint(m, cp, cid, sid, d2)
            worst = max(worst, float(d2) ** 0.5)
        assert worst <= 1e-9 * scale, "iso %g: a border edge %g mm from the volume's boundary" % (v, worst)
        # VTK's own isosurface
        cf = vtk.vtkContour3DLinearGrid()
        cf.SetInputData(ug)
        cf.SetInputArrayToProcess(0, 0, 0, vtk.vtkDataObject.FIELD_ASSOCIATION_POINTS, "potential")
        cf.SetValue(0, v)
        cf.SetMergePoints(True)
        cf.Update()
        vp, vt = polys_of(cf.GetOutput())
        a_ours, a_vtk = tri_area(pts, sel), tri_area(vp, vt)
        assert abs(a_ours - a_vtk) <= 1e-6 * a_vtk, "iso %g: area %.10g, VTK's %.10g" % (v, a_ours, a_vtk)
        print("ok iso %-12.6g %7d triangles (VTK %7d) area %.10g (VTK %.10g, rel %.1e) border edges %d (on the boundary, "
              "%.1e mm)" % (v, len(sel), len(vt), a_ours, a_vtk, abs(a_ours - a_vtk) / a_vtk, len(border), worst))
        nchk += 1
    for k, (p0, n) in enumerate(planes):
        sel = polys[plane == k + 1]
        assert len(sel), "plane %d: no triangle" % (k + 1)
        pl = vtk.vtkPlane()
        pl.SetOrigin(*p0)
        pl.SetNormal(*n)
        cu = vtk.vtkCutter()
        cu.SetInputData(ug)
        cu.SetCutFunction(pl)
        cu.Update()
        vp, vt = polys_of(cu.GetOutput())
        a_ours, a_vtk = tri_area(pts, sel), tri_area(vp, vt)
        assert abs(a_ours - a_vtk) <= 1e-6 * a_vtk, "plane %d: area %.10g, VTK's %.10g" % (k + 1, a_ours, a_vtk)
        pv, inside = interp(pts[sel.ravel()], np.repeat(tet[nl:][plane == k + 1], 3))
        assert inside, "plane %d: a vertex outside its tetrahedron" % (k + 1)
        perr = np.abs(pv - pot[sel.ravel()]).max()
        assert perr <= 1e-9 * rng, "plane %d: potentials off by %g" % (k + 1, perr)
        print("ok plane %d: %d triangles area %.10g (vtkCutter %.10g), potentials within %.1e of the volume's" %
              (k + 1, len(sel), a_ours, a_vtk, perr))
        nchk += 1
    if nl:
        cv = v2n(cd.GetArray("contour_value"))[:nl]
        lines = v2n(pd.GetLines().GetConnectivityArray()).reshape(-1, 2)
        err = np.abs(pot[lines] - cv[:, None]).max()
        assert err == 0, "contour points' potential differs from contour_value by %g" % err
        pv, inside = interp(pts[lines.ravel()], np.repeat(tet[:nl], 2))
        assert inside, "contours: a point outside its tetrahedron"
        perr = np.abs(pv - pot[lines.ravel()]).max()
        assert perr <= 1e-9 * rng, "contours: the volume's potential off by %g" % perr
        print("ok %d contour segments, on their values (volume within %.1e)" % (nl, perr))
    assert nchk > 0, "nothing checked"
    print("ok %s: %d points, %d triangles, %d lines" % (ours, len(pts), npoly, nl))


main()
