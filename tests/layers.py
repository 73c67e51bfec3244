#!/usr/bin/env python3
"""The library's layers (docs/decisions.md, "One direction"): a module uses only modules below it.

    level 0  core
    level 1  model, parallel, web (the web page's blobs and file: quantization, deflate, base64)
    level 2  geom, io, image, leads
    level 3  mesh, check, digitizer (tracing on image planes: livewire, threshold regions, snap,
             interpolation; uses image and geom)
    level 4  fem, bem, render, phantom, import, edit, inverse
    level 5  raytrace (RaySpray: render's scenes traced with Embree)
    level 6  picture (a picture's settings and data -> scenes and annotations; render and view share it),
             capi (flat accessors for bindings: python/thorax over libthorax.so)
    level 7  view (the interactive viewer, GTK 4)
    level 8  cli

A module may use itself and any module of a lower level, never a sibling or a module above.
Within io, the same rule one floor down (docs/design/io.md, "io by family"): src/io/ is split by
family, each a folder, and a family uses only itself, io common and the families below it:

    io level 0  common   private headers several families share (text scanning, integers, text helpers)
    io level 1  map3d    map3d/CVRTI/SCIRun files: graphicsio (.geom, .tsdf), .pts/.fac, channels, lmarks
    io level 2  surface, volume, series, export   readers of surfaces, volume meshes; time series; exports
    io level 3  model    thorax's own files: model directory, volume mesh, contours, solution, electrodes, dipoles

Checked three ways, each failing with the file and what it uses:
  includes  every #include "thorax/M/..." in src/X/ and include/thorax/X/ (and a private header
            "M/..." of src/M/ is used only inside src/M/; a private header "io/F/..." of an io family
            only inside src/io/F/, unless F is common; every file of src/io/ is in a known family);
  headers   every public header is include/thorax/M/NAME.h of a known module M, and each function
            it declares is defined in src/M/ (header names match their modules);
  calls     with --build BUILD: every thx_ symbol an object file of src/X/ needs (nm -u) is
            defined in src/X/ or a module below it; within io, every symbol (thx_ or a family's
            own, e.g. series_read_pot) an object of src/io/F/ needs from another io object is
            defined in F or a family below F.
Usage: layers.py SRC [--build BUILD]     exit 0 when all hold, 1 with the violations listed;
       layers.py --self-test             the checker on made-up trees with planted violations.
"""
import os
import re
import shutil
import subprocess
import sys
import tempfile

LEVEL = {"core": 0, "model": 1, "parallel": 1, "web": 1, "geom": 2, "io": 2, "image": 2, "leads": 2, "mesh": 3, "check": 3, "digitizer": 3,
         "fem": 4, "bem": 4, "render": 4, "phantom": 4, "import": 4, "edit": 4, "inverse": 4, "field": 4, "raytrace": 5, "picture": 6, "capi": 6, "view": 7, "cli": 8}


IO_LEVEL = {"common": 0, "map3d": 1, "surface": 2, "volume": 2, "series": 2, "export": 2, "model": 3}


def allowed(user, used):
    return user == used or LEVEL[used] < LEVEL[user]


def io_allowed(user, used):
    return user == used or IO_LEVEL[used] < IO_LEVEL[user]


def io_family(rel):
    """The io family of a path src/io/F/... (None outside src/io/; "" for a file directly in src/io/)."""
    parts = rel.replace(os.sep, "/").split("/")
    if parts[:2] != ["src", "io"]:
        return None
    return parts[2] if len(parts) > 3 else ""


def strip_comments(text):
    text = re.sub(r"/\*.*?\*/", lambda m: "\n" * m.group(0).count("\n"), text, flags=re.S)
    return re.sub(r"//[^\n]*", "", text)


def sources(root):
    """(module, path) of every .c/.cc/.h under src/ and include/thorax/."""
    out = []
    for base in ("src", os.path.join("include", "thorax")):
        top = os.path.join(root, base)
        if not os.path.isdir(top):
            continue
        for mod in sorted(os.listdir(top)):
            d = os.path.join(top, mod)
            if not os.path.isdir(d):
                out.append((None, os.path.join(base, mod)))
                continue
            for dirpath, _, files in os.walk(d):
                for f in sorted(files):
                    if f.endswith((".c", ".cc", ".h")):
                        out.append((mod, os.path.relpath(os.path.join(dirpath, f), root)))
    return out


