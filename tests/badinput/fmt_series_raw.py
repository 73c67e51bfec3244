"""Bad thorax raw series (THXSER01 header + little-endian float64), read by `thorax series convert`."""
import struct

from run import Case

ROWS, FRAMES = 3, 4


def raw(rows=ROWS, frames=FRAMES, magic=b"THXSER01", unit=b"mV", tunit=b"ms", label=b"test", times=None, vals=None):
    h = magic + struct.pack("<QQ", rows, frames)
    h += unit.ljust(32, b"\0")[:32] + tunit.ljust(16, b"\0")[:16] + label.ljust(128, b"\0")[:128]
    times = times if times is not None else [float(f) for f in range(frames)]
    vals = vals if vals is not None else [float(i) for i in range(rows * frames)]
    return h + struct.pack("<%dd" % len(times), *times) + struct.pack("<%dd" % len(vals), *vals)


GOOD_RAW = raw()
ARGV = ["series", "convert", "s.raw", "-o", "out.txt", "-q"]
AT = r"s\.raw: (byte offset \d+|bytes \d+-\d+): "


def bad(name, data, where=AT):
    return Case("series raw", name, {"s.raw": data}, ARGV, "out.txt", where=where, good={"s.raw": GOOD_RAW},
                force=False)


def patch(off, b):
    return GOOD_RAW[:off] + b + GOOD_RAW[off + len(b):]


CASES = [
    bad("claims 2^40 rows in a 328-byte file", patch(8, struct.pack("<Q", 1 << 40))),
    bad("claims 2^40 frames", patch(16, struct.pack("<Q", 1 << 40))),
    bad("claims 2^64-1 rows (size overflow)", patch(8, struct.pack("<Q", 2 ** 64 - 1))),
    bad("rows x frames overflow 64 bits", patch(8, struct.pack("<QQ", 2 ** 32, 2 ** 32))),
    bad("zero rows", patch(8, struct.pack("<Q", 0))),
    bad("zero frames", patch(16, struct.pack("<Q", 0))),
    bad("one row more than the data", patch(8, struct.pack("<Q", ROWS + 1))),
    bad("truncated: last value cut", GOOD_RAW[:-3]),
    bad("truncated: cut in half", GOOD_RAW[:len(GOOD_RAW) // 2]),
    bad("truncated inside the header", GOOD_RAW[:100]),
    bad("header only", GOOD_RAW[:200]),
    bad("one trailing byte", GOOD_RAW + b"\0"),
    bad("trailing garbage", GOOD_RAW + b"garbage!"),
    bad("wrong magic", patch(0, b"HELLOSER")),
    bad("unsupported version", patch(6, b"02")),
    bad("unit without NUL", patch(24, b"u" * 32)),
    bad("time_unit without NUL", patch(56, b"t" * 16)),
    bad("label without NUL", patch(72, b"l" * 128)),
    bad("time axis not increasing", raw(times=[0.0, 1.0, 1.0, 2.0])),
    bad("time axis decreasing", raw(times=[3.0, 2.0, 1.0, 0.0])),
    bad("NaN time", raw(times=[0.0, float("nan"), 2.0, 3.0])),
    bad("infinite time", raw(times=[0.0, 1.0, 2.0, float("inf")])),
    bad("a PNG renamed .raw (no magic)", b"\x89PNG\r\n\x1a\n" + bytes(200)),
    bad("empty file", b"", where=r"s\.raw: byte offset 0: "),
]
