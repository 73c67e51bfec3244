"""Bad model.json manifests (a model directory: model.json beside valid surface files), read by
`thorax export` (any command that reads a model reads it through thx_model_read). Each message
names m/model.json and the key (JSON has no useful line for most damages: the key, the surface
and its number are the position)."""
import json

from run import Case

BOX_PTS = b"".join(b"%d %d %d\n" % (x, y, z) for z in (0, 20) for y in (0, 20) for x in (0, 20))
BOX_FAC = b"1 3 4\n1 4 2\n5 6 8\n5 8 7\n1 2 6\n1 6 5\n3 7 8\n3 8 4\n1 5 7\n1 7 3\n2 4 8\n2 8 6\n"
HEART_PTS = b"5 5 5\n15 5 5\n5 15 5\n5 5 15\n"
HEART_FAC = b"1 3 2\n1 2 4\n2 3 4\n1 4 3\n"
BASE = {
    "format": "thorax-model", "version": 1, "units": "mm",
    "surfaces": [
        {"name": "box", "role": "outer", "pts": "box.pts", "fac": "box.fac", "n_nodes": 8, "n_tris": 12,
         "interior": [10, 10, 10]},
        {"name": "heart", "role": "heart", "pts": "heart.pts", "fac": "heart.fac", "n_nodes": 4, "n_tris": 4},
    ],
    "frame": {"superior": "+z", "anterior": "+y", "left": "-x"},
    "provenance": {"program": "fmt_model.py"},
}
ARGV = ["export", "m", "--format", "obj", "-o", "out", "-q"]
SURF = {"m/box.pts": BOX_PTS, "m/box.fac": BOX_FAC, "m/heart.pts": HEART_PTS, "m/heart.fac": HEART_FAC}


def files(text):
    f = {"m/model.json": text}
    f.update(SURF)
    return f


GOOD = files(json.dumps(BASE, indent=1).encode())


def raw(name, text, where):
    return Case("model.json", name, files(text), ARGV, "out", where=r"m/model\.json(:\d+)?: " + where, good=GOOD,
                force=False)


def edit(name, fn, where):
    m = json.loads(json.dumps(BASE))
    fn(m)
    return raw(name, json.dumps(m, indent=1).encode(), where)


def setk(path, value):
    def f(m):
        o = m
        for k in path[:-1]:
            o = o[k]
        o[path[-1]] = value
    return f


def delk(path):
    def f(m):
        o = m
        for k in path[:-1]:
            o = o[k]
        del o[path[-1]]
    return f


