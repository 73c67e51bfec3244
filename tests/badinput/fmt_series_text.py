"""Bad thorax text series (thorax-series 1), read by `thorax series convert`."""
from run import Case

GOOD_TXT = (b"thorax-series 1\nrows 3\nframes 4\nunit mV\ntime_unit ms\nlabel a test series\n"
            b"t0 0\ndt 1\n1 2 3 4\n-1.5 nan 0.25 7\n0 0 0 1e-3\nend\n")
ARGV = ["series", "convert", "s.txt", "-o", "out.raw", "-q"]


def txt(name, data, where=""):
    return Case("series text", name, {"s.txt": data}, ARGV, "out.raw", where=where, good={"s.txt": GOOD_TXT},
                force=False)


L = GOOD_TXT.split(b"\n")


def with_line(i, new):
    return b"\n".join(L[:i] + [new] + L[i + 1:])


CASES = [
    txt("claims 5e8 frames in 48 bytes", b"thorax-series 1\nrows 1\nframes 500000000\n0 0\nend\n",
        where=r"s\.txt:3: 'frames 500000000': a file of 48 bytes"),
    txt("claims 2^62 rows", with_line(1, b"rows 4611686018427387904"), where=r"s\.txt:2: "),
    txt("rows x frames beyond the file", with_line(1, b"rows 20"), where=r"s\.txt:9: .*cannot be in a file"),
    txt("rows overflowing 64 bits", with_line(1, b"rows 99999999999999999999999")),
    txt("negative frames", with_line(2, b"frames -4")),
    txt("rows 0", with_line(1, b"rows 0")),
    txt("NUL byte in a value", GOOD_TXT[:GOOD_TXT.index(b"-1.5") + 2] + b"\0" + GOOD_TXT[GOOD_TXT.index(b"-1.5") + 2:],
        where=r"s\.txt:10: NUL byte at byte offset \d+"),
    txt("NUL byte at a line start", GOOD_TXT[:GOOD_TXT.index(b"0 0 0")] + b"\0" + GOOD_TXT[GOOD_TXT.index(b"0 0 0"):]),
    txt("truncated: no end line", GOOD_TXT[:-4]),
    txt("truncated: a row missing", b"\n".join(L[:10] + [b""])),
    txt("truncated: cut mid-row", GOOD_TXT[:GOOD_TXT.index(b"0 0 0") + 3]),
    txt("text after end", GOOD_TXT + b"5 6 7 8\n"),
    txt("a row with too few values", with_line(9, b"-1.5 nan 0.25")),
    txt("a row with too many values", with_line(9, b"-1.5 nan 0.25 7 8")),
    txt("a letter for a number", with_line(9, b"-1.5 x 0.25 7")),
    txt("trailing garbage after a number", with_line(9, b"-1.5 nan 0.25 7abc")),
    txt("a value too large for a double", with_line(9, b"-1.5 1e999 0.25 7")),
    txt("end before the last row", with_line(10, b"end")),
    txt("unknown keyword", with_line(4, b"time_units ms")),
    txt("rows given twice", with_line(4, b"rows 3")),
    txt("dt zero", with_line(7, b"dt 0")),
    txt("t0 without dt", b"\n".join(L[:7] + L[8:])),
    txt("time axis not increasing", b"\n".join(L[:6] + [b"time 0 1 1 2"] + L[8:])),
    txt("time axis with 3 of 4 times", b"\n".join(L[:6] + [b"time 0 1 2"] + L[8:])),
    txt("unit of two words", with_line(3, b"unit m V")),
    txt("label longer than 127 bytes", with_line(5, b"label " + b"x" * 200)),
    txt("wrong version", with_line(0, b"thorax-series 2")),
    txt("not a series (contours header)", with_line(0, b"thorax-contours 1")),
    txt("empty file", b"", where=r"s\.txt: "),
    txt("binary garbage", bytes(range(1, 256)) * 3),
]
