"""Bad volume meshes (.pts + .tet, CARP .pts + .elem, legacy VTK UNSTRUCTURED_GRID, VTU, Gmsh MSH 4.1),
read by `thorax import MESH`."""
import struct
from run import Case
from meshes import (VPTS, VTET, CARP_PTS, CARP_ELEM, VTK_UG as UG, VTK_UG_BIN as UGB, VTK_UG_BIN_HEAD as UGBH, MSH,
                    VTU_ASCII, VTU_BIN, VTU_ZLIB, VTU_APP, VP, VT, vtu, with_line, insert_at, line_start, VOL_ARGV)

POS = lambda f: f.replace(".", r"\.") + r"(:\d+:|: byte \d+)"


def tet(name, pts=VPTS, elem=VTET, damaged="m.tet", where=""):
    return Case(".pts/.tet", name, {"m.pts": pts, "m.tet": elem}, VOL_ARGV("m.pts"), "m", where=where,
                damaged=damaged, good={"m.pts": VPTS, "m.tet": VTET})


def carp(name, pts=CARP_PTS, elem=CARP_ELEM, damaged="m.elem", where=""):
    return Case(".pts/.elem (CARP)", name, {"m.pts": pts, "m.elem": elem}, VOL_ARGV("m.pts"), "m", where=where,
                damaged=damaged, good={"m.pts": CARP_PTS, "m.elem": CARP_ELEM})


def vtk(name, data, where=POS("m.vtk")):
    return Case(".vtk (UNSTRUCTURED_GRID)", name, {"m.vtk": data}, VOL_ARGV("m.vtk"), "m", where=where,
                good={"m.vtk": UG})


def vtkb(name, data, where=POS("m.vtk")):
    return Case(".vtk (UNSTRUCTURED_GRID)", "binary: " + name, {"m.vtk": data}, VOL_ARGV("m.vtk"), "m", where=where,
                good={"m.vtk": UGB})


def vu(name, data, good=VTU_ASCII, where=POS("m.vtu")):
    return Case(".vtu", name, {"m.vtu": data}, VOL_ARGV("m.vtu"), "m", where=where, good={"m.vtu": good})


def msh(name, data, where=""):
    return Case(".msh", name, {"m.msh": data}, VOL_ARGV("m.msh"), "m", where=where, good={"m.msh": MSH})


def override(which, fn):
    return lambda name, head, data: fn(head, data) if name == which else (head, data)


