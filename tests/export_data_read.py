#!/usr/bin/python3
"""Reads thorax's exports with data back with VTK and Gmsh themselves and checks every value.

usage: export_data_read.py MODEL SERIES ROWS OUTDIR FORMAT [FRAMES] [DOMAIN]
       export_data_read.py --jobs FILE     (one such line of arguments a line: all in one process,
                                            each model read once; exit 1 if any job fails)

MODEL   the model directory (model.json, NAME.pts/.fac, volume.pts/.tet, NAME.vmap)
SERIES  the series that was exported: a thorax raw series (THXSER01); ROWS says whose nodes
        its rows are: "volume" or "surface:NAME"
OUTDIR  where `thorax export --format FORMAT` wrote (FORMAT vtu, vtp, vtk or msh)
FRAMES  the exported frames, 1-based, comma separated ("all" or absent: every frame)
DOMAIN  for vtu: "noheart" when the currents leave out a region named heart (a forward
        solution of the epicardial problem), else every region carries currents

Checks (each printed; exit 1 on any failure):
  vtu  the .pvd (parsed as XML: vtkPVDReader is ParaView's, not VTK's) lists one file per
       frame at the series' times; each file opened with vtkXMLUnstructuredGridReader has
       volume.pts's points and volume.tet's tetrahedra, "potential" = the series' column (1e-6
       relative), "current_density" = -sigma grad(phi) computed here with numpy from the
       points and model.json's conductivity tensors (1e-6 relative), "region", "conductivity",
       field data "region_name", "region_sigma", "surface_name", "TimeValue";
  vtp  per surface with data: the .pvd, vtkXMLPolyDataReader, NAME.pts's points, "potential"
       = the series (through NAME.vmap for a volume series), "TimeValue", "surface_name";
  vtk  the same with vtkPolyDataReader (legacy), without a .pvd;
  msh  gmsh.open: physical groups of dimension 2 named as the surfaces, whose triangles cover
       each surface's area and enclose its volume (so they are oriented outward), of dimension
       3 named as the regions holding volume.tet's tetrahedra per region; the views
       (gmsh.view.getModelData) hold one step per frame with the series' time and values.
"""
import json
import math
import os
import sys
import xml.etree.ElementTree as ET

import numpy as np

fails = 0


def check(what, ok, detail=""):
    global fails
    print("%-4s %s%s" % ("ok" if ok else "FAIL", what, (": " + detail) if detail else ""))
    if not ok:
        fails += 1


def raw_series(p):
    b = open(p, "rb").read()
    assert b[:8] == b"THXSER01", p + ": not a thorax raw series"
    r, f = (int(x) for x in np.frombuffer(b[8:24], dtype="<u8"))
    d = np.frombuffer(b[200:], dtype="<f8")
    return d[f:].reshape(f, r).T.copy(), d[:f].copy()  # rows x frames, times


def read_xyz(p):
    return np.loadtxt(p, ndmin=2)[:, :3]


