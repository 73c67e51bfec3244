"""Bad PLY files (ascii and binary), read by `thorax import`."""
import struct
from run import Case
from meshes import (PLY_ASCII as A, PLY_BIN as B, PLY_BIN_HEAD as BH, PLY_BIN_VERTS as BV, T, ply_header,
                    with_line, insert_at, line_start, SURF_ARGV)

ARGV = SURF_ARGV("s.ply")
BYTE = r"s\.ply: byte \d+"
BODY = A[len(ply_header(b"ascii")):]


def a(name, data, where=""):
    return Case(".ply (ascii)", name, {"s.ply": data}, ARGV, "m", where=where, good={"s.ply": A})


def b(name, data, where=BYTE):
    return Case(".ply (binary)", name, {"s.ply": data}, ARGV, "m", where=where, good={"s.ply": B})


def faces(fmt="<", count="B", idx="i", rows=None):
    return b"".join(struct.pack(fmt + count + "3" + idx, 3, *t) for t in (rows or T))


H = len(ply_header(b"ascii").split(b"\n")) - 1  # first body line (0-based)
CASES = [
    a("NUL byte in the header", insert_at(A, line_start(A, 3), b"\0")),
    a("NUL byte in a number", insert_at(A, line_start(A, H + 1) + 2, b"\0")),
    a("vertex count 2^31 - 1", with_line(A, 3, b"element vertex 2147483647")),
    a("vertex count 2^63", with_line(A, 3, b"element vertex 9223372036854775808")),
    a("negative face count", A.replace(b"element face 8", b"element face -8")),
    a("face count one more than the faces", A.replace(b"element face 8", b"element face 9")),
    a("face count one fewer (trailing data)", A.replace(b"element face 8", b"element face 7")),
    a("unknown property type", with_line(A, 4, b"property float33 x")),
    a("header without end_header", ply_header(b"ascii").replace(b"end_header\n", b"")),
    a("a letter for a coordinate", with_line(A, H + 1, b"-50 y 0")),
    a("NaN coordinate", with_line(A, H + 1, b"-50 nan 0")),
    a("trailing garbage after a number", with_line(A, H + 1, b"-50 0 0abc")),
    a("face index past the last vertex", with_line(A, H + 6, b"3 0 2 6")),
    a("negative face index", with_line(A, H + 6, b"3 0 -2 4")),
    a("face index 2^63 - 1 (float-to-integer overflow)", with_line(A, H + 6, b"3 0 2 9223372036854775807")),
    a("face index 2^53 + 1 (rounded as a double)", with_line(A, H + 6, b"3 0 2 9007199254740993")),
    a("fractional face index", with_line(A, H + 6, b"3 0 2.5 4")),
    a("list length 300 for a uchar", with_line(A, H + 6, b"300 0 2 4")),
    a("list length 2", with_line(A, H + 6, b"2 0 2")),
    a("truncated: last face cut", A[:-4]),
    a("truncated: vertices only", A[:line_start(A, H + 6)]),
    a("empty property-less element with a huge count, then garbage",
      A.replace(b"end_header", b"element junk 2147483647\nend_header") + b"9\n"),
    a("not a PLY file", b"ply2\n" + A[4:], where=r"s\.ply:1:"),
    b("NUL byte in the header", insert_at(B, 10, b"\0"), where=r"s\.ply:\d+:"),
    b("face count 2^31 - 1", BH.replace(b"element face 8", b"element face 2147483647") + BV + faces(),
      where=r"s\.ply:\d+:"),
    b("vertex count one more than the vertices", BH.replace(b"element vertex 6", b"element vertex 7") + BV + faces()),
    b("face count one fewer (trailing bytes)", BH.replace(b"element face 8", b"element face 7") + BV + faces()),
    b("truncated: last face cut", B[:-5]),
    b("truncated: inside the vertices", B[:len(BH) + 30], where=r"s\.ply(: byte \d+|:\d+:)"),
    b("truncated: header only", BH, where=r"s\.ply(: byte \d+|:\d+:)"),
    b("NaN coordinate", BH + struct.pack("<3f", float("nan"), 0, 0) + BV[12:] + faces()),
    b("infinite coordinate", BH + BV[:24] + struct.pack("<3f", 0, float("inf"), 0) + BV[36:] + faces()),
    b("face index past the last vertex", BH + BV + faces(rows=[(0, 2, 6)] + T[1:])),
    b("negative face index", BH + BV + faces(rows=[(0, -2, 4)] + T[1:])),
    b("face index 2^31 - 1", BH + BV + faces(rows=[(0, 2, 2147483647)] + T[1:])),
    b("face index 2^32 - 1 as uint", BH.replace(b"uchar int", b"uchar uint") + BV +
      faces(idx="I", rows=[(0, 2, 4294967295)] + T[1:])),
    b("list length 255", BH + BV + struct.pack("<B3i", 255, 0, 2, 4) + faces(rows=T[1:])),
    b("list length 0", BH + BV + struct.pack("<B", 0) + faces(rows=T[1:])),
    b("wrong byte order", B.replace(b"binary_little_endian", b"binary_big_endian")),
    b("a second copy appended", B + B[len(BH):]),
    b("one trailing byte", B + b"\n"),
    b("list count of a float type", BH.replace(b"uchar int", b"float int") + BV + faces(), where=r"s\.ply:\d+:"),
    b("faces before the vertices", BH.replace(b"element face 8\nproperty list uchar int vertex_indices\n", b"")
      .replace(b"element vertex 6", b"element face 8\nproperty list uchar int vertex_indices\nelement vertex 6") +
      faces() + BV, where=r"s\.ply:\d+:"),
    b("vertex count 0 (trailing bytes)", BH.replace(b"element vertex 6", b"element vertex 0") + BV + faces(),
      where=r"s\.ply(: byte \d+|:\d+:)"),
    b("unknown format", B.replace(b"binary_little_endian", b"binary_middle_endian"), where=r"s\.ply:\d+:"),
]