def check_includes(root, files):
    bad = []
    inc = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)
    for mod, rel in files:
        if mod is None:
            bad.append(f"{rel}: a header outside include/thorax/MODULE/ (which module is it?)")
            continue
        if mod not in LEVEL:
            bad.append(f"{rel}: '{mod}' is not a module of the layer table (tests/layers.py)")
            continue
        fam = io_family(rel)
        if fam is not None and fam not in IO_LEVEL:
            bad.append(f"{rel}: '{fam or 'src/io/'}' is not an io family of the table (tests/layers.py, IO_LEVEL)"
                       if fam else f"{rel}: a file directly in src/io/, not in a family folder (tests/layers.py, IO_LEVEL)")
            continue
        text = strip_comments(open(os.path.join(root, rel), errors="replace").read())
        for m in inc.finditer(text):
            name = m.group(1)
            line = text.count("\n", 0, m.start()) + 1
            parts = name.split("/")
            if parts[0] == "thorax":
                used = parts[1] if len(parts) == 3 else None
                if used not in LEVEL:
                    bad.append(f"{rel}:{line}: includes {name}, not a header of a module (thorax/MODULE/NAME.h)")
                elif not allowed(mod, used):
                    bad.append(f"{rel}:{line}: {mod} (level {LEVEL[mod]}) includes {name} of {used} "
                               f"(level {LEVEL[used]}): against the direction")
            elif len(parts) >= 2 and parts[0] in LEVEL and parts[0] != mod:
                bad.append(f"{rel}:{line}: {mod} includes {name}, a private header of {parts[0]}")
            elif parts[0] == "io" and mod == "io":
                used = parts[1] if len(parts) == 3 else None
                if used not in IO_LEVEL:
                    bad.append(f"{rel}:{line}: includes {name}, not a header of an io family (io/FAMILY/NAME.h)")
                elif used != fam and used != "common":
                    bad.append(f"{rel}:{line}: io family {fam} includes {name}, a private header of io family "
                               f"{used} (only io/common/ headers are shared)")
    return bad


def declared(header_text):
    """Function names a header declares (prototypes ending in ';', outside inline bodies)."""
    text = strip_comments(header_text)
    text = re.sub(r"^\s*#.*$", "", text, flags=re.M)
    # drop bodies of inline functions and struct/enum braces
    depth, flat = 0, []
    for ch in text:
        if ch == "{":
            depth += 1
            continue
        if ch == "}":
            depth -= 1
            flat.append(";")
            continue
        if depth == 0:
            flat.append(ch)
    names = set()
    for stmt in "".join(flat).split(";"):
        if "typedef" in stmt or "(" not in stmt:
            continue
        m = re.search(r"\b(thx_\w+)\s*\(", stmt)
        if m and "static" not in stmt.split(m.group(1))[0]:
            names.add(m.group(1))
    return names


_NM = {}


def nm(obj, flag):
    """`nm FLAG obj`'s lines (flag: "-u" or "--defined-only", the latter with -g). Asked for one object,
    it runs nm once over every object in the same directory tree not yet read (one process, not one per
    object: the tree has about 350) and keeps the answers."""
    key = (obj, flag)
    if key not in _NM:
        cut = obj.find(".dir" + os.sep)
        top = obj[:cut + 4] if cut >= 0 else os.path.dirname(obj)
        objs = sorted(os.path.join(d, f) for d, _, fs in os.walk(top) for f in fs
                      if f.endswith(".o") and (os.path.join(d, f), flag) not in _NM)
        args = ["nm", "-g", "--defined-only"] if flag == "--defined-only" else ["nm", "-u"]
        for k in range(0, len(objs), 200):
            chunk = objs[k:k + 200]
            r = subprocess.run(args + chunk, capture_output=True, text=True)
            cur = None
            lines = {o: [] for o in chunk}
            for ln in r.stdout.splitlines():
                if ln.endswith(":") and ln[:-1] in lines:
                    cur = ln[:-1]
                elif cur is not None and ln.strip():
                    lines[cur].append(ln)
            if len(chunk) == 1:  # nm names no file when given one
                lines[chunk[0]] = [ln for ln in r.stdout.splitlines() if ln.strip()]
            for o in chunk:
                _NM[(o, flag)] = lines[o]
        _NM.setdefault(key, [])
    return _NM[key]


def defined_symbols(root, build):
    """symbol -> module, from the library's object files."""
    objdir = os.path.join(build, "CMakeFiles", "thorax.dir", "src")
    out = {}
    for mod, obj in objects(objdir, root):
        for ln in nm(obj, "--defined-only"):
            p = ln.split()
            if len(p) == 3 and p[2].startswith("thx_"):
                out[p[2]] = mod
    return out


