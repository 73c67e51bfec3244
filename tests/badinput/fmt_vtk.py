"""Bad legacy VTK POLYDATA files (ASCII and BINARY), read by `thorax import`."""
import struct
from run import Case
from meshes import VTK_ASCII as A, VTK_BIN as B, VTK_BIN_HEAD as BH, P, T, with_line, insert_at, line_start, SURF_ARGV

ARGV = SURF_ARGV("s.vtk")
POS = r"s\.vtk(:\d+:|: byte \d+)"


def a(name, data, where=""):
    return Case(".vtk (POLYDATA)", name, {"s.vtk": data}, ARGV, "m", where=where, good={"s.vtk": A})


def b(name, data, where=POS):
    return Case(".vtk (POLYDATA)", "binary: " + name, {"s.vtk": data}, ARGV, "m", where=where, good={"s.vtk": B})


def binary(points=None, cells=None, head=b"POLYGONS 8 32", tail=b"\n"):
    pts = points if points is not None else b"".join(struct.pack(">3f", *p) for p in P)
    cl = cells if cells is not None else b"".join(struct.pack(">4i", 3, *t) for t in T)
    return BH + pts + b"\n" + head + b"\n" + cl + tail


# ASCII lines: 0-3 header, 4 POINTS, 5-10 points, 11 POLYGONS, 12-19 polygons
CASES = [
    a("NUL byte in a point", insert_at(A, line_start(A, 6) + 2, b"\0")),
    a("NUL byte in the title", insert_at(A, line_start(A, 1) + 2, b"\0")),
    a("POINTS count 2^31 - 1", with_line(A, 4, b"POINTS 2147483647 float")),
    a("POINTS count 2^63", with_line(A, 4, b"POINTS 9223372036854775808 float")),
    a("POINTS count one more than the points", with_line(A, 4, b"POINTS 7 float")),
    a("POINTS of an unknown type", with_line(A, 4, b"POINTS 6 float128")),
    a("a letter for a coordinate", with_line(A, 6, b"-50 y 0")),
    a("NaN coordinate", with_line(A, 6, b"-50 nan 0")),
    a("trailing garbage after a number", with_line(A, 6, b"-50 0 0abc")),
    a("POLYGONS sizes 2^31 - 1", with_line(A, 11, b"POLYGONS 2147483647 2147483647")),
    a("POLYGONS size one short", with_line(A, 11, b"POLYGONS 8 31")),
    a("POLYGONS size one long", with_line(A, 11, b"POLYGONS 8 33")),
    a("polygon vertex count larger than the list", with_line(A, 19, b"30 0 3 5")),
    a("polygon index past the last point", with_line(A, 12, b"3 0 2 6")),
    a("negative polygon index", with_line(A, 12, b"3 0 -2 4")),
    a("polygon index 2^63 - 1 (float-to-integer overflow)", with_line(A, 12, b"3 0 2 9223372036854775807")),
    a("polygon index 2^53 + 1 (rounded as a double)", with_line(A, 12, b"3 0 2 9007199254740993")),
    a("fractional polygon index", with_line(A, 12, b"3 0 2.5 4")),
    a("POLYGONS before POINTS", A[:line_start(A, 4)] + A[line_start(A, 11):]),
    a("truncated: last polygon cut", A[:-4]),
    a("unknown section", A + b"POLYHEDRA 1 2\n"),
    a("DATASET not POLYDATA", A.replace(b"POLYDATA", b"STRUCTURED_POINTS")),
    a("not ASCII or BINARY", A.replace(b"ASCII", b"TEXT")),
    b("POINTS data cut", BH + b"\0" * 20),
    b("POLYGONS data one int short", binary(cells=b"".join(struct.pack(">4i", 3, *t) for t in T)[:-4], tail=b"")),
    b("NaN coordinate", binary(points=struct.pack(">3f", float("nan"), 0, 0) + b"".join(struct.pack(">3f", *p) for p in P[1:]))),
    b("polygon index past the last point", binary(cells=struct.pack(">4i", 3, 0, 2, 6) + b"".join(struct.pack(">4i", 3, *t) for t in T[1:]))),
    b("little-endian data", binary(cells=b"".join(struct.pack("<4i", 3, *t) for t in T))),
    b("64-bit index beyond 2^53", BH.replace(b"Version 3.0", b"Version 5.1") + b"".join(struct.pack(">3f", *p) for p in P) +
      b"\nPOLYGONS 9 24\nOFFSETS vtktypeint64\n" + struct.pack(">9q", *range(0, 27, 3)) + b"\nCONNECTIVITY vtktypeint64\n" +
      struct.pack(">24q", *([0, 2, 0x7fffffffffffffff] + [x for t in T[1:] for x in t])) + b"\n"),
]
