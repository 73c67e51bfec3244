"""Bad map3d .channels files (read by `thorax series convert REC --channels FILE -o OUT`) and bad
.leadlinks files (read by `thorax leads MODEL --data SERIES --array FILE -o DIR`).

The .channels fixture: a 4-channel, 2-frame text recording and a map of 3 nodes. The .leadlinks
fixture: the one-octahedron model of fmt_electrodes (6 nodes) and a 6-row series on it."""
from run import Case
import fmt_electrodes as E

REC = b"thorax-series 1\nrows 4\nframes 2\nunit uV\n1 2\n3 4\n5 6\n7 8\nend\n"
GOOD_C = b"3 leads\n 1 4\n 2 2\n 3 1\n"
C_ARGV = ["series", "convert", "rec.txt", "--channels", "m.channels", "-o", "out.txt", "-q"]


def bad_c(name, data, where=""):
    files = {"m.channels": data, "rec.txt": REC}
    return Case(".channels (map3d)", name, files, C_ARGV, "out.txt", where=where,
                good={"m.channels": GOOD_C, "rec.txt": REC}, force=False)


FIXTURE_L = {k: v for k, v in E.FIXTURE.items() if k.startswith("m/")}
FIXTURE_L["d.txt"] = b"thorax-series 1\nrows 6\nframes 2\nunit mV\n1 2\n3 4\n5 6\n7 8\n9 10\n11 12\nend\n"
GOOD_L = b"2 leads\n  1 5\n  V1 2\n"
L_ARGV = ["leads", "m", "--data", "d.txt", "--array", "a.leadlinks", "-o", "out", "-q"]


def bad_l(name, data, where=""):
    files = {"a.leadlinks": data}
    files.update(FIXTURE_L)
    good = {"a.leadlinks": GOOD_L}
    good.update(FIXTURE_L)
    return Case(".leadlinks (map3d)", name, files, L_ARGV, "out/array.txt", where=where, good=good, force=False)


CASES = [
    bad_c("empty file", b""),
    bad_c("no count", b"leads\n 1 4\n"),
    bad_c("count 0", b"0 leads\n"),
    bad_c("count overflowing 64 bits", b"99999999999999999999999 leads\n 1 4\n"),
    bad_c("count more than the file holds", b"2147483647 leads\n 1 4\n"),
    bad_c("truncated: 2 of 3 lines", b"3 leads\n 1 4\n 2 2\n"),
    bad_c("a node twice", b"3 leads\n 1 4\n 1 2\n 3 1\n"),
    bad_c("a node beyond the count", b"3 leads\n 1 4\n 2 2\n 4 1\n"),
    bad_c("node 0", b"3 leads\n 0 4\n 2 2\n 3 1\n"),
    bad_c("a letter for a channel", b"3 leads\n 1 4\n 2 x\n 3 1\n"),
    bad_c("a third field", b"3 leads\n 1 4 9\n 2 2\n 3 1\n"),
    bad_c("a channel overflowing 32 bits", b"3 leads\n 1 4294967297\n 2 2\n 3 1\n"),
    bad_c("text after the lines", GOOD_C + b" 4 3\n"),
    bad_c("NUL byte", GOOD_C[:12] + b"\0" + GOOD_C[13:]),
    bad_c("a channel beyond the recording (4 rows)", b"3 leads\n 1 4\n 2 5\n 3 1\n"),
    bad_c("negative count", b"-3 leads\n 1 4\n 2 2\n 3 1\n"),
    bad_c("count in hex", b"0x3 leads\n 1 4\n 2 2\n 3 1\n"),
    bad_c("a third field on the count line", b"3 leads more\n 1 4\n 2 2\n 3 1\n"),
    bad_c("a fractional node", b"3 leads\n 1.5 4\n 2 2\n 3 1\n"),
    bad_c("lines ended by CR alone", GOOD_C.replace(b"\n", b"\r")),
    bad_l("empty file", b"", where=r"a\.leadlinks:\d+: "),
    bad_l("no count", b"leads\n  1 5\n  V1 2\n"),
    bad_l("count 0", b"0 leads\n"),
    bad_l("count overflowing 64 bits", b"99999999999999999999999 leads\n  1 5\n"),
    bad_l("count more than the file holds", b"2147483647 leads\n  1 5\n"),
    bad_l("a node overflowing 32 bits", b"2 leads\n  1 5\n  V1 4294967297\n"),
    bad_l("a fractional node", b"2 leads\n  1 5\n  V1 2.5\n"),
    bad_l("a third field", b"2 leads\n  1 5\n  V1 2 7\n"),
    bad_l("a label of 40 characters", b"2 leads\n  1 5\n  " + b"L" * 40 + b" 2\n"),
    bad_l("a node in hex", b"2 leads\n  1 5\n  V1 0x2\n"),
    bad_l("lines ended by CR alone", GOOD_L.replace(b"\n", b"\r")),
    bad_l("truncated: 1 of 2 lines", b"2 leads\n  1 5\n"),
    bad_l("a node past the surface (6 nodes)", b"2 leads\n  1 5\n  V1 7\n"),
    bad_l("a negative node (map3d's unlinked lead)", b"2 leads\n  1 5\n  V1 -1\n"),
    bad_l("a label twice", b"2 leads\n  1 5\n  1 2\n"),
    bad_l("a label with a slash", b"2 leads\n  1 5\n  V/1 2\n"),
    bad_l("a keyword as a label", b"2 leads\n  1 5\n  end 2\n"),
    bad_l("a letter for a node", b"2 leads\n  1 5\n  V1 x\n"),
    bad_l("text after the lines", GOOD_L + b"  V2 3\n"),
    bad_l("NUL byte", GOOD_L[:10] + b"\0" + GOOD_L[11:]),
]