PTS_ERR = dict(damaged="m.pts")
# VTK lines: 0-3 header, 4 POINTS, 5-11 points, 12 CELLS, 13-20 cells, 21 CELL_TYPES, 22-29 types, 30 CELL_DATA ...
# MSH lines: 0-2 format, 3 $Nodes, 4 counts, 5 block, 6-12 tags, 13-19 coordinates, 20 $EndNodes, 21 $Elements,
#            22 counts, 23 block, 24-31 elements, 32 $EndElements
CASES = [
    tet("NUL byte in a node line", pts=insert_at(VPTS, 3, b"\0"), **PTS_ERR),
    tet("NUL byte in an element line", elem=insert_at(VTET, line_start(VTET, 2) + 1, b"\0")),
    tet("two coordinates on a node line", pts=with_line(VPTS, 1, b"-50 0"), **PTS_ERR),
    tet("a letter for a coordinate", pts=with_line(VPTS, 1, b"-50 y 0"), **PTS_ERR),
    tet("NaN coordinate", pts=with_line(VPTS, 1, b"-50 nan 0"), **PTS_ERR),
    tet("trailing garbage after a coordinate", pts=with_line(VPTS, 1, b"-50 0 0abc"), **PTS_ERR),
    tet("three node numbers on an element line", elem=with_line(VTET, 1, b"3 2 5")),
    tet("seven numbers on an element line", elem=with_line(VTET, 1, b"3 2 5 7 1 1 1")),
    tet("region column on some lines only", elem=with_line(VTET, 1, b"3 2 5 7")),
    tet("node number past the last node", elem=with_line(VTET, 1, b"3 2 5 8 1")),
    tet("node number 0 with a node number 7 (ambiguous base)", elem=with_line(VTET, 1, b"3 0 5 7 1"),
        where=r"m\.tet(:\d+:|: )"),
    tet("negative node number", elem=with_line(VTET, 1, b"3 -2 5 7 1")),
    tet("node number 2^63 (signed overflow)", elem=with_line(VTET, 1, b"3 2 5 9223372036854775808 1")),
    tet("node number -2^63", elem=with_line(VTET, 1, b"3 2 5 -9223372036854775808 1")),
    tet("node number overflowing 64 bits", elem=with_line(VTET, 1, b"3 2 5 99999999999999999999 1")),
    tet("fractional node number", elem=with_line(VTET, 1, b"3 2.5 5 7 1")),
    tet("hex node number", elem=with_line(VTET, 1, b"3 0x2 5 7 1")),
    tet("fractional region", elem=with_line(VTET, 1, b"3 2 5 7 1.5")),
    tet("region 2^64", elem=with_line(VTET, 1, b"3 2 5 7 18446744073709551616")),
    tet("truncated: last element cut", elem=VTET[:-4]),
    tet("truncated: node line cut", pts=VPTS[:-3], damaged="m.pts", where=r"m\.(pts|tet)(:\d+:|: )"),
    tet("count line larger than the nodes", pts=b"2147483647\n" + VPTS, **PTS_ERR),
    carp("NUL byte in an element line", elem=insert_at(CARP_ELEM, line_start(CARP_ELEM, 2) + 4, b"\0")),
    carp("element count 2^31 - 1", elem=with_line(CARP_ELEM, 0, b"2147483647")),
    carp("element count 2^63", elem=with_line(CARP_ELEM, 0, b"9223372036854775808")),
    carp("element count one more", elem=with_line(CARP_ELEM, 0, b"9")),
    carp("element count one fewer", elem=with_line(CARP_ELEM, 0, b"7")),
    carp("negative element count", elem=with_line(CARP_ELEM, 0, b"-8")),
    carp("node count 2^31 - 1", pts=with_line(CARP_PTS, 0, b"2147483647"), damaged="m.pts"),
    carp("node count one fewer", pts=with_line(CARP_PTS, 0, b"6"), damaged="m.pts"),
    carp("node count 2^64", pts=with_line(CARP_PTS, 0, b"18446744073709551616"), damaged="m.pts"),
    carp("a triangle element", elem=with_line(CARP_ELEM, 1, b"Tr 0 2 4 1")),
    carp("a hexahedron element", elem=with_line(CARP_ELEM, 1, b"Hx 0 2 4 6 1 3 5 0 1")),
    carp("unknown element type", elem=with_line(CARP_ELEM, 1, b"Zz 0 2 4 6 1")),
    carp("a plain line among Tt lines", elem=with_line(CARP_ELEM, 2, b"2 1 4 6 1")),
    carp("node number past the last node", elem=with_line(CARP_ELEM, 1, b"Tt 0 2 4 7 1")),
    carp("node number -1", elem=with_line(CARP_ELEM, 1, b"Tt 0 2 4 -1 1")),
    carp("node number 2^63", elem=with_line(CARP_ELEM, 1, b"Tt 0 2 4 9223372036854775808 1")),
    carp("three node numbers", elem=with_line(CARP_ELEM, 1, b"Tt 0 2 4")),
    carp("a letter for a node number", elem=with_line(CARP_ELEM, 1, b"Tt 0 2 x 6 1")),
    carp("trailing garbage after a number", elem=with_line(CARP_ELEM, 1, b"Tt 0 2 4 6 1;")),
    carp("truncated: last element cut", elem=CARP_ELEM[:-5]),
    vtk("NUL byte in a point", insert_at(UG, line_start(UG, 6) + 1, b"\0")),
    vtk("POINTS count 2^31 - 1", with_line(UG, 4, b"POINTS 2147483647 float")),
    vtk("POINTS count 2^63", with_line(UG, 4, b"POINTS 9223372036854775808 float")),
    vtk("POINTS count one more", with_line(UG, 4, b"POINTS 8 float")),
    vtk("a letter for a coordinate", with_line(UG, 6, b"-50 y 0")),
    vtk("trailing garbage after a number", with_line(UG, 6, b"-50 0 0abc")),
    vtk("CELLS sizes 2^31 - 1", with_line(UG, 12, b"CELLS 2147483647 2147483647")),
    vtk("CELLS count larger than its entries", with_line(UG, 12, b"CELLS 40 40")),
    vtk("CELLS size one short", with_line(UG, 12, b"CELLS 8 39")),
    vtk("cell point count larger than the list", with_line(UG, 20, b"40 0 3 5 6")),
    vtk("cell index past the last point", with_line(UG, 13, b"4 0 2 4 7")),
    vtk("negative cell index", with_line(UG, 13, b"4 0 2 4 -1")),
    vtk("cell index 2^63 - 1 (float-to-integer overflow)", with_line(UG, 13, b"4 0 2 4 9223372036854775807")),
    vtk("cell index 2^53 + 1 (rounded as a double)", with_line(UG, 13, b"4 0 2 4 9007199254740993")),
    vtk("a hexahedron cell", with_line(UG, 22, b"12")),
    vtk("cell type 2^40", with_line(UG, 22, b"1099511627776")),
    vtk("CELL_TYPES count one short", with_line(UG, 21, b"CELL_TYPES 7")),
    vtk("a second POINTS section", UG + b"POINTS 1 float\n0 0 0\n"),
    vtk("a second CELLS section", UG[:line_start(UG, 30)] + b"CELLS 1 5\n4 0 1 2 3\n"),
    vtk("region not an integer", UG.replace(b"LOOKUP_TABLE default\n1\n", b"LOOKUP_TABLE default\n1.5\n")),
    vtk("region array value not a number", UG.replace(b"LOOKUP_TABLE default\n1\n", b"LOOKUP_TABLE default\nx\n")),
    vtk("truncated: in the cell types", UG[:line_start(UG, 25)]),
    vtk("truncated: in the region array", UG[:-4]),
    vtkb("POINTS data cut", UGBH + b"\0" * 30),
    vtkb("CELLS data one int short", UGB[:UGB.index(b"\nCELL_TYPES")] .replace(b"CELLS 8 40", b"CELLS 8 41") +
         UGB[UGB.index(b"\nCELL_TYPES"):]),
    vtkb("NaN coordinate", UGBH + struct.pack(">3f", float("nan"), 0, 0) + UGB[len(UGBH) + 12:]),
    vtkb("64-bit index beyond 2^53", UGBH.replace(b"Version 3.0", b"Version 5.1") +
         b"".join(struct.pack(">3f", *p) for p in VP) + b"\nCELLS 9 32\nOFFSETS vtktypeint64\n" +
         struct.pack(">9q", *range(0, 36, 4)) + b"\nCONNECTIVITY vtktypeint64\n" +
         struct.pack(">32q", *([0, 2, 4, 0x7fffffffffffffff] + [x for t in VT[1:] for x in t])) +
         b"\nCELL_TYPES 8\n" + struct.pack(">8i", *([10] * 8)) + b"\n"),
    vu("NUL byte in the XML", insert_at(VTU_ASCII, 30, b"\0")),
    vu("NumberOfPoints 2^31 - 1", VTU_ASCII.replace(b'NumberOfPoints="7"', b'NumberOfPoints="2147483647"')),
    vu("NumberOfPoints 2^63", VTU_ASCII.replace(b'NumberOfPoints="7"', b'NumberOfPoints="9223372036854775808"')),
    vu("NumberOfCells 2^31 - 1", VTU_ASCII.replace(b'NumberOfCells="8"', b'NumberOfCells="2147483647"')),
    vu("NumberOfCells one fewer (trailing values)", VTU_ASCII.replace(b'NumberOfCells="8"', b'NumberOfCells="7"')),
    vu("connectivity index 2^63 - 1", VTU_ASCII.replace(b"0 2 4 6", b"0 2 4 9223372036854775807", 1)),
    vu("connectivity index past the last point", VTU_ASCII.replace(b"0 2 4 6", b"0 2 4 7", 1)),
    vu("a letter for a coordinate", VTU_ASCII.replace(b"50 0 0", b"50 y 0", 1)),
    vu("base64 cut", VTU_BIN.replace(b"</DataArray>", b"", 1).replace(b"\n<DataArray", b"A</DataArray>\n<DataArray", 1)
       if False else VTU_BIN[:VTU_BIN.index(b"\n</DataArray>") - 8] + VTU_BIN[VTU_BIN.index(b"\n</DataArray>"):], VTU_BIN),
    vu("base64 with a bad character", VTU_BIN.replace(b'format="binary">\n', b'format="binary">\n!', 1), VTU_BIN),
    vu("binary header size 2^32 - 1",
       vtu("binary", raw_override=override("Points", lambda h, d: (struct.pack("<I", 0xFFFFFFFF), d))), VTU_BIN),
    vu("binary header size one short",
       vtu("binary", raw_override=override("types", lambda h, d: (struct.pack("<I", len(d) - 1), d[:-1]))), VTU_BIN),
    vu("zlib block count 2^32 - 1",
       vtu("binary", True, raw_override=override("Points", lambda h, d: (struct.pack("<I", 0xFFFFFFFF) + h[4:], d))),
       VTU_ZLIB),
    vu("zlib block size wrapping 64 bits",
       vtu("binary", True, raw_override=override("connectivity", lambda h, d: (struct.pack("<6I", 3, 0x80000000,
                                                                                            0x80000000, 10, 10, 10), d))),
       VTU_ZLIB),
    vu("zlib compressed size past the data",
       vtu("binary", True, raw_override=override("offsets", lambda h, d: (h[:12] + struct.pack("<I", 100000), d))),
       VTU_ZLIB),
    vu("zlib data damaged",
       vtu("binary", True, raw_override=override("offsets", lambda h, d: (h, d[:4] + bytes(len(d) - 4)))), VTU_ZLIB),
    vu("appended offset past the end", VTU_APP.replace(b'offset="0"', b'offset="99999"', 1), VTU_APP),
    vu("appended data cut", VTU_APP[:VTU_APP.index(b"\n_") + 40], VTU_APP),
    vu("unknown compressor", VTU_ZLIB.replace(b"vtkZLibDataCompressor", b"vtkLZ4DataCompressor"), VTU_ZLIB),
    vu("a hexahedron cell", VTU_ASCII.replace(b"10 10 10 10 10 10 10 10", b"12 10 10 10 10 10 10 10")),
    msh("NUL byte in a node line", insert_at(MSH, line_start(MSH, 14) + 2, b"\0")),
    msh("MSH version 2.2", with_line(MSH, 1, b"2.2 0 8")),
    msh("binary MSH", with_line(MSH, 1, b"4.1 1 8")),
    msh("node count 2^31 - 1", with_line(MSH, 4, b"1 2147483647 1 7")),
    msh("node count 2^63", with_line(MSH, 4, b"1 9223372036854775808 1 7")),
    msh("node block of 2^31 - 1 nodes", with_line(MSH, 5, b"3 1 0 2147483647")),
    msh("node block count 2^31 - 1", with_line(MSH, 4, b"2147483647 7 1 7")),
    msh("a letter for a coordinate", with_line(MSH, 14, b"-50 y 0")),
    msh("trailing garbage after a coordinate", with_line(MSH, 14, b"-50 0 0abc")),
    msh("node tag twice", with_line(MSH, 7, b"1")),
    msh("element count 2^31 - 1", with_line(MSH, 22, b"1 2147483647 1 8")),
    msh("element block of 2^31 - 1 elements", with_line(MSH, 23, b"3 1 4 2147483647")),
    msh("element count one more", with_line(MSH, 22, b"1 9 1 9")),
    msh("element refers to a missing node", with_line(MSH, 24, b"1 1 3 5 8")),
    msh("node tag 2^63", with_line(MSH, 24, b"1 1 3 5 9223372036854775808")),
    msh("three nodes for a tetrahedron", with_line(MSH, 24, b"1 1 3 5")),
    msh("hexahedra in a volume", with_line(MSH, 23, b"3 1 5 8")),
    msh("$EndNodes missing", with_line(MSH, 20, None)),
    msh("a second $Nodes section", MSH + b"\n".join(MSH.split(b"\n")[3:21]) + b"\n"),
    msh("truncated: in the elements", MSH[:line_start(MSH, 28)]),
    msh("truncated: $EndElements missing", MSH[:line_start(MSH, 32)]),
]
