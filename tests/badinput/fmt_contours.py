"""Bad contour files (docs/formats.md, "Contours"), read by `thorax surfaces`.

The reader reads nothing in part: every damage below is refused with exit 1 and a message
naming the file and line (and the surface, layer and loop where there is one); digitization
noise that can be repaired (a repeated closing point, near-coincident points, a small
self-crossing, a narrow hole) is repaired instead, unless --strict, which refuses it.
"""
import math

from run import Case

ARGV = ["surfaces", "c.txt", "-o", "m", "-q"]


def ring(cx, cy, r, n=12):
    return [b"%.3f %.3f" % (cx + r * math.cos(2 * math.pi * k / n), cy + r * math.sin(2 * math.pi * k / n)) for k in range(n)]


HEAD = [b"thorax-contours 1", b"# a test file", b"units mm", b"spacing 5", b"frame +z +y",
        b"surface torso outer cap grid", b"surface heart heart cap polygon"]
BODY = []
for z in (0, 10, 20, 30):  # the heart closes inside the torso's end planes (surfaces that meet fail the check)
    BODY += [b"layer %d" % z, b"loop torso"] + ring(0, 0, 60) + ([b"loop heart"] + ring(10, 5, 20) if 0 < z < 30 else [])
LINES = HEAD + BODY + [b"end"]
GOOD = {"c.txt": b"\n".join(LINES) + b"\n"}
TEXT = GOOD["c.txt"]


def at(line):
    """Index in LINES of the 1-based line number `line`."""
    return line - 1


FIRST_POINT = LINES.index(b"loop torso") + 2  # line number of the torso's first point (layer 0)


def case(name, lines=None, data=None, where="", argv=ARGV):
    if data is None:
        data = b"\n".join(lines) + b"\n"
    return Case("contours", name, {"c.txt": data}, argv, "m", where=where, good=GOOD, force=False)


def replace(line, new):
    L = list(LINES)
    L[at(line)] = new
    return L


def insert(line, new):
    L = list(LINES)
    L[at(line):at(line)] = new
    return L


LAYER2 = LINES.index(b"layer 10") + 1  # line of 'layer 10'
TORSO2 = LAYER2 + 1                      # its 'loop torso'
CASES = [
    case("NUL byte at a line start", data=TEXT[:TEXT.index(b"layer 10")] + b"\0" + TEXT[TEXT.index(b"layer 10"):]),
    case("NUL byte inside a number", data=TEXT[:TEXT.index(b"60.000")] + b"6\0" + TEXT[TEXT.index(b"60.000") + 1:]),
    case("truncated: no 'end' line, a loop cut short after its third point",
         data=b"\n".join(LINES[:LINES.index(b"layer 20") + 5]) + b"\n"),
    case("truncated: cut inside a keyword", data=TEXT[:TEXT.index(b"layer 20") + 13]),
    case("truncated: the last number cut", data=TEXT[:TEXT.rindex(b"\nend")][:-3]),
    case("trailing garbage after a number", replace(FIRST_POINT, b"60.000x 0.000")),
    case("three numbers on a point line", replace(FIRST_POINT, b"60 0 1")),
    case("one number on a point line", replace(FIRST_POINT, b"60")),
    case("hex number", replace(FIRST_POINT, b"0x3c 0")),
    case("NaN coordinate", replace(FIRST_POINT, b"nan 0")),
    case("infinite coordinate", replace(FIRST_POINT, b"60 -inf")),
    case("overflowing coordinate 1e999", replace(FIRST_POINT, b"1e999 0")),
    case("coordinate overflowing once in mm (units m)", replace(3, b"units m")[:at(FIRST_POINT)] + [b"1e306 0"] + LINES[at(FIRST_POINT) + 1:]),
    case("point before any loop", insert(LAYER2 + 1, [b"1 2"])),
    case("loop of an undeclared surface", replace(TORSO2, b"loop lung")),
    case("unknown keyword", insert(LAYER2, [b"slab 3"])),
    case("not a contour file (wrong first line)", replace(1, b"thorax-contour 1")),
    case("unknown format version", replace(1, b"thorax-contours 2")),
    case("empty file", data=b"", where=r"c\.txt: "),
    case("only comments", data=b"# nothing\n\n", where=r"c\.txt: "),
    case("binary garbage", data=bytes(range(1, 256)) * 4),
    case("a layer without loops", insert(LAYER2, [b"layer 5"])),
    case("a layer repeated", replace(LAYER2, b"layer 0")),
    case("layers out of order", replace(LINES.index(b"layer 20") + 1, b"layer 5")),
    case("a loop of 2 points", LINES[:at(FIRST_POINT) + 2] + LINES[at(FIRST_POINT) + 12:]),
    case("a loop crossing itself widely (not repairable)",
         replace(FIRST_POINT + 3, b"-60 -1") ),
    case("surface declared twice", insert(8, [b"surface torso outer"])),
    case("surface declared after the first layer", insert(LAYER2, [b"surface lung lung"])),
    case("frame: an axis that is none", replace(5, b"frame +z +q")),
    case("frame: superior and anterior on one axis", replace(5, b"frame +z -z")),
    case("frame given twice", insert(6, [b"frame +y +z"])),
    case("frame after the first layer", insert(LAYER2, [b"frame +z +y"])),
    case("unknown units", replace(3, b"units inch")),
    case("spacing zero", replace(4, b"spacing 0")),
    case("text after 'end'", data=TEXT + b"layer 30\n"),
    case("a surface that vanishes and reappears",
         [l for i, l in enumerate(LINES) if not (LAYER2 + 13 <= i + 1 <= LAYER2 + 25)]),
    case("a hole wider than the node spacing (refused)",
         LINES[:at(TORSO2 + 13)] + [b"loop torso"] + ring(0, 0, 15) + LINES[at(TORSO2 + 13):]),
    case("--strict: a loop closed by repeating its first point",
         LINES[:at(FIRST_POINT) + 12] + [LINES[at(FIRST_POINT)]] + LINES[at(FIRST_POINT) + 12:],
         where=r"c\.txt:\d+: .*repeats the first point", argv=ARGV + ["--strict"]),
    case("--strict: near-coincident points",
         insert(FIRST_POINT + 1, [b"60.001 0.001"]), where=r"c\.txt:\d+: .*near-coincident", argv=ARGV + ["--strict"]),
]
