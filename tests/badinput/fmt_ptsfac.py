"""Bad .pts/.fac pairs (map3d/SCIRun), read by `thorax import`."""
from run import Case

PTS = b"1 0 0\n-1 0 0\n0 1 0\n0 -1 0\n0 0 1\n0 0 -1\n"
FAC = b"1 3 5\n3 2 5\n2 4 5\n4 1 5\n3 1 6\n2 3 6\n4 2 6\n1 4 6\n"
ARGV = ["import", "-o", "m", "s.pts", "--name", "torso", "--role", "outer", "-q"]
GOOD = {"s.pts": PTS, "s.fac": FAC}


def pts(name, data, where=""):
    return Case(".pts/.fac", name, {"s.pts": data, "s.fac": FAC}, ARGV, "m", where=where, good=GOOD)


def fac(name, data, where=""):
    return Case(".pts/.fac", name, {"s.fac": data, "s.pts": PTS}, ARGV, "m", where=where, good=GOOD)


L = PTS.split(b"\n")
F = FAC.split(b"\n")
CASES = [
    pts("NUL byte at a line start", PTS[:12] + b"\0" + PTS[12:]),
    pts("NUL byte inside a number", PTS[:2] + b"\0" + PTS[2:]),
    pts("two coordinates on a line", b"\n".join(L[:2] + [b"0 1"] + L[3:])),
    pts("four coordinates on a line", b"\n".join(L[:2] + [b"0 1 0 7"] + L[3:])),
    pts("a letter for a number", b"\n".join(L[:3] + [b"0 x 0"] + L[4:])),
    pts("NaN coordinate", b"\n".join(L[:3] + [b"0 nan 0"] + L[4:])),
    pts("infinite coordinate", b"\n".join(L[:3] + [b"0 inf 0"] + L[4:])),
    pts("overflowing coordinate 1e999", b"\n".join(L[:3] + [b"0 1e999 0"] + L[4:])),
    pts("trailing garbage after a number", b"\n".join(L[:1] + [b"-1 0 0abc"] + L[2:])),
    pts("truncated: last line cut mid-number", PTS[:-4]),
    pts("truncated: nodes missing", b"\n".join(L[:4]) + b"\n", where=r"s\.fac:\d+: .*out of range"),
    pts("empty file", b"", where=r"s\.pts: "),
    pts("only blank lines", b"\n\n  \n", where=r"s\.pts: "),
    pts("binary garbage", bytes(range(1, 200)), where=r"s\.pts(:\d+)?: "),
    fac("NUL byte in a line", FAC[:6] + b"\0" + FAC[6:]),
    fac("two node numbers on a line", b"\n".join(F[:1] + [b"3 2"] + F[2:])),
    fac("four node numbers on a line", b"\n".join(F[:1] + [b"3 2 5 1"] + F[2:])),
    fac("node number 0 in a 1-based file", b"\n".join(F[:1] + [b"3 0 5"] + F[2:])),
    fac("node number past the last node", b"\n".join(F[:1] + [b"3 7 5"] + F[2:])),
    fac("negative node number", b"\n".join(F[:1] + [b"3 -2 5"] + F[2:])),
    fac("node number overflowing 64 bits", b"\n".join(F[:1] + [b"3 99999999999999999999 5"] + F[2:])),
    fac("node number 2^31", b"\n".join(F[:1] + [b"3 2147483648 5"] + F[2:])),
    fac("fractional node number", b"\n".join(F[:1] + [b"3 2.5 5"] + F[2:])),
    fac("hex node number", b"\n".join(F[:1] + [b"3 0x2 5"] + F[2:])),
    fac("trailing garbage after a node number", b"\n".join(F[:1] + [b"3 2 5;"] + F[2:])),
    fac("truncated: last triangle cut", FAC[:-4]),
]
