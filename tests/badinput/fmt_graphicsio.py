"""Bad map3d/CVRTI graphicsio files, made from the real ones in ../shared/data/map3d by one damage
each: .tsdf read by `thorax series convert`, .geom by `thorax import`. Every message must name the
file and the byte offset of the field at fault."""
import os
import struct

from run import Case

DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "..", "shared", "data", "map3d")
with open(os.path.join(DATA, "data", "torso", "dipole2.tsdf"), "rb") as f:
    TSDF = f.read()  # 40-byte header, series header at 468 (324 bytes), data at 816: 352 x 6 VAX reals
with open(os.path.join(DATA, "geom", "torso", "daltorsoepi.geom"), "rb") as f:
    GEOM = f.read()  # 2 surfaces; surface 1 at 468: node header 576 (352 nodes at 612), elements 4836 (700 at 4876)

TS_ARGV = ["series", "convert", "s.tsdf", "-o", "out.txt", "-q"]
GEOM_ARGV = ["import", "-o", "out", "s.geom@1", "--name", "torso", "--role", "outer", "-q"]


def put(data, off, v):
    b = bytearray(data)
    struct.pack_into("<i", b, off, v)
    return bytes(b)


def tsdf(name, data, where=r"s\.tsdf: byte \d+: "):
    return Case(".tsdf (map3d)", name, {"s.tsdf": data}, TS_ARGV, "out.txt", where=where, good={"s.tsdf": TSDF},
                force=False)


def geom(name, data, where=r"s\.geom: byte \d+: "):
    return Case(".geom (map3d)", name, {"s.geom": data}, GEOM_ARGV, "out", where=where, damaged="s.geom",
                good={"s.geom": GEOM})


def reserved(data, off):
    b = bytearray(data)
    b[off:off + 4] = b"\x00\x80\x00\x00"  # sign bit, exponent 0: VAX's reserved operand
    return bytes(b)


