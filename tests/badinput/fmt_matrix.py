"""Bad plain numeric matrices and CSV (one line per row, one column per frame), read by
`thorax series convert`."""
from run import Case

GOOD = b"# 3 channels x 4 frames\n1 2 3 4\n-1.5 nan 0.25 7\n0 0 0 1e-3\n"
GOOD_CSV = b"lead,0,1,2.5,4\nV1,1,2,3,4\nV2,-1.5,nan,0.25,7\n"
ARGV = ["series", "convert", "s.txt", "-o", "out.raw", "-q"]
CSV_ARGV = ["series", "convert", "s.csv", "-o", "out.raw", "-q"]


def mat(name, data, where=""):
    return Case("matrix (text, CSV)", name, {"s.txt": data}, ARGV, "out.raw", where=where, good={"s.txt": GOOD}, force=False)


def csv(name, data, where=""):
    return Case("matrix (text, CSV)", name, {"s.csv": data}, CSV_ARGV, "out.raw", where=where, good={"s.csv": GOOD_CSV},
                force=False)


CASES = [
    mat("a short row", b"1 2 3 4\n5 6 7\n", where=r"s\.txt:2: row 2 has 3 values, row 1 has 4"),
    mat("a long row", b"1 2 3 4\n5 6 7 8 9\n"),
    mat("a letter for a number", b"1 2 3 4\n5 x 7 8\n", where=r"s\.txt:2: value 2 'x' is not a number"),
    mat("a value too large for a double", b"1 2\n1e999 2\n"),
    mat("two commas (an empty cell)", b"1,2,,4\n", where=r"s\.txt:1: empty cell"),
    mat("a trailing comma", b"1,2,3,\n", where=r"s\.txt:1: the line ends with a comma"),
    mat("a NUL byte", b"1 2 3 4\n5 6\x007 8\n", where=r"s\.txt:2: NUL byte at byte offset 11"),
    mat("an empty file", b"", where=r"s\.txt: "),
    csv("only comments", b"# nothing\n# here\n", where=r"s\.csv: no values"),
    mat("inf in a number", b"1 2\n3 infx\n", where=r"s\.txt:2: value 2 'infx'"),
    mat("a number glued to a word", b"1 2\n3 4abc\n", where=r"s\.txt:2: value 2 '4abc'"),
    mat("a row of fewer values after a blank line", b"1 2 3\n\n4 5\n", where=r"s\.txt:3: row 2 has 2 values"),
    csv("a header time nan", b"lead,0,nan,2\nV1,1,2,3\n", where=r"s\.csv: time of frame 2 is nan"),
    csv("a header with a time too large", b"lead,0,1e999\nV1,1,2\n", where=r"s\.csv:1: header cell 3"),
    csv("two commas in a row", b"lead,0,1\nV1,1,,2\n", where=r"s\.csv:2: empty cell"),
    csv("a header time that is not a number", b"lead,0,x,2\nV1,1,2,3\n", where=r"s\.csv:1: header cell 3 'x'"),
    csv("header times not increasing", b"lead,0,2,1\nV1,1,2,3\n", where=r"s\.csv: time of frame 3"),
    csv("a row with fewer values than times", b"lead,0,1,2\nV1,1,2\n", where=r"s\.csv:2: row 1 has 2 values, the header has 3"),
    csv("a row name and no values", b"lead,0,1\nV1\n", where=r"s\.csv:2: a row name and no values"),
    csv("a header and no rows", b"lead,0,1\n", where=r"s\.csv: no values"),
]