def objects(objdir, root):
    """(module, object) of the objects whose source is in the tree (a moved file leaves a stale one)."""
    res = []
    if not os.path.isdir(objdir):
        return res
    for mod in sorted(os.listdir(objdir)):
        for dirpath, _, files in os.walk(os.path.join(objdir, mod)):
            for f in sorted(files):
                src = os.path.join(root, "src", os.path.relpath(os.path.join(dirpath, f[:-2]), objdir))
                if f.endswith(".o") and os.path.exists(src):
                    res.append((mod, os.path.join(dirpath, f)))
    return res


def check_headers(root, files, defs):
    bad = []
    for mod, rel in files:
        if mod is None or not rel.startswith("include") or mod not in LEVEL:
            continue
        for name in sorted(declared(open(os.path.join(root, rel)).read())):
            where = defs.get(name)
            if where is None:
                continue  # declared, not (yet) defined: the linker's business
            if where != mod:
                bad.append(f"{rel}: declares {name}, which src/{where}/ defines (a header belongs to its module)")
    return bad


def check_calls(root, build, defs):
    bad = []
    objdirs = [(os.path.join(build, "CMakeFiles", "thorax.dir", "src"), None),
               (os.path.join(build, "CMakeFiles", "thorax_petsc.dir", "src"), None),
               (os.path.join(build, "CMakeFiles", "thorax_view.dir", "src"), "view"),
               (os.path.join(build, "CMakeFiles", "thorax_cli.dir", "src"), "cli")]
    for objdir, force in objdirs:
        for mod, obj in objects(objdir, root):
            mod = force or mod
            if mod not in LEVEL:
                bad.append(f"{obj}: object of an unknown module '{mod}'")
                continue
            for ln in nm(obj, "-u"):
                sym = ln.split()[-1]
                used = defs.get(sym)
                if used and not allowed(mod, used):
                    src = os.path.relpath(obj, objdir).replace(".o", "")
                    bad.append(f"src/{src}: {mod} (level {LEVEL[mod]}) calls {sym} of {used} "
                               f"(level {LEVEL[used]}): against the direction")
    return bad


def check_io_calls(root, build):
    """Within io: an object of family F needs from another io object only symbols of F or a family below."""
    objdir = os.path.join(build, "CMakeFiles", "thorax.dir", "src")
    objs = [o for m, o in objects(objdir, root) if m == "io"]
    fam_of = lambda obj: os.path.relpath(obj, os.path.join(objdir, "io")).split(os.sep)[0]
    defs = {}
    for obj in objs:
        for ln in nm(obj, "--defined-only"):
            p = ln.split()
            if len(p) == 3:
                defs[p[2]] = fam_of(obj)
    bad = []
    for obj in objs:
        fam = fam_of(obj)
        if fam not in IO_LEVEL:
            continue  # named by check_includes
        for ln in nm(obj, "-u"):
            sym = ln.split()[-1]
            used = defs.get(sym)
            if used in IO_LEVEL and not io_allowed(fam, used):
                src = os.path.relpath(obj, objdir).replace(".o", "")
                bad.append(f"src/{src}: io family {fam} (io level {IO_LEVEL[fam]}) calls {sym} of io family "
                           f"{used} (io level {IO_LEVEL[used]}): against the direction")
    return bad


def run(root, build):
    files = sources(root)
    bad = check_includes(root, files)
    ncalls = 0
    if build:
        defs = defined_symbols(root, build)
        if not defs:
            bad.append(f"{build}: no object files of the library (build it first)")
        bad += check_headers(root, files, defs)
        calls = check_calls(root, build, defs) + check_io_calls(root, build)
        ncalls = len(defs)
        bad += calls
    return files, bad, ncalls


