"""Bad STL files (ASCII and binary), read by `thorax import`."""
import struct
from run import Case
from meshes import STL_ASCII as A, STL_BIN as B, with_line, insert_at, line_start, SURF_ARGV

ARGV = SURF_ARGV("s.stl")
BYTE = r"s\.stl: byte \d+"


def a(name, data, where=""):
    return Case(".stl (ASCII)", name, {"s.stl": data}, ARGV, "m", where=where, good={"s.stl": A})


def b(name, data, where=BYTE):
    return Case(".stl (binary)", name, {"s.stl": data}, ARGV, "m", where=where, good={"s.stl": B})


def corner(data, t, k, xyz):
    """Binary STL with corner k of facet t set to xyz (floats)."""
    o = 84 + 50 * t + 12 + 12 * k
    return data[:o] + struct.pack("<3f", *xyz) + data[o + 12:]


# ASCII lines: 0 solid, then per facet 7 lines: facet, outer loop, 3 vertex, endloop, endfacet
CASES = [
    a("NUL byte at a line start", insert_at(A, line_start(A, 3), b"\0"), where=r"s\.stl(:\d+:|: byte \d+)"),
    a("NUL byte inside a number", insert_at(A, line_start(A, 3) + 12, b"\0"), where=r"s\.stl(:\d+:|: byte \d+)"),
    a("two coordinates on a vertex line", with_line(A, 3, b"   vertex 50 0")),
    a("four coordinates on a vertex line", with_line(A, 3, b"   vertex 50 0 0 1")),
    a("a letter for a coordinate", with_line(A, 3, b"   vertex 50 y 0")),
    a("NaN coordinate", with_line(A, 3, b"   vertex 50 nan 0")),
    a("overflowing coordinate 1e999", with_line(A, 3, b"   vertex 50 1e999 0")),
    a("trailing garbage after a number", with_line(A, 3, b"   vertex 50 0 0x")),
    a("vertex outside a loop", with_line(A, 2, b"  outer looop")),
    a("facet normal not numbers", with_line(A, 1, b" facet normal a b c")),
    a("facet normal with two numbers", with_line(A, 1, b" facet normal 0 0")),
    a("endloop without outer loop", with_line(A, 2, b"")),
    a("outer loop inside a loop", with_line(A, 5, b"  outer loop")),
    a("a facet of two vertices", with_line(A, 5, None)),
    a("unknown keyword", with_line(A, 1, b" facett normal 0 0 1")),
    a("truncated: last facet cut", A[:A.rfind(b"   vertex")]),
    a("truncated: cut mid-number", A[:A.rfind(b"endloop") - 5]),
    a("no solid line, too short for binary", A[6:60], where=r"s\.stl(:\d+:| )"),
    a("garbage after a vertex", with_line(A, 3, b"   vertex 50 0 0 ;")),
    a("empty file", b"", where=r"s\.stl(:\d+:| )"),
    b("one byte short", B[:-1]),
    b("one byte too many", B + b"\0"),
    b("facet count 2^32 - 1", B[:80] + struct.pack("<I", 0xFFFFFFFF) + B[84:]),
    b("facet count 0 with facets", B[:80] + struct.pack("<I", 0) + B[84:]),
    b("facet count one more than the facets", B[:80] + struct.pack("<I", 9) + B[84:]),
    b("facet count one fewer than the facets", B[:80] + struct.pack("<I", 7) + B[84:]),
    b("NaN corner", corner(B, 2, 1, (float("nan"), 0, 0))),
    b("infinite corner", corner(B, 2, 1, (float("inf"), 0, 0))),
    b("-infinite corner", corner(B, 7, 2, (0, float("-inf"), 0))),
    b("NaN in the first facet", corner(B, 0, 0, (0, 0, float("nan")))),
    b("truncated: header only", B[:84]),
    b("truncated: half a facet", B[:84 + 25]),
    b("truncated: 80-byte header cut", B[:60], where=r"s\.stl(:\d+:| )"),
    b("truncated: last facet cut", B[:-10]),
    b("truncated: last attribute bytes missing", B[:-2]),
    b("padded with a newline", B + b"\n"),
    b("a second file appended", B + B),
    b("count in big-endian", B[:80] + struct.pack(">I", 8) + B[84:]),
    b("huge infinite corner in the last facet", corner(B, 7, 0, (float("inf"), float("inf"), float("inf")))),
    b("NaN corner mid-file", corner(B, 4, 2, (float("nan"),) * 3)),
]
