#!/usr/bin/python3
"""Reads thorax's volume exports with VTK and Gmsh and checks them against
the model directory they came from.

usage: volume_read.py MODEL_DIR VTU_FILE MSH_FILE

MODEL_DIR holds volume.pts (x y z a line) and volume.tet ("a b c d region"
a line, 1-based) and model.json (its "regions": names and ids); they are
read here with plain Python, independently of thorax's reader.

VTU (vtkXMLUnstructuredGridReader, Debian's python3-vtk9): number of points
and cells, every cell a tetrahedron (VTK_TETRA = 10), connectivity equal to
volume.tet, points equal to volume.pts, cell array "region" (Int32) equal to
the region column (so its range is within 1..number of regions), point
arrays "surface" and "surface_node" present, and every tetrahedron
right-handed (positive signed volume from VTK's points).

MSH (Gmsh's Python API, Debian's python3-gmsh): the node count and tags
1..N, coordinates, one element type (4, the 4-node tetrahedron), element
tags 1..T with the nodes of volume.tet's lines, one physical group of
dimension 3 per region with the region's name and id, the elements of each
volume entity all of that entity's region, and every Jacobian determinant
positive (Gmsh's own verdict on orientation). If the gmsh module cannot be
imported, the gmsh command line converts the file (gmsh -0 FILE -o OUT
-format msh41) and the counts of the copy are compared instead. If neither
exists the check FAILS: Gmsh is a required test dependency (scripts/deps.sh).

Exits non-zero on any mismatch and prints each check.
"""
import json
import os
import shutil
import subprocess
import sys
import tempfile

failures = 0


def check(what, ok, detail=""):
    global failures
    print("%-4s %s%s" % ("ok" if ok else "FAIL", what, (": " + detail) if detail else ""))
    if not ok:
        failures += 1


def read_model(d):
    pts = []
    with open(os.path.join(d, "volume.pts")) as f:
        for line in f:
            w = line.split()
            if w:
                pts.append(tuple(float(x) for x in w))
    tets, regs = [], []
    with open(os.path.join(d, "volume.tet")) as f:
        for line in f:
            w = line.split()
            if w:
                tets.append(tuple(int(x) for x in w[:4]))
                regs.append(int(w[4]))
    with open(os.path.join(d, "model.json")) as f:
        regions = json.load(f)["regions"]
    return pts, tets, regs, regions


def signed_volume(p0, p1, p2, p3):
    a = [p1[k] - p0[k] for k in range(3)]
    b = [p2[k] - p0[k] for k in range(3)]
    c = [p3[k] - p0[k] for k in range(3)]
    cross = (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])
    return (cross[0] * c[0] + cross[1] * c[1] + cross[2] * c[2]) / 6.0


def check_vtu(path, pts, tets, regs, n_regions):
    import vtk

    r = vtk.vtkXMLUnstructuredGridReader()
    r.SetFileName(path)
    r.Update()
    g = r.GetOutput()
    np_, nc = g.GetNumberOfPoints(), g.GetNumberOfCells()
    check(path + " points", np_ == len(pts), "%d, expected %d" % (np_, len(pts)))
    check(path + " cells", nc == len(tets), "%d, expected %d" % (nc, len(tets)))
    if np_ != len(pts) or nc != len(tets):
        return
    types = {g.GetCellType(i) for i in range(nc)}
    check(path + " all cells tetra", types == {vtk.VTK_TETRA}, "cell types %s" % sorted(types))
    worst = max(max(abs(a - b) for a, b in zip(g.GetPoint(i), pts[i])) for i in range(np_))
    check(path + " points equal volume.pts", worst == 0.0, "largest difference %g" % worst)
    conn_ok, right = True, 0
    for i in range(nc):
        ids = g.GetCell(i).GetPointIds()
        q = [ids.GetId(k) for k in range(ids.GetNumberOfIds())]
        if q != [t - 1 for t in tets[i]]:
            conn_ok = False
        if signed_volume(*(g.GetPoint(k) for k in q)) > 0:
            right += 1
    check(path + " connectivity equals volume.tet", conn_ok)
    check(path + " tetrahedra right-handed", right == nc, "%d of %d" % (right, nc))
    reg = g.GetCellData().GetArray("region")
    check(path + " cell data 'region'", reg is not None and reg.GetDataType() == vtk.VTK_INT)
    if reg is not None:
        lo, hi = reg.GetRange()
        check(path + " region range", 1 <= lo and hi <= n_regions, "%g..%g in 1..%d" % (lo, hi, n_regions))
        vals = [int(reg.GetValue(i)) for i in range(nc)]
        check(path + " region equals volume.tet's column", vals == regs)
    for name in ("surface", "surface_node"):
        a = g.GetPointData().GetArray(name)
        check(path + " point data '%s'" % name, a is not None and a.GetNumberOfTuples() == np_)


