#!/usr/bin/env python3
"""Keeps only some surfaces of a contours file (format 'thorax-contours 1', docs/formats.md).

Usage: contours_keep.py IN OUT SURFACE...

The header (units, spacing, frame), the named surfaces' 'surface' lines and their loops are kept
in order, every other surface and its loops dropped; a layer left without loops is dropped too.
The sanitized suite (THORAX_QUICK) uses it to mesh the phantom's torso and heart alone where a test
is about something other than the mesh (tests/e2e_outputs.sh): every meshing step still runs, on a
model a third the size. Not a test itself.
"""
import sys


def main():
    if len(sys.argv) < 4:
        print(__doc__)
        return 2
    src, dst, keep = sys.argv[1], sys.argv[2], set(sys.argv[3:])
    lines = open(src).read().split("\n")
    declared = [l.split()[1] for l in lines if l.split()[:1] == ["surface"]]
    missing = keep - set(declared)
    if missing:
        print("contours_keep.py: %s: no surface %s" % (src, ", ".join(sorted(missing))), file=sys.stderr)
        return 1
    out, layer, in_kept_loop = [], None, False
    for l in lines:
        w = l.split()
        if w[:1] == ["surface"] and w[1] not in keep:
            continue
        if w[:1] == ["layer"]:
            layer, in_kept_loop = l, False  # written with its first kept loop
            continue
        if w[:1] == ["loop"]:
            in_kept_loop = w[1] in keep
            if in_kept_loop and layer is not None:
                out.append(layer)
                layer = None
            if not in_kept_loop:
                continue
        elif w[:1] == ["end"]:
            in_kept_loop = False
        elif layer is not None or (w and not in_kept_loop and w[0][:1] in "-.0123456789"):
            continue  # a point of a dropped loop
        out.append(l)
    open(dst, "w").write("\n".join(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