TEXT = json.dumps(BASE, indent=1).encode()
S0 = ["surfaces", 0]
CASES = [
    raw("NUL byte inside", TEXT[:40] + b"\0" + TEXT[40:], r"NUL byte at byte offset 40"),
    raw("NUL byte after the object", TEXT + b"\0junk", r"NUL byte at byte offset"),
    raw("trailing garbage after the object", TEXT + b"\n{}\n", r"not valid JSON"),
    raw("truncated: cut in half", TEXT[: len(TEXT) // 2], r"not valid JSON"),
    raw("empty file", b"", r"not valid JSON"),
    raw("not an object (an array)", b"[1, 2]\n", r"not a JSON object"),
    raw("nested 2000 deep", b"[" * 2000 + b"]" * 2000, r"not valid JSON"),
    raw("a key given twice (units)", TEXT.replace(b'"units": "mm",', b'"units": "mm", "units": "m",'),
        r'key "units" appears twice'),
    edit("unknown key (misspelt frame)", lambda m: m.update(fram=m.pop("frame")), r'unknown key "fram"'),
    edit("format of another program", setk(["format"], "vtk"), r'"format"'),
    edit("version 2", setk(["version"], 2), r'"version": model format version 2'),
    edit("version as a string", setk(["version"], "1"), r'"version" missing or not a number'),
    edit("units in metres", setk(["units"], "m"), r'"units"'),
    edit("surfaces not an array", setk(["surfaces"], {"box": 1}), r'"surfaces"'),
    edit("surface entry not an object", setk(["surfaces", 1], "heart"), r'surface 2: not a JSON object'),
    edit("surface name missing", delk(S0 + ["name"]), r'surface 1: "name"'),
    edit("surface name with a slash", setk(S0 + ["name"], "../box"), r'surface 1: "name"'),
    edit("surface named model.json", setk(S0 + ["name"], "model.json"), r'surface 1: "name"'),
    edit("unknown surface key (interiour)", lambda m: m["surfaces"][0].update(interiour=[1, 2, 3]),
         r'surface 1 \("box"\): unknown key "interiour"'),
    raw("a surface key given twice (n_nodes)", TEXT.replace(b'"n_nodes": 8,', b'"n_nodes": 8, "n_nodes": 9,'),
        r'surface 1 \("box"\): key "n_nodes" appears twice'),
    edit("unknown role", setk(S0 + ["role"], "liver"), r'surface 1 \("box"\): "role" missing or unknown \("liver"\)'),
    edit("pts outside the model directory", setk(S0 + ["pts"], "../box.pts"), r'surface 1 \("box"\): "pts"'),
    edit("fac not a string", setk(S0 + ["fac"], 3), r'surface 1 \("box"\): "pts" and "fac"'),
    edit("negative node count", setk(S0 + ["n_nodes"], -8), r'surface 1 \("box"\): "n_nodes"'),
    edit("fractional node count", setk(S0 + ["n_nodes"], 8.5), r'surface 1 \("box"\): "n_nodes"'),
    edit("node count as a string", setk(S0 + ["n_nodes"], "8"), r'surface 1 \("box"\): "n_nodes"'),
    edit("node count 1e300", setk(S0 + ["n_nodes"], 1e300), r'surface 1 \("box"\): "n_nodes"'),
    edit("node count not the file's", setk(S0 + ["n_nodes"], 9), r'surface "box": manifest says 9 nodes \("n_nodes"\)'),
    edit("triangle count not the file's", setk(["surfaces", 1, "n_tris"], 3),
         r'surface "heart": manifest says 3 triangles \("n_tris"\)'),
    edit("interior with two values", setk(S0 + ["interior"], [1, 2]), r'surface 1 \("box"\): "interior"'),
    edit("interior as text", setk(S0 + ["interior"], "10 10 10"), r'surface 1 \("box"\): "interior"'),
    edit("two surfaces of one name", setk(["surfaces", 1, "name"], "box"), r'surface 2 \("box"\): a surface of that name'),
    edit("frame axis not an axis", setk(["frame", "superior"], "+w"), r'"frame"\."superior" is not an axis'),
    edit("frame axis as a number", setk(["frame", "anterior"], 2), r'"frame"\."anterior" must be a string'),
    edit("frame without anterior", delk(["frame", "anterior"]), r'"frame"\."anterior" missing'),
    edit("frame superior and anterior on one axis", setk(["frame", "anterior"], "-z"), r'"frame": "superior" and "anterior"'),
    edit("frame left-handed", setk(["frame", "left"], "+x"), r'"frame"\."left" is \+x but superior x anterior is -x'),
    edit("frame unknown key (right)", lambda m: m["frame"].update(right="+x"), r'"frame": unknown key "right"'),
    edit("frame not an object", setk(["frame"], "+z +y"), r'"frame" must be an object'),
    edit("provenance not an object", setk(["provenance"], "fmt_model.py"), r'"provenance" must be an object'),
    edit("volume with an unknown key", setk(["volume"], {"pts": "volume.pts", "tets": "volume.tet"}),
         r'"volume": unknown key "tets"'),
    edit("volume count as a string", setk(["volume"], {"pts": "volume.pts", "tet": "volume.tet", "n_nodes": "18"}),
         r'"volume"\."n_nodes" must be a count'),
]
