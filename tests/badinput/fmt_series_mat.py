"""Bad MATLAB .mat series (MATLAB 5 files built byte by byte here), read by `thorax series convert`."""
import struct
import zlib

from run import Case


def el(t, data, small_ok=False):
    """A MATLAB 5 element: tag + data + padding to 8 bytes (small form when asked and data <= 4 bytes)."""
    if small_ok and len(data) <= 4:
        return struct.pack("<HH", t, len(data)) + data.ljust(4, b"\0")
    pad = (-len(data)) % 8
    return struct.pack("<II", t, len(data)) + data + b"\0" * pad


def matrix(name, cls, dims, body, flags=0, dtype_dims=5, raw_size=None, nzmax=0):
    """A miMATRIX element of class cls with the given dims and the sub-elements in body."""
    inner = el(6, struct.pack("<II", cls | flags, nzmax)) + el(dtype_dims, struct.pack("<%di" % len(dims), *dims))
    inner += el(1, name.encode())
    inner += body
    return struct.pack("<II", 14, raw_size if raw_size is not None else len(inner)) + inner


def double(name, rows, cols, values, dims=None):
    return matrix(name, 6, dims or [rows, cols], el(9, struct.pack("<%dd" % len(values), *values)))


def chars(name, text):
    return matrix(name, 4, [1, len(text)], el(4, text.encode("utf-16-le")))


def header(version=0x0100, mark=b"IM"):
    return b"MATLAB 5.0 MAT-file, made by fmt_series_mat.py".ljust(116) + b"\0" * 8 + struct.pack("<H", version) + mark


def compressed(var):
    z = zlib.compress(var, 9)
    return struct.pack("<II", 15, len(z)) + z


POTVALS = double("potvals", 3, 4, [float(i) for i in range(12)])
TIME = double("time", 1, 4, [0.0, 1.0, 2.0, 3.0])
META = chars("unit", "mV") + chars("time_unit", "ms") + chars("label", "a test series")
GOOD_MAT = header() + POTVALS + TIME + META
ARGV = ["series", "convert", "s.mat", "-o", "out.txt", "-q"]
AT = r"s\.mat: (variable \d+ \('[^']*', at byte offset \d+|byte offset \d+)"


def bad(name, data, where=AT):
    return Case("series .mat", name, {"s.mat": data}, ARGV, "out.txt", where=where, good={"s.mat": GOOD_MAT},
                force=False)


def nest(depth):
    v = double("x", 1, 1, [1.0])
    for _ in range(depth):
        v = matrix("c", 1, [1, 1], v)
    return v


def struct_var(name, dims, fields, children):
    flen = 8
    body = el(5, struct.pack("<i", flen), small_ok=True) + el(1, b"".join(f.encode().ljust(flen, b"\0") for f in fields))
    return matrix(name, 2, dims, body + b"".join(children))


ZEROS = matrix("potvals", 6, [1, 16000000], el(2, bytes(16000000)))
CASES = [
    bad("potvals claims 100000 x 100000 over 12 values",
        header() + double("potvals", 3, 4, [float(i) for i in range(12)], dims=[100000, 100000]) + TIME + META),
    bad("time claims 10^9 frames", header() + POTVALS + double("time", 1, 4, [0.0, 1, 2, 3], dims=[1, 10 ** 9]) + META),
    bad("a cell claiming 10^9 cells", GOOD_MAT + matrix("c", 1, [1, 10 ** 9], b"")),
    bad("a struct claiming 2^40 fields", GOOD_MAT + struct_var("s", [1 << 20, 1 << 20], ["potvals"], [])),
    bad("dimensions multiplying past 2^64", GOOD_MAT + matrix("big", 6, [2 ** 31 - 1] * 4, el(9, b""))),
    bad("cut in half (time, unit, label lost)", GOOD_MAT[:len(GOOD_MAT) // 2]),
    bad("last variable cut by 4 bytes", GOOD_MAT[:-4]),
    bad("cut inside the header", GOOD_MAT[:100]),
    bad("header only", header(), where=r"s\.mat: byte offset 128: "),
    bad("5 stray bytes at the end", GOOD_MAT + b"\1\2\3\4\5"),
    bad("16 garbage bytes at the end", GOOD_MAT + b"\x55" * 16),
    bad("a variable claiming more bytes than the file", GOOD_MAT + struct.pack("<II", 14, 10 ** 6) + bytes(16)),
    bad("values fewer than the dimensions need", header() + matrix("potvals", 6, [3, 4], el(9, bytes(88))) + TIME + META),
    bad("a negative dimension", header() + double("potvals", 3, 4, [0.0] * 12, dims=[-3, -4]) + TIME + META),
    bad("one dimension only", header() + double("potvals", 12, 1, [0.0] * 12, dims=[12]) + TIME + META),
    bad("array flags of the wrong type", header() + POTVALS.replace(struct.pack("<II", 6, 8), struct.pack("<II", 5, 8), 1) +
        TIME + META),
    bad("unknown array class 99", GOOD_MAT + matrix("u", 99, [1, 1], b"")),
    bad("a MATLAB object (class 3)", GOOD_MAT + matrix("o", 3, [1, 1], b"")),
    bad("a function handle (class 16)", GOOD_MAT + matrix("f", 16, [1, 1], b"")),
    bad("cells nested 40 deep", GOOD_MAT + nest(40)),
    bad("unit of 2 characters holding 3", header() + POTVALS + TIME + matrix("unit", 4, [1, 2], el(4, "mV!".encode("utf-16-le")))),
    bad("a sparse matrix with a short column index", GOOD_MAT + matrix("sp", 5, [2, 2], el(5, struct.pack("<i", 0)) +
        el(5, struct.pack("<ii", 0, 1)) + el(9, struct.pack("<d", 1.0)), nzmax=1)),
    bad("zlib bomb: 16 KB inflating to 16e6 uint8 zeros (128 MB of doubles)", header() + compressed(ZEROS)),
    bad("a compressed variable cut short", header() + compressed(POTVALS)[:-6] + compressed(TIME)),
    bad("a compressed size past the end of the file", header() + struct.pack("<II", 15, 5000) + zlib.compress(POTVALS)),
    bad("compressed bytes that are not zlib", header() + struct.pack("<II", 15, 64) + bytes(range(64))),
    bad("compressed data going on after its variable", header() + compressed(POTVALS + TIME)),
    bad("MATLAB v7.3 (HDF5) header", header(version=0x0200) + POTVALS, where=r"s\.mat: byte offset 124: "),
    bad("a damaged byte order mark", header(mark=b"XY") + POTVALS, where=r"s\.mat: byte offset 126: "),
    bad("element of type miDOUBLE at the top level", header() + el(9, struct.pack("<d", 1.0)) + POTVALS),
]
