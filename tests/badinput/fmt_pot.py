"""Bad map3d .pot files (one value per node, one frame), read by `thorax series convert`."""
from run import Case

VALUES = [(-2.96 + 0.011 * i) for i in range(352)]
GOOD_POT = b"".join(b"  %10.5f    \n" % v for v in VALUES)
ARGV = ["series", "convert", "s.pot", "-o", "out.txt", "-q"]
L = GOOD_POT.split(b"\n")


def pot(name, data, where=""):
    return Case(".pot (map3d)", name, {"s.pot": data}, ARGV, "out.txt", where=where, good={"s.pot": GOOD_POT},
                force=False)


def line(i, new):
    return b"\n".join(L[:i] + [new] + L[i + 1:])


def nul_at(off):
    return GOOD_POT[:off] + b"\0" + GOOD_POT[off + 1:]


CASES = [
    pot("NUL byte after 11 of 352 values", nul_at(sum(len(x) + 1 for x in L[:11]) + 4),
        where=r"s\.pot:12: NUL byte at byte offset \d+"),
    pot("NUL byte at the start", nul_at(0)),
    pot("NUL byte at the end", GOOD_POT + b"\0"),
    pot("NUL byte inside a number", nul_at(GOOD_POT.index(b".") + 1)),
    pot("a letter for a number", line(5, b"  abc")),
    pot("trailing garbage after a number", line(7, b"  1.25x")),
    pot("two numbers glued by a comma", line(9, b"  1.25,2.5")),
    pot("a value too large for a double", line(3, b"  1e999")),
    pot("a negative value too large", line(3, b"  -1e400")),
    pot("a lone minus sign", line(100, b"  -")),
    pot("a lone decimal point", line(101, b"  .")),
    pot("a lone exponent", line(102, b"  e5")),
    pot("a Fortran D exponent", line(4, b"  1.5D+01")),
    pot("a percent sign", line(6, b"  12%")),
    pot("a comment line", line(8, b"# comment")),
    pot("a header word", b"potentials\n" + GOOD_POT),
    pot("binary garbage", bytes(range(1, 256)) * 2),
    pot("a UTF-8 byte order mark", b"\xef\xbb\xbf" + GOOD_POT),
    pot("a Latin-1 minus", line(10, b"  \xad1.5")),
    pot("empty file", b"", where=r"s\.pot: "),
    pot("only blanks", b"  \n\n \t \n", where=r"s\.pot: "),
    pot("truncated mid-exponent", GOOD_POT[:GOOD_POT.index(b"\n") + 1] + b"  1.5e"),
]
