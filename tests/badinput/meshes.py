"""Valid base files for the import bad-input modules (fmt_tri, fmt_obj, fmt_stl, fmt_ply,
fmt_vtk, fmt_vtp, fmt_volume): an octahedron of radius 50 mm (a closed outward surface) and
the same octahedron cut into 8 tetrahedra about its centre (one region), in every format
`thorax import` reads, plus small helpers that damage a text file line by line."""
import base64
import struct
import zlib

R = 50
P = [(R, 0, 0), (-R, 0, 0), (0, R, 0), (0, -R, 0), (0, 0, R), (0, 0, -R)]
T = [(0, 2, 4), (2, 1, 4), (1, 3, 4), (3, 0, 4), (2, 0, 5), (1, 2, 5), (3, 1, 5), (0, 3, 5)]
VP = P + [(0, 0, 0)]
VT = [(a, b, c, 6) for a, b, c in T]

SURF_ARGV = lambda f: ["import", "-o", "m", f, "--name", "torso", "--role", "outer", "-q"]
VOL_ARGV = lambda f: ["import", "-o", "m", f, "-q"]


def xyz(p):
    return "%d %d %d" % p


def lines(b):
    return b.split(b"\n")


def with_line(b, i, new):
    """b with its line i (0-based) replaced by new (bytes); None deletes it."""
    ls = lines(b)
    ls[i:i + 1] = [] if new is None else [new]
    return b"\n".join(ls)


def insert_at(b, pos, s):
    return b[:pos] + s + b[pos:]


def line_start(b, i):
    """Byte offset of line i (0-based)."""
    return sum(len(x) + 1 for x in lines(b)[:i])


# ---- surfaces
OPENMEEG = ("- 6\n" + "".join("%s 0 0 1\n" % xyz(p) for p in P) + "- 8 8 8\n" +
            "".join("%d %d %d\n" % t for t in T)).encode()
ECGSIM = ("6\n" + "".join("%d %s\n" % (i + 1, xyz(p)) for i, p in enumerate(P)) + "8\n" +
          "".join("%d %d %d %d\n" % (i + 1, a + 1, b + 1, c + 1) for i, (a, b, c) in enumerate(T))).encode()
OBJ = ("# octahedron\n" + "".join("v %s\n" % xyz(p) for p in P) + "vn 0 0 1\n" +
       "".join("f %d//1 %d//1 %d//1\n" % (a + 1, b + 1, c + 1) for a, b, c in T)).encode()


def normal(t):
    a, b, c = (P[i] for i in t)
    u = [b[i] - a[i] for i in range(3)]
    v = [c[i] - a[i] for i in range(3)]
    n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
    m = sum(x * x for x in n) ** 0.5
    return [x / m for x in n]


STL_ASCII = ("solid octa\n" + "".join(
    " facet normal %g %g %g\n  outer loop\n" % tuple(normal(t)) +
    "".join("   vertex %s\n" % xyz(P[i]) for i in t) + "  endloop\n endfacet\n" for t in T) +
    "endsolid octa\n").encode()
STL_BIN = b"binary octahedron".ljust(80, b" ") + struct.pack("<I", len(T)) + b"".join(
    struct.pack("<3f", *normal(t)) + b"".join(struct.pack("<3f", *P[i]) for i in t) + b"\0\0" for t in T)


def ply_header(fmt, nv=6, nf=8, extra=b""):
    return (b"ply\nformat " + fmt + b" 1.0\ncomment octahedron\nelement vertex %d\nproperty float x\n"
            b"property float y\nproperty float z\n" % nv + extra + b"element face %d\n"
            b"property list uchar int vertex_indices\nend_header\n" % nf)


PLY_ASCII = ply_header(b"ascii") + ("".join("%s\n" % xyz(p) for p in P) +
                                    "".join("3 %d %d %d\n" % t for t in T)).encode()
PLY_BIN_HEAD = ply_header(b"binary_little_endian")
PLY_BIN_VERTS = b"".join(struct.pack("<3f", *p) for p in P)
PLY_BIN = PLY_BIN_HEAD + PLY_BIN_VERTS + b"".join(struct.pack("<B3i", 3, *t) for t in T)

VTK_ASCII = ("# vtk DataFile Version 3.0\noctahedron\nASCII\nDATASET POLYDATA\nPOINTS 6 float\n" +
             "".join("%s\n" % xyz(p) for p in P) + "POLYGONS 8 32\n" + "".join("3 %d %d %d\n" % t for t in T)).encode()
VTK_BIN_HEAD = b"# vtk DataFile Version 3.0\noctahedron\nBINARY\nDATASET POLYDATA\nPOINTS 6 float\n"
VTK_BIN = (VTK_BIN_HEAD + b"".join(struct.pack(">3f", *p) for p in P) + b"\nPOLYGONS 8 32\n" +
           b"".join(struct.pack(">4i", 3, *t) for t in T) + b"\n")