def rel(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    scale = max(np.abs(b).max(), 1e-300)
    return np.abs(a - b).max() / scale


_models = {}


def load_model(d):
    if d not in _models:
        _models[d] = read_model(d)
    return _models[d]


def read_model(d):
    j = json.load(open(os.path.join(d, "model.json")))
    m = {"surf": [], "regions": [], "volume": None}
    for s in j["surfaces"]:
        e = {"name": s["name"], "xyz": read_xyz(os.path.join(d, s["pts"])),
             "tri": np.loadtxt(os.path.join(d, s["fac"]), dtype=np.int64, ndmin=2) - 1}
        if "vmap" in s:
            e["vmap"] = np.loadtxt(os.path.join(d, s["vmap"]), dtype=np.int64, ndmin=1) - 1
        m["surf"].append(e)
    for r in j.get("regions", []):
        sg = r["sigma"]
        sg = np.array(sg, float) if isinstance(sg, list) else sg * np.eye(3)
        m["regions"].append((r["id"], r["name"], sg))
    if "volume" in j:
        v = j["volume"]
        tet = np.loadtxt(os.path.join(d, v["tet"]), dtype=np.int64, ndmin=2)
        m["volume"] = {"xyz": read_xyz(os.path.join(d, v["pts"])), "tet": tet[:, :4] - 1, "region": tet[:, 4]}
    return m


def currents(m, phi, domain):
    """J = -1000 sigma grad(phi) per tetrahedron (phi in mV over mm gives mA/m^2)."""
    v = m["volume"]
    p = v["xyz"][v["tet"]]                      # T x 4 x 3
    D = p[:, 1:, :] - p[:, :1, :]               # rows: edges from node 0
    dphi = phi[v["tet"][:, 1:]] - phi[v["tet"][:, :1]]
    g = np.linalg.solve(D, dphi[:, :, None])[:, :, 0]
    sig = np.zeros((len(m["regions"]) + 1, 3, 3))
    for rid, name, s in m["regions"]:
        if not (domain == "noheart" and name == "heart"):
            sig[rid] = s
    return -1000.0 * np.einsum("tij,tj->ti", sig[v["region"]], g)


def pvd(outdir, stem, want_files, want_times):
    p = os.path.join(outdir, stem + ".pvd")
    if not os.path.exists(p):
        check(p, False, "missing")
        return
    root = ET.parse(p).getroot()
    ds = root.find("Collection").findall("DataSet")
    files = [e.get("file") for e in ds]
    times = np.array([float(e.get("timestep")) for e in ds])
    check(p + " files", files == want_files, "%d listed" % len(files))
    check(p + " times", len(times) == len(want_times) and np.array_equal(times, want_times),
          "%s .. %s" % (times[:1], times[-1:]))


def field(data, name):
    a = data.GetFieldData().GetAbstractArray(name)
    if a is None:
        return None
    if a.IsA("vtkStringArray"):
        return [a.GetValue(i) for i in range(a.GetNumberOfValues())]
    from vtk.util.numpy_support import vtk_to_numpy
    return vtk_to_numpy(a)


def arr(data, where, name):
    from vtk.util.numpy_support import vtk_to_numpy
    a = (data.GetPointData() if where == "point" else data.GetCellData()).GetArray(name)
    return None if a is None else vtk_to_numpy(a)


def main():
    if len(sys.argv) == 3 and sys.argv[1] == "--jobs":
        failed = []
        for line in open(sys.argv[2]):
            args = line.split()
            if not args:
                continue
            print("== " + " ".join(args))
            if job(args) != 0:
                failed.append(" ".join(args))
        for a in failed:
            print("FAIL job: " + a)
        print("%d of the jobs failed" % len(failed) if failed else "all jobs passed")
        return 1 if failed else 0
    return job(sys.argv[1:])


def job(argv):
    """One read-back (the arguments of the first usage line): 0 when every check passed."""
    global fails
    fails = 0
    if len(argv) < 5:
        print(__doc__, file=sys.stderr)
        return 2
    model_dir, series, rows, outdir, fmt = argv[:5]
    frames_arg = argv[5] if len(argv) > 5 else "all"
    domain = argv[6] if len(argv) > 6 else "all"
    m = load_model(model_dir)
    S, T = raw_series(series)
    frames = list(range(S.shape[1])) if frames_arg == "all" else [int(x) - 1 for x in frames_arg.split(",")]
    width = max(4, len(str(S.shape[1])))
    names = [s["name"] for s in m["surf"]]
    # the data per surface (rows of its nodes) and on the volume
    vol = S if rows == "volume" else None
    surfdata = {}
    for s in m["surf"]:
        if vol is not None:
            surfdata[s["name"]] = vol[s["vmap"]]
        elif rows == "surface:" + s["name"]:
            surfdata[s["name"]] = S
    check("series rows", (vol is not None and vol.shape[0] == m["volume"]["xyz"].shape[0]) or len(surfdata) == 1,
          "%d rows as %s" % (S.shape[0], rows))
    want_t = T[frames]

    if fmt == "vtu":
        import vtk
        v = m["volume"]
        files = ["volume_%0*d.vtu" % (width, f + 1) for f in frames]
        pvd(outdir, "volume", files, want_t)
        region_names = [r[1] for r in m["regions"]]
        sig = {r[0]: r[2] for r in m["regions"]}
        for k, f in enumerate(frames):
            p = os.path.join(outdir, files[k])
            r = vtk.vtkXMLUnstructuredGridReader()
            r.SetFileName(p)
            r.Update()
            g = r.GetOutput()
            from vtk.util.numpy_support import vtk_to_numpy
            check(p + " size", g.GetNumberOfPoints() == len(v["xyz"]) and g.GetNumberOfCells() == len(v["tet"]),
                  "%d points, %d cells" % (g.GetNumberOfPoints(), g.GetNumberOfCells()))
            if k == 0:
                pts = vtk_to_numpy(g.GetPoints().GetData())
                check(p + " points = volume.pts", np.abs(pts - v["xyz"]).max() <= 1e-9 * max(1, np.abs(v["xyz"]).max()))
                conn = vtk_to_numpy(g.GetCells().GetConnectivityArray()).reshape(-1, 4)
                check(p + " tetrahedra = volume.tet", np.array_equal(conn, v["tet"]))
                check(p + " region", np.array_equal(arr(g, "cell", "region"), v["region"]))
                cond = arr(g, "cell", "conductivity")
                want = np.array([np.trace(sig[r]) / 3 for r in v["region"]])
                check(p + " conductivity (S/m)", cond is not None and rel(cond, want) < 1e-12)
                check(p + " field region_name", field(g, "region_name") == region_names, str(field(g, "region_name")))
                rs = field(g, "region_sigma")
                check(p + " field region_sigma", rs is not None and rel(rs.reshape(-1, 3, 3),
                      np.array([r[2] for r in m["regions"]])) < 1e-12)
                check(p + " field surface_name", field(g, "surface_name") == names, str(field(g, "surface_name")))
            tv = field(g, "TimeValue")
            check(p + " TimeValue", tv is not None and float(tv[0]) == T[f], "%s vs %s" % (tv, T[f]))
            pot = arr(g, "point", "potential")
            check(p + " potential = series frame %d" % (f + 1), pot is not None and rel(pot, vol[:, f]) < 1e-6,
                  "rel %.2e" % (rel(pot, vol[:, f]) if pot is not None else -1))
            J = arr(g, "cell", "current_density")
            want = currents(m, vol[:, f], domain)
            check(p + " current_density = -sigma grad phi", J is not None and J.shape == want.shape and rel(J, want) < 1e-6,
                  "rel %.2e" % (rel(J, want) if J is not None and J.shape == want.shape else -1))

    elif fmt in ("vtp", "vtk"):
        import vtk
        for s in m["surf"]:
            if s["name"] not in surfdata:
                continue
            data = surfdata[s["name"]]
            files = ["%s_%0*d.%s" % (s["name"], width, f + 1, fmt) for f in frames]
            if fmt == "vtp":
                pvd(outdir, s["name"], files, want_t)
            for k, f in enumerate(frames):
                p = os.path.join(outdir, files[k])
                r = vtk.vtkXMLPolyDataReader() if fmt == "vtp" else vtk.vtkPolyDataReader()
                r.SetFileName(p)
                r.Update()
                g = r.GetOutput()
                from vtk.util.numpy_support import vtk_to_numpy
                ok = g.GetNumberOfPoints() == len(s["xyz"]) and g.GetNumberOfCells() == len(s["tri"])
                check(p + " size", ok, "%d points, %d cells" % (g.GetNumberOfPoints(), g.GetNumberOfCells()))
                if not ok:
                    continue
                if k == 0:
                    pts = vtk_to_numpy(g.GetPoints().GetData())
                    check(p + " points = %s.pts" % s["name"], np.abs(pts - s["xyz"]).max() <= 1e-9 * max(1, np.abs(s["xyz"]).max()))
                    conn = vtk_to_numpy(g.GetPolys().GetConnectivityArray()).reshape(-1, 3)
                    check(p + " triangles = %s.fac" % s["name"], np.array_equal(conn, s["tri"]))
                    check(p + " field surface_name", field(g, "surface_name") == names, str(field(g, "surface_name")))
                tv = field(g, "TimeValue")
                check(p + " TimeValue", tv is not None and float(tv[0]) == T[f], "%s vs %s" % (tv, T[f]))
                pot = arr(g, "point", "potential")
                check(p + " potential = series frame %d" % (f + 1), pot is not None and rel(pot, data[:, f]) < 1e-6,
                      "rel %.2e" % (rel(pot, data[:, f]) if pot is not None else -1))

    elif fmt == "msh":
        import gmsh
        v = m["volume"]
        p = os.path.join(outdir, "volume.msh")
        gmsh.initialize(["-noenv"])
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.open(p)
        groups = gmsh.model.getPhysicalGroups()
        named = {(d, gmsh.model.getPhysicalName(d, t)): t for d, t in groups}
        check(p + " physical surfaces", sorted(n for d, n in named if d == 2) == sorted(names),
              str(sorted(n for d, n in named if d == 2)))
        tags, coords, _ = gmsh.model.mesh.getNodes()
        X = np.zeros((int(tags.max()) + 1, 3))
        X[tags.astype(np.int64)] = coords.reshape(-1, 3)
        check(p + " nodes = volume.pts", len(tags) == len(v["xyz"]) and np.abs(X[1:] - v["xyz"]).max() < 1e-9 * max(1, np.abs(v["xyz"]).max()))
        for s in m["surf"]:
            t = named.get((2, s["name"]))
            if t is None:
                continue
            tri = []
            for e in gmsh.model.getEntitiesForPhysicalGroup(2, t):
                types, _, nodes = gmsh.model.mesh.getElements(2, e)
                for ty, nd in zip(types, nodes):
                    check(p + " %s: triangles only" % s["name"], ty == 2, "type %d" % ty)
                    tri.append(nd.reshape(-1, 3).astype(np.int64))
            tri = np.vstack(tri)
            a, b, c = X[tri[:, 0]], X[tri[:, 1]], X[tri[:, 2]]
            area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1).sum()
            vol6 = np.einsum("ij,ij->i", a, np.cross(b, c)).sum()
            sa, sb, sc = (s["xyz"][s["tri"][:, k]] for k in range(3))
            warea = 0.5 * np.linalg.norm(np.cross(sb - sa, sc - sa), axis=1).sum()
            wvol6 = np.einsum("ij,ij->i", sa, np.cross(sb, sc)).sum()
            check(p + " %s: %d faces cover its area" % (s["name"], len(tri)), abs(area - warea) <= 1e-9 * warea,
                  "%.6f vs %.6f mm^2" % (area, warea))
            check(p + " %s: faces enclose its volume (outward)" % s["name"], abs(vol6 - wvol6) <= 1e-6 * abs(wvol6),
                  "%.6f vs %.6f mm^3" % (vol6 / 6, wvol6 / 6))
        for rid, name, _ in m["regions"]:
            t = named.get((3, name))
            n = 0
            for e in gmsh.model.getEntitiesForPhysicalGroup(3, t) if t is not None else []:
                types, etags, nodes = gmsh.model.mesh.getElements(3, e)
                for ty, et, nd in zip(types, etags, nodes):
                    n += len(et)
                    sel = et.astype(np.int64) - 1
                    check(p + " region %s: tetrahedra as volume.tet" % name,
                          ty == 4 and np.array_equal(nd.reshape(-1, 4).astype(np.int64) - 1, v["tet"][sel])
                          and np.all(v["region"][sel] == rid))
            check(p + " region %s: count" % name, n == int((v["region"] == rid).sum()), "%d" % n)
        views = {}
        for vt in gmsh.view.getTags():
            views[gmsh.option.getString("View[%d].Name" % gmsh.view.getIndex(vt))] = vt
        want = [("volume", vol)] if vol is not None else [(k, d) for k, d in surfdata.items()]
        for who, data in want:
            stem = "potential" if who == "volume" else "potential on " + who
            vname = [n for n in views if n == stem or n.startswith(stem + " (")]
            check(p + " view of %s" % who, len(vname) == 1, "views: %s" % sorted(views))
            if len(vname) != 1:
                continue
            vt = views[vname[0]]
            idx = np.arange(len(data)) if who == "volume" else m["surf"][names.index(who)]["vmap"]
            nsteps = int(gmsh.option.getNumber("View[%d].NbTimeStep" % gmsh.view.getIndex(vt)))
            check(p + " view \"%s\": %d steps" % (vname[0], nsteps), nsteps == len(frames))
            for k, f in enumerate(frames):
                typ, ntags, d, time, nc = gmsh.view.getModelData(vt, k)
                vals = np.full(len(X), np.nan)
                vals[np.asarray(ntags, dtype=np.int64)] = np.array([x[0] for x in d])
                ok = typ == "NodeData" and time == T[f] and rel(vals[idx + 1], data[:, f]) < 1e-6
                check(p + " view \"%s\" step %d: frame %d, time %g" % (vname[0], k, f + 1, time), ok,
                      "%s, %d values, rel %.2e" % (typ, len(d), rel(vals[idx + 1], data[:, f])))
        gmsh.finalize()
    else:
        print("unknown format " + fmt, file=sys.stderr)
        return 2
    print("%d check(s) failed" % fails if fails else "all checks passed")
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