def check_msh_api(gmsh, path, pts, tets, regs, regions):
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.open(path)
        tags, coord, _ = gmsh.model.mesh.getNodes()
        tags = [int(t) for t in tags]
        check(path + " nodes", len(tags) == len(pts), "%d, expected %d" % (len(tags), len(pts)))
        check(path + " node tags 1..N", sorted(tags) == list(range(1, len(pts) + 1)))
        if len(tags) == len(pts):
            worst = max(max(abs(coord[3 * i + k] - pts[t - 1][k]) for k in range(3)) for i, t in enumerate(tags))
            check(path + " node coordinates equal volume.pts", worst == 0.0, "largest difference %g" % worst)
        etypes, etags, enodes = gmsh.model.mesh.getElements(3)
        check(path + " element types", list(etypes) == [4], "types %s (4 = tetrahedron)" % list(etypes))
        n_el = sum(len(t) for t in etags)
        check(path + " elements", n_el == len(tets), "%d, expected %d" % (n_el, len(tets)))
        if list(etypes) == [4]:
            conn = {}
            for t, k in zip(etags[0], range(len(etags[0]))):
                conn[int(t)] = tuple(int(x) for x in enodes[0][4 * k:4 * k + 4])
            check(path + " element tags 1..T", sorted(conn) == list(range(1, len(tets) + 1)))
            check(path + " elements equal volume.tet", all(conn.get(i + 1) == tets[i] for i in range(len(tets))))
            _, dets, _ = gmsh.model.mesh.getJacobians(4, [0.25, 0.25, 0.25])
            check(path + " Jacobians positive (Gmsh)", len(dets) == len(tets) and min(dets) > 0,
                  "smallest %g" % (min(dets) if len(dets) else float("nan")))
        groups = gmsh.model.getPhysicalGroups(3)
        want = [(3, r["id"]) for r in regions]
        check(path + " physical groups", sorted(groups) == want, "%s" % groups)
        names_ok = all(gmsh.model.getPhysicalName(3, r["id"]) == r["name"] for r in regions)
        check(path + " physical names", names_ok)
        ok = True
        for r in regions:
            ents = gmsh.model.getEntitiesForPhysicalGroup(3, r["id"])
            got = 0
            for e in ents:
                _, et, _ = gmsh.model.mesh.getElements(3, int(e))
                for block in et:
                    got += len(block)
                    ok &= all(regs[int(t) - 1] == r["id"] for t in block)
            want_n = regs.count(r["id"])
            check(path + " region %d (%s) elements" % (r["id"], r["name"]), got == want_n,
                  "%d, expected %d" % (got, want_n))
        check(path + " every element in its region's physical group", ok)
    finally:
        gmsh.finalize()


def check_msh_cli(path, pts, tets, regions):
    exe = shutil.which("gmsh")
    check("gmsh: python3-gmsh or the gmsh command", exe is not None,
          exe or "neither is installed (scripts/deps.sh installs gmsh and python3-gmsh)")
    if exe is None:
        return
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "copy.msh")
        p = subprocess.run([exe, "-0", path, "-o", out, "-format", "msh41"], capture_output=True, text=True)
        check(path + " read by the gmsh command", p.returncode == 0 and os.path.exists(out), p.stderr.strip()[-300:])
        if not os.path.exists(out):
            return
        with open(out) as f:
            lines = f.read().split("\n")

        def header(section):
            return [int(x) for x in lines[lines.index(section) + 1].split()]

        n_blocks, n_nodes = header("$Nodes")[:2]
        n_eblocks, n_el = header("$Elements")[:2]
        n_phys = header("$PhysicalNames")[0]
        check(path + " nodes (gmsh copy)", n_nodes == len(pts), "%d, expected %d" % (n_nodes, len(pts)))
        check(path + " elements (gmsh copy)", n_el == len(tets), "%d, expected %d" % (n_el, len(tets)))
        check(path + " physical names (gmsh copy)", n_phys == len(regions), "%d, expected %d" % (n_phys, len(regions)))


def main():
    if len(sys.argv) != 4:
        print(__doc__, file=sys.stderr)
        return 2
    model, vtu, msh = sys.argv[1:]
    pts, tets, regs, regions = read_model(model)
    check("model ids 1..R", [r["id"] for r in regions] == list(range(1, len(regions) + 1)))
    check_vtu(vtu, pts, tets, regs, len(regions))
    try:
        import gmsh
    except ImportError as e:
        print("note: python3-gmsh not importable (%s); using the gmsh command" % e)
        check_msh_cli(msh, pts, tets, regions)
    else:
        check_msh_api(gmsh, msh, pts, tets, regs, regions)
    print("%d check(s) failed" % failures if failures else "all checks passed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
