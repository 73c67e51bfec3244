"""Bad Wavefront OBJ files, read by `thorax import`."""
from run import Case
from meshes import OBJ, with_line, insert_at, line_start, SURF_ARGV

ARGV = SURF_ARGV("s.obj")


def c(name, data, where=""):
    return Case(".obj", name, {"s.obj": data}, ARGV, "m", where=where, good={"s.obj": OBJ})


# line 0 comment, 1-6 vertices, 7 vn, 8-15 faces
CASES = [
    c("NUL byte at a line start", insert_at(OBJ, line_start(OBJ, 3), b"\0")),
    c("NUL byte inside a number", insert_at(OBJ, line_start(OBJ, 2) + 3, b"\0")),
    c("NUL byte in a comment", insert_at(OBJ, 3, b"\0")),
    c("two coordinates on a vertex line", with_line(OBJ, 2, b"v -50 0")),
    c("a letter for a coordinate", with_line(OBJ, 2, b"v -50 y 0")),
    c("NaN coordinate", with_line(OBJ, 2, b"v -50 nan 0")),
    c("overflowing coordinate 1e999", with_line(OBJ, 2, b"v -50 1e999 0")),
    c("trailing garbage after a number", with_line(OBJ, 2, b"v -50 0 0abc")),
    c("garbage after the coordinates", with_line(OBJ, 2, b"v -50 0 0 junk")),
    c("eight numbers on a vertex line", with_line(OBJ, 2, b"v -50 0 0 1 1 1 1 1")),
    c("face vertex 0", with_line(OBJ, 8, b"f 0 3 5")),
    c("face vertex past the last vertex", with_line(OBJ, 8, b"f 1 3 7")),
    c("negative face vertex beyond the first", with_line(OBJ, 8, b"f -7 3 5")),
    c("face vertex 2^63", with_line(OBJ, 8, b"f 1 3 9223372036854775808")),
    c("face vertex -2^63", with_line(OBJ, 8, b"f 1 3 -9223372036854775808")),
    c("face vertex overflowing 64 bits", with_line(OBJ, 8, b"f 1 3 99999999999999999999")),
    c("fractional face vertex", with_line(OBJ, 8, b"f 1 3.5 5")),
    c("hex face vertex", with_line(OBJ, 8, b"f 1 0x3 5")),
    c("a letter in a texture number", with_line(OBJ, 8, b"f 1/x 3 5")),
    c("three slashes in a face vertex", with_line(OBJ, 8, b"f 1/1/1/1 3 5")),
    c("a face of two vertices", with_line(OBJ, 8, b"f 1 3")),
    c("a face before any vertex", b"f 1 2 3\n" + OBJ),
    c("truncated: last face cut to two vertices", OBJ[:-5]),
    c("truncated: cut inside a face vertex", OBJ[:-3]),
    c("trailing garbage after a face vertex", with_line(OBJ, 8, b"f 1 3 5;")),
]