def self_test():
    """Planted violations must each be found; a clean tree must pass."""
    tmp = tempfile.mkdtemp(prefix="thorax-layers.")
    try:
        def put(rel, text):
            p = os.path.join(tmp, rel)
            os.makedirs(os.path.dirname(p), exist_ok=True)
            open(p, "w").write(text)
        put("include/thorax/model/a.h", "#include \"thorax/core/core.h\"\nint thx_a(void);\n")
        put("include/thorax/geom/g.h", "#include \"thorax/model/a.h\"\nint thx_g(void);\n")
        put("src/model/a.c", "#include \"thorax/model/a.h\"\nint thx_a(void) { return 1; }\n")
        put("src/geom/g.c", "#include \"thorax/geom/g.h\"\n/* #include \"thorax/mesh/m.h\" in a comment */\n")
        put("src/io/common/t.h", "int t;\n")
        put("src/io/series/s.c", "#include \"io/common/t.h\"\n#include \"io/series/impl.h\"\n")
        put("src/io/series/impl.h", "int u;\n")
        _, bad, _ = run(tmp, None)
        ok = not bad
        cases = [
            ("src/model/b.c", "#include \"thorax/geom/g.h\"\n", "model (level 1) includes thorax/geom/g.h"),
            ("src/geom/h.c", "#include \"thorax/io/x.h\"\n", "geom (level 2) includes thorax/io/x.h"),
            ("src/mesh/m.c", "#include \"check/private.h\"\n", "a private header of check"),
            ("include/thorax/stray.h", "int thx_s(void);\n", "outside include/thorax/MODULE/"),
            ("src/viewer/v.c", "int v;\n", "'viewer' is not a module"),
            ("src/io/surface/s.c", "#include \"io/series/series_impl.h\"\n",
             "io family surface includes io/series/series_impl.h, a private header of io family series"),
            ("src/io/stray.c", "int s;\n", "a file directly in src/io/"),
            ("src/io/images/i.c", "int i;\n", "'images' is not an io family"),
            ("src/mesh/n.c", "#include \"io/common/parse_uint.h\"\n", "mesh includes io/common/parse_uint.h, a private header of io"),
        ]
        for rel, text, want in cases:
            put(rel, text)
            _, bad, _ = run(tmp, None)
            found = any(want in b for b in bad)
            print(f"self-test: {rel}: {'found' if found else 'MISSED'} ({want})")
            ok &= found
            os.remove(os.path.join(tmp, rel))
        # calls within io, on object files compiled here: down is allowed, up and sideways are not
        objdir = os.path.join(tmp, "build", "CMakeFiles", "thorax.dir", "src")
        def obj(rel, text):
            put(rel, text)
            o = os.path.join(objdir, rel[len("src/"):] + ".o")
            os.makedirs(os.path.dirname(o), exist_ok=True)
            subprocess.run(["cc", "-c", "-o", o, os.path.join(tmp, rel)], check=True)
        obj("src/io/map3d/m.c", "int thx_m(void) { return 1; }\n")
        obj("src/io/surface/s.c", "int thx_m(void);\nint surface_s(void) { return thx_m(); }\n")
        good = check_io_calls(tmp, os.path.join(tmp, "build"))
        print(f"self-test: io calls down (surface -> map3d): {'passed' if not good else good}")
        ok &= not good
        for rel, text, want in [
            ("src/io/map3d/up.c", "int surface_s(void);\nint thx_u(void) { return surface_s(); }\n",
             "io family map3d (io level 1) calls surface_s of io family surface"),
            ("src/io/series/side.c", "int surface_s(void);\nint thx_v(void) { return surface_s(); }\n",
             "io family series (io level 2) calls surface_s of io family surface"),
        ]:
            obj(rel, text)
            found = any(want in b for b in check_io_calls(tmp, os.path.join(tmp, "build")))
            print(f"self-test: {rel}: {'found' if found else 'MISSED'} ({want})")
            ok &= found
            os.remove(os.path.join(tmp, rel))
        decl = declared("/* thx_c(void); */\ntypedef int (*thx_fn)(int);\nstatic inline int thx_i(void) { return thx_j(); }\n"
                        "thx_status thx_d(thx_ctx *ctx,\n    int x);\nvoid thx_e(void);\n")
        print(f"self-test: declared names {sorted(decl)}")
        ok &= decl == {"thx_d", "thx_e"}
        return ok
    finally:
        shutil.rmtree(tmp)


def main():
    args = sys.argv[1:]
    if args == ["--self-test"]:
        ok = self_test()
        print("self-test: " + ("passed" if ok else "FAILED"))
        return 0 if ok else 1
    if not args:
        print(__doc__)
        return 2
    root = args[0]
    build = args[args.index("--build") + 1] if "--build" in args else None
    files, bad, nsym = run(root, build)
    for b in bad:
        print("layers: " + b)
    mods = sorted({m for m, _ in files if m}, key=lambda m: (LEVEL.get(m, 99), m))
    print(f"layers: {len(files)} files in {len(mods)} modules ({', '.join(mods)})"
          + (f", {nsym} library symbols" if build else "") + f": {len(bad)} violation(s)")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
