"""Bad .tri files (OpenMEEG "- NV" and ECGSim / MBFYS text), read by `thorax import`."""
from run import Case
from meshes import OPENMEEG as OM, ECGSIM as EC, with_line, insert_at, line_start, SURF_ARGV

ARGV = SURF_ARGV("s.tri")


def om(name, data, where=""):
    return Case(".tri (OpenMEEG)", name, {"s.tri": data}, ARGV, "m", where=where, good={"s.tri": OM})


def ec(name, data, where=""):
    return Case(".tri (ECGSim)", name, {"s.tri": data}, ARGV, "m", where=where, good={"s.tri": EC})


BYTE = r"s\.tri(:\d+)?: "
CASES = [
    om("NUL byte at a line start", insert_at(OM, line_start(OM, 3), b"\0")),
    om("NUL byte inside a number", insert_at(OM, line_start(OM, 2) + 1, b"\0")),
    om("vertex count 2^31 - 1", with_line(OM, 0, b"- 2147483647")),
    om("vertex count 2^63", with_line(OM, 0, b"- 9223372036854775808")),
    om("negative vertex count", with_line(OM, 0, b"- -6")),
    om("vertex count missing", with_line(OM, 0, b"-")),
    om("garbage after the vertex count", with_line(OM, 0, b"- 6 x")),
    om("five numbers on a vertex line", with_line(OM, 2, b"-50 0 0 0 0")),
    om("seven numbers on a vertex line", with_line(OM, 2, b"-50 0 0 0 0 1 1")),
    om("a letter for a coordinate", with_line(OM, 2, b"-50 y 0 0 0 1")),
    om("NaN coordinate", with_line(OM, 2, b"-50 nan 0 0 0 1")),
    om("overflowing coordinate 1e999", with_line(OM, 2, b"-50 1e999 0 0 0 1")),
    om("trailing garbage after a number", with_line(OM, 2, b"-50 0 0 0 0 1abc")),
    om("triangle count 2^31 - 1", with_line(OM, 7, b"- 2147483647 2147483647 2147483647")),
    om("triangle counts differ", with_line(OM, 7, b"- 8 7 8")),
    om("triangle header missing", with_line(OM, 7, None)),
    om("vertex index past the last vertex", with_line(OM, 8, b"0 2 6")),
    om("negative vertex index", with_line(OM, 8, b"0 -2 4")),
    om("vertex index 2^63 (signed overflow)", with_line(OM, 8, b"0 2 9223372036854775808")),
    om("vertex index overflowing 64 bits", with_line(OM, 8, b"0 2 99999999999999999999")),
    om("fractional vertex index", with_line(OM, 8, b"0 2.5 4")),
    om("hex vertex index", with_line(OM, 8, b"0 0x2 4")),
    om("two indices on a triangle line", with_line(OM, 8, b"0 2")),
    om("four indices on a triangle line", with_line(OM, 8, b"0 2 4 1")),
    om("truncated: last triangle cut", OM[:-3]),
    om("truncated: triangles missing", b"\n".join(OM.split(b"\n")[:12]) + b"\n"),
    om("trailing garbage after the last triangle", OM + b"0 1 2\n"),
    om("empty file", b"", where=BYTE),
    ec("NUL byte at a line start", insert_at(EC, line_start(EC, 3), b"\0")),
    ec("NUL byte inside a number", insert_at(EC, line_start(EC, 2) + 3, b"\0")),
    ec("node count 2^31 - 1", with_line(EC, 0, b"2147483647")),
    ec("node count 2^63", with_line(EC, 0, b"9223372036854775808")),
    ec("negative node count", with_line(EC, 0, b"-6")),
    ec("node count not a number", with_line(EC, 0, b"six")),
    ec("a letter for a coordinate", with_line(EC, 2, b"2 -50 x 0")),
    ec("NaN coordinate", with_line(EC, 2, b"2 -50 nan 0")),
    ec("infinite coordinate", with_line(EC, 2, b"2 -50 inf 0")),
    ec("trailing garbage after a number", with_line(EC, 2, b"2 -50 0 0q")),
    ec("triangle count 2^31 - 1", with_line(EC, 7, b"2147483647")),
    ec("triangle count 2^64", with_line(EC, 7, b"18446744073709551616")),
    ec("triangle count missing (file ends after the nodes)", b"\n".join(EC.split(b"\n")[:7]) + b"\n"),
    ec("node number past the last node", with_line(EC, 8, b"1 1 3 7")),
    ec("node number -2^63 (signed overflow on the base)", with_line(EC, 8, b"1 1 3 -9223372036854775808")),
    ec("node number 2^63 - 1", with_line(EC, 8, b"1 1 3 9223372036854775807")),
    ec("node number overflowing 64 bits", with_line(EC, 8, b"1 1 3 99999999999999999999")),
    ec("fractional node number", with_line(EC, 8, b"1 1 3.5 5")),
    ec("hex node number", with_line(EC, 8, b"1 1 0x3 5")),
    ec("a letter for a node number", with_line(EC, 8, b"1 1 c 5")),
    ec("label not an integer", with_line(EC, 9, b"x 3 2 5")),
    ec("truncated: last triangle cut", EC[:-3]),
    ec("truncated: nodes cut", b"\n".join(EC.split(b"\n")[:4]) + b"\n"),
    ec("empty file", b"", where=BYTE),
]