CASES = [
    tsdf("truncated in the header", TSDF[:30], where=r"s\.tsdf: byte 0: the file is 30 bytes"),
    tsdf("truncated in the series header", TSDF[:600], where=r"s\.tsdf: byte 468: time series 1: its 324-byte header"),
    tsdf("truncated in the data", TSDF[:9000], where=r"s\.tsdf: byte 568: the data at byte 816"),
    tsdf("header size 48", put(TSDF, 0, 48), where=r"s\.tsdf: byte 0: header size 48"),
    tsdf("2^31-1 time series", put(TSDF, 28, 2**31 - 1), where=r"s\.tsdf: byte 28: time series count"),
    tsdf("first series header beyond the end", put(TSDF, 32, 10**6), where=r"s\.tsdf: byte 32: "),
    tsdf("series header size 100", put(TSDF, 468, 100), where=r"s\.tsdf: byte 468: time series 1: header size 100"),
    tsdf("10^9 frames", put(TSDF, 468 + 96, 10**9), where=r"s\.tsdf: byte 560: .*cannot fit"),
    tsdf("negative channels", put(TSDF, 468 + 92, -5), where=r"s\.tsdf: byte 560: "),
    tsdf("data pointer negative", put(TSDF, 468 + 100, -4), where=r"s\.tsdf: byte 568: "),
    tsdf("a VAX reserved operand (NaN)", reserved(TSDF, 816 + 4 * 400),
         where=r"s\.tsdf: byte 2416: time series 1: channel 49, frame 2 is a VAX reserved operand"),
    tsdf("storage format 7", put(put(TSDF, 468, 336), 468 + 324, 7), where=r"s\.tsdf: byte 792: "),
    tsdf("data in an external file", TSDF[:468 + 132] + b"t1f001.raw\0" + TSDF[468 + 143:],
         where=r"s\.tsdf: byte 600: .*external file 't1f001.raw'"),
    tsdf("truncated at 1 byte", TSDF[:1], where=r"s\.tsdf: byte 0: the file is 1 bytes"),
    tsdf("truncated in the info block", TSDF[:200], where=r"s\.tsdf: byte 28: time series count 1 is impossible in a file of 200"),
    tsdf("truncated 1 byte short", TSDF[:-1], where=r"s\.tsdf: byte 568: the data at byte 816 \(8448 bytes\) is not inside the file \(9263"),
    tsdf("info block pointer beyond the end", put(TSDF, 8, 9000), where=r"s\.tsdf: byte 8: the file info block at byte 9000"),
    tsdf("zero frames", put(TSDF, 468 + 96, 0), where=r"s\.tsdf: byte 560: time series 1: 352 channels x 0 frames"),
    tsdf("a second series claimed, its header beyond the end", put(put(TSDF, 28, 2), 468 + 4, 10**7),
         where=r"s\.tsdf: byte 472: the next time series header"),
    tsdf("a reserved operand in the last value", reserved(TSDF, len(TSDF) - 4),
         where=r"s\.tsdf: byte 9260: time series 1: channel 352, frame 6"),
    tsdf("an all-zero file", bytes(len(TSDF)), where=r"s\.tsdf: byte 0: header size 0"),
    tsdf("a text file", b"thorax-series 1\n" * 20, where=r"s\.tsdf: byte 0: header size"),
    tsdf("no time series (a .geom)", GEOM, where=r"s\.tsdf: byte 28: the file holds no time series but surfaces"),
    geom("truncated in the nodes", GEOM[:4500], where=r"s\.geom: byte 584: the nodes at byte 612 \(4224 bytes\) is not inside"),
    geom("truncated: too short for its nodes", GEOM[:2000], where=r"s\.geom: byte 580: surface 1: node count 352 is impossible"),
    geom("truncated in the second surface", GEOM[:14000], where=r"s\.geom: byte 13392: the nodes at byte 13420"),
    geom("10^6 nodes", put(GEOM, 580, 10**6), where=r"s\.geom: byte 580: surface 1: node count 1000000"),
    geom("node header beyond the end", put(GEOM, 476, 10**7), where=r"s\.geom: byte 476: the node header"),
    geom("a node number 353 of 352", put(GEOM, 4876 + 4 * 7, 353),
         where=r"s\.geom: byte 4904: surface 1: triangle 3: node number 353 out of range 1\.\.352"),
    geom("a node number 0 (1-based)", put(GEOM, 4876, 0), where=r"s\.geom: byte 4876: .*node number 0"),
    geom("tetrahedra", put(GEOM, 4836 + 8, 4), where=r"s\.geom: byte 4844: .*tetrahedra"),
    geom("a VAX reserved operand in a coordinate", reserved(GEOM, 612 + 4 * 5),
         where=r"s\.geom: byte 632: surface 1: node 2: coordinate z is a VAX reserved operand"),
    geom("surface count 10^6", put(GEOM, 12, 10**6), where=r"s\.geom: byte 12: surface count"),
    geom("next surface pointer out of the file", put(GEOM, 472, 10**8), where=r"s\.geom: byte 472: the next surface"),
    geom("truncated at 40 bytes", GEOM[:40], where=r"s\.geom: byte 16: the first surface header at byte 468"),
    geom("truncated in the surface header", GEOM[:480], where=r"s\.geom: byte 16: the first surface header at byte 468"),
    geom("truncated in the triangles", GEOM[:13000], where=r"s\.geom: byte 4848: the triangles at byte 4876"),
    geom("triangle count 10^6", put(GEOM, 4840, 10**6), where=r"s\.geom: byte 4840: surface 1: triangle count"),
    geom("line segments", put(GEOM, 4844, 2), where=r"s\.geom: byte 4844: .*line segments"),
    geom("no element header", put(GEOM, 480, 0), where=r"s\.geom: byte 480: surface 1 has no elements"),
    geom("surface header size 4", put(GEOM, 468, 4), where=r"s\.geom: byte 468: surface 1: header size 4"),
    geom("a node number -1", put(GEOM, 4876 + 4 * 100, -1), where=r"s\.geom: byte 5276: surface 1: triangle 34: node number -1"),
    geom("a second surface's node count beyond the file", put(GEOM, 13388, 10**6),
         where=r"s\.geom: byte 13388: surface 2: node count 1000000"),
    geom("no surfaces (a .tsdf)", TSDF, where=r"s\.geom: byte 12: the file holds no surface but time series"),
]
