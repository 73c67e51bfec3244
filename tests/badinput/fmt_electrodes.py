"""Bad thorax electrode files (thorax-electrodes 1), read by `thorax leads SOLUTION --twelve FILE`.

The fixture is the smallest thing `thorax leads` accepts: a model of one octahedron surface
("torso", 6 nodes), a solution naming it with a 6-row torso series, and an output folder."""
from run import Case

MODEL_JSON = (b'{"format": "thorax-model", "version": 1, "units": "mm", "surfaces": [{"name": "torso", '
              b'"role": "outer", "pts": "torso.pts", "fac": "torso.fac", "n_nodes": 6, "n_tris": 8, '
              b'"interior": [0, 0, 0]}]}\n')
FIXTURE = {
    "m/model.json": MODEL_JSON,
    "m/torso.pts": b"1 0 0\n-1 0 0\n0 1 0\n0 -1 0\n0 0 1\n0 0 -1\n",
    "m/torso.fac": b"1 3 5\n3 2 5\n2 4 5\n4 1 5\n3 1 6\n2 3 6\n4 2 6\n1 4 6\n",
    "sol/solution.json": b'{"format": "thorax-solution", "model": "m", "files": {"torso": "torso.txt"}}\n',
    "sol/torso.txt": b"thorax-series 1\nrows 6\nframes 2\nunit mV\n1 2\n3 4\n5 6\n7 8\n9 10\n11 12\nend\n",
    "out/.keep": b"",
}
POS = {1: b"1.000000 0.000000 0.000000", 2: b"-1.000000 0.000000 0.000000", 3: b"0.000000 1.000000 0.000000",
       4: b"0.000000 -1.000000 0.000000", 5: b"0.000000 0.000000 1.000000", 6: b"0.000000 0.000000 -1.000000"}
NAMES = [b"RA", b"LA", b"LL", b"V1", b"V2", b"V3", b"V4", b"V5", b"V6"]
ROWS = [b"%s %d %s" % (n, i % 6 + 1, POS[i % 6 + 1]) for i, n in enumerate(NAMES)]
HEAD = [b"thorax-electrodes 1", b"surface torso", b"count 9"]
GOOD_E = b"\n".join(HEAD + ROWS + [b"end", b""])
# Checks against the model (a node past the surface, a position away from its node, an unknown
# surface) name the file and the electrode: "e.txt: electrode N".
ARGV = ["leads", "sol", "--twelve", "e.txt", "-o", "out", "-q"]


def lines(head=HEAD, rows=ROWS, tail=(b"end", b"")):
    return b"\n".join(list(head) + list(rows) + list(tail))


def row(i, new):
    return lines(rows=ROWS[:i] + [new] + ROWS[i + 1:])


def bad(name, data, where=""):
    files = {"e.txt": data}
    files.update(FIXTURE)
    good = {"e.txt": GOOD_E}
    good.update(FIXTURE)
    return Case("electrodes", name, files, ARGV, "out/ecg12.txt", where=where, good=good, force=False)


NUL_AT = GOOD_E.index(b"V1")
CASES = [
    bad("count 2^31 in a small file", lines(head=HEAD[:2] + [b"count 2147483646"])),
    bad("count overflowing 64 bits", lines(head=HEAD[:2] + [b"count 99999999999999999999999"])),
    bad("count 0", lines(head=HEAD[:2] + [b"count 0"])),
    bad("negative count", lines(head=HEAD[:2] + [b"count -9"])),
    bad("count in hex", lines(head=HEAD[:2] + [b"count 0x9"])),
    bad("NUL byte in a name", GOOD_E[:NUL_AT] + b"\0" + GOOD_E[NUL_AT + 1:], where=r"e\.txt:7: NUL byte at byte offset \d+"),
    bad("NUL byte at the end", GOOD_E + b"\0"),
    bad("truncated: no end line", lines(tail=(b"",))),
    bad("truncated: 8 of 9 electrodes", lines(rows=ROWS[:8], tail=())),
    bad("end after 8 of 9 electrodes", lines(rows=ROWS[:8])),
    bad("more electrode lines than count", lines(rows=ROWS + [b"V7 1 " + POS[1]])),
    bad("text after end", GOOD_E + b"V7 1 " + POS[1] + b"\n"),
    bad("node 0 (nodes are 1-based)", row(0, b"RA 0 " + POS[1])),
    bad("node overflowing 32 bits", row(0, b"RA 4294967297 " + POS[1])),
    bad("node overflowing 64 bits", row(0, b"RA 18446744073709551617 " + POS[1])),
    bad("negative node", row(0, b"RA -1 " + POS[1])),
    bad("fractional node", row(0, b"RA 1.5 " + POS[1])),
    bad("node with a sign", row(0, b"RA +1 " + POS[1])),
    bad("a coordinate missing", row(3, b"V1 4 0 -1")),
    bad("a coordinate too many", row(3, b"V1 4 0 -1 0 7")),
    bad("a letter for a coordinate", row(3, b"V1 4 0 x 0")),
    bad("an infinite coordinate", row(3, b"V1 4 0 inf 0")),
    bad("a coordinate too large for a double", row(3, b"V1 4 0 1e999 0")),
    bad("trailing garbage after a coordinate", row(3, b"V1 4 0 -1 0abc")),
    bad("a duplicate name", row(4, b"V1 5 " + POS[5])),
    bad("a name with a slash", row(4, b"V/2 5 " + POS[5])),
    bad("a keyword as a name", row(4, b"end 5 " + POS[5])),
    bad("count before surface twice", lines(head=HEAD + [b"count 9"])),
    bad("wrong version", lines(head=[b"thorax-electrodes 2"] + HEAD[1:])),
    bad("empty file", b"", where=r"e\.txt:\d+: "),
    bad("a node past the model's surface (6 nodes)", row(0, b"RA 7 " + POS[1]), where=r"e\.txt: electrode 1 "),
    bad("a position 0.5 mm from its node", row(1, b"LA 2 -1.500000 0.000000 0.000000"), where=r"e\.txt: electrode 2 "),
    bad("a surface the model does not have", lines(head=[HEAD[0], b"surface heart", HEAD[2]]),
        where=r"e\.txt: the electrodes' surface \"heart\""),
]
