"""Bad VTK XML PolyData (.vtp) files, read by `thorax import`."""
from run import Case
from meshes import VTP, with_line, insert_at, line_start, SURF_ARGV

ARGV = SURF_ARGV("s.vtp")


def c(name, data, where=""):
    return Case(".vtp", name, {"s.vtp": data}, ARGV, "m", where=where, good={"s.vtp": VTP})


L = VTP.split(b"\n")
PT = next(i for i, x in enumerate(L) if x.startswith(b'<DataArray type="Float32"')) + 1   # first point line
CN = next(i for i, x in enumerate(L) if b'Name="connectivity"' in x) + 1                 # first polygon line
OF = next(i for i, x in enumerate(L) if b'Name="offsets"' in x) + 1                      # the offsets line
CASES = [
    c("NUL byte in a point", insert_at(VTP, line_start(VTP, PT) + 1, b"\0")),
    c("NUL byte in a tag", insert_at(VTP, line_start(VTP, 3) + 3, b"\0")),
    c("NumberOfPoints 2^31 - 1", VTP.replace(b'NumberOfPoints="6"', b'NumberOfPoints="2147483647"')),
    c("NumberOfPoints 2^63", VTP.replace(b'NumberOfPoints="6"', b'NumberOfPoints="9223372036854775808"')),
    c("NumberOfPoints negative", VTP.replace(b'NumberOfPoints="6"', b'NumberOfPoints="-6"')),
    c("NumberOfPoints one more", VTP.replace(b'NumberOfPoints="6"', b'NumberOfPoints="7"')),
    c("NumberOfPoints one fewer (trailing values)", VTP.replace(b'NumberOfPoints="6"', b'NumberOfPoints="5"')),
    c("NumberOfPolys 2^31 - 1", VTP.replace(b'NumberOfPolys="8"', b'NumberOfPolys="2147483647"')),
    c("NumberOfPolys one more", VTP.replace(b'NumberOfPolys="8"', b'NumberOfPolys="9"')),
    c("a letter for a coordinate", with_line(VTP, PT + 1, b"-50 y 0")),
    c("NaN coordinate", with_line(VTP, PT + 1, b"-50 nan 0")),
    c("trailing garbage after a number", with_line(VTP, PT + 1, b"-50 0 0abc")),
    c("connectivity index past the last point", with_line(VTP, CN, b"0 2 6")),
    c("negative connectivity index", with_line(VTP, CN, b"0 -2 4")),
    c("connectivity index 2^63 - 1", with_line(VTP, CN, b"0 2 9223372036854775807")),
    c("fractional connectivity index", with_line(VTP, CN, b"0 2.5 4")),
    c("offsets decreasing", with_line(VTP, OF, b"3 6 5 12 15 18 21 24")),
    c("last offset past the connectivity", with_line(VTP, OF, b"3 6 9 12 15 18 21 27")),
    c("last offset 1e30", with_line(VTP, OF, b"3 6 9 12 15 18 21 1e30")),
    c("binary DataArray", VTP.replace(b'format="ascii"', b'format="binary"', 1)),
    c("not PolyData", VTP.replace(b'type="PolyData"', b'type="ImageData"')),
    c("truncated: cut in the points", VTP[:line_start(VTP, PT + 2)]),
    c("truncated: cut in the connectivity", VTP[:line_start(VTP, CN + 3)]),
    c("two Pieces", VTP.replace(b"</Piece>", b"</Piece>\n<Piece NumberOfPoints=\"0\">\n</Piece>")),
]