VTP = ('<?xml version="1.0"?>\n<VTKFile type="PolyData" version="0.1" byte_order="LittleEndian">\n<PolyData>\n'
       '<Piece NumberOfPoints="6" NumberOfVerts="0" NumberOfLines="0" NumberOfStrips="0" NumberOfPolys="8">\n'
       '<Points>\n<DataArray type="Float32" NumberOfComponents="3" format="ascii">\n' +
       "".join("%s\n" % xyz(p) for p in P) + '</DataArray>\n</Points>\n<Polys>\n'
       '<DataArray type="Int32" Name="connectivity" format="ascii">\n' + "".join("%d %d %d\n" % t for t in T) +
       '</DataArray>\n<DataArray type="Int32" Name="offsets" format="ascii">\n' +
       " ".join(str(3 * i + 3) for i in range(8)) + '\n</DataArray>\n</Polys>\n</Piece>\n</PolyData>\n</VTKFile>\n'
       ).encode()

# ---- volumes
VPTS = "".join("%s\n" % xyz(p) for p in VP).encode()
VTET = "".join("%d %d %d %d 1\n" % (a + 1, b + 1, c + 1, d + 1) for a, b, c, d in VT).encode()
CARP_PTS = b"7\n" + VPTS
CARP_ELEM = b"8\n" + "".join("Tt %d %d %d %d 1\n" % t for t in VT).encode()
VTK_UG = ("# vtk DataFile Version 3.0\nocta\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 7 float\n" +
          "".join("%s\n" % xyz(p) for p in VP) + "CELLS 8 40\n" + "".join("4 %d %d %d %d\n" % t for t in VT) +
          "CELL_TYPES 8\n" + "10\n" * 8 + "CELL_DATA 8\nSCALARS region int 1\nLOOKUP_TABLE default\n" +
          "1\n" * 8).encode()
VTK_UG_BIN_HEAD = b"# vtk DataFile Version 3.0\nocta\nBINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS 7 float\n"
VTK_UG_BIN = (VTK_UG_BIN_HEAD + b"".join(struct.pack(">3f", *p) for p in VP) + b"\nCELLS 8 40\n" +
              b"".join(struct.pack(">5i", 4, *t) for t in VT) + b"\nCELL_TYPES 8\n" + struct.pack(">8i", *([10] * 8)) +
              b"\n")
MSH = ("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 7 1 7\n3 1 0 7\n" + "".join("%d\n" % (i + 1) for i in range(7)) +
       "".join("%s\n" % xyz(p) for p in VP) + "$EndNodes\n$Elements\n1 8 1 8\n3 1 4 8\n" +
       "".join("%d %d %d %d %d\n" % (i + 1, a + 1, b + 1, c + 1, d + 1) for i, (a, b, c, d) in enumerate(VT)) +
       "$EndElements\n").encode()

VTU_ARRAYS = [("Points", "Float32", 3, [x for p in VP for x in p], "f"),
              ("connectivity", "Int32", 1, [x for t in VT for x in t], "i"),
              ("offsets", "Int32", 1, [4 * i + 4 for i in range(8)], "i"),
              ("types", "UInt8", 1, [10] * 8, "B")]


def vtu(fmt="ascii", comp=False, arrays=None, raw_override=None):
    """A VTU of the octahedron: fmt ascii, binary (base64 inline) or appended (raw);
    comp: zlib; raw_override(name, header, data) may damage one array's bytes."""
    arrays = arrays or VTU_ARRAYS
    app = b""
    out = []
    for name, ty, nc, vals, code in arrays:
        attrs = 'type="%s" Name="%s" NumberOfComponents="%d"' % (ty, name, nc)
        if fmt == "ascii":
            out.append('<DataArray %s format="ascii">\n%s\n</DataArray>\n' % (attrs, " ".join(str(v) for v in vals)))
            continue
        data = struct.pack("<%d%s" % (len(vals), code), *vals)
        if comp:
            z = zlib.compress(data)
            head = struct.pack("<4I", 1, len(data), len(data), len(z))
            data = z
        else:
            head = struct.pack("<I", len(data))
        if raw_override:
            head, data = raw_override(name, head, data)
        if fmt == "binary":
            body = (base64.b64encode(head) + base64.b64encode(data)) if comp else base64.b64encode(head + data)
            out.append('<DataArray %s format="binary">\n%s\n</DataArray>\n' % (attrs, body.decode()))
        else:
            out.append('<DataArray %s format="appended" offset="%d"/>\n' % (attrs, len(app)))
            app += head + data
    body = ('<Piece NumberOfPoints="7" NumberOfCells="8">\n<Points>\n' + out[0] + '</Points>\n<Cells>\n' +
            "".join(out[1:4]) + '</Cells>\n</Piece>\n')
    head = ('<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" '
            'header_type="UInt32"%s>\n<UnstructuredGrid>\n' % (' compressor="vtkZLibDataCompressor"' if comp else ""))
    s = (head + body + "</UnstructuredGrid>\n").encode()
    if fmt == "appended":
        s += b'<AppendedData encoding="raw">\n_' + app + b"\n</AppendedData>\n"
    return s + b"</VTKFile>\n"


VTU_ASCII = vtu()
VTU_BIN = vtu("binary")
VTU_ZLIB = vtu("binary", comp=True)
VTU_APP = vtu("appended")
