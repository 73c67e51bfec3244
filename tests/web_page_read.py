#!/usr/bin/python3
"""Reads a page of `thorax export --format html` with Python alone (html.parser, base64, zlib, numpy):
an independent decoder of docs/design/web.md's "The page's data, version 1".

    web_page_read.py PAGE.html [SURFACE=SERIES ...] [--leads SERIES] [--max-mb MB]

Checks the page's structure (the description first, blobs 0..n-1 in order, each blob's size after
inflating as data-bytes says and as its type and count say, the viewer's script last), decodes every
surface's potentials (frame deltas undone) and compares them with the series given (a thorax raw
series, THXSER01, rows the surface's nodes): every decoded value within the page's max_error of the
series', NaN where the series has NaN. --leads: the page's leads against that series (float32). Prints
one line of figures per surface; exit 1 with the reason on the first fault.
"""
import base64
import html.parser
import json
import sys
import zlib

import numpy as np

TYPES = {"float32": "<f4", "float64": "<f8", "uint32": "<u4", "uint16": "<u2", "uint8": "u1"}


def fail(msg):
    print("web_page_read: FAIL: " + msg, file=sys.stderr)
    sys.exit(1)


class Page(html.parser.HTMLParser):
    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.scripts = []  # (attrs, text)
        self.cur = None
        self.title = None
        self.in_title = False

    def handle_starttag(self, tag, attrs):
        if tag == "script":
            self.cur = [dict(attrs), []]
        elif tag == "title":
            self.in_title = True

    def handle_endtag(self, tag):
        if tag == "script" and self.cur is not None:
            self.scripts.append((self.cur[0], "".join(self.cur[1])))
            self.cur = None
        elif tag == "title":
            self.in_title = False

    def handle_data(self, data):
        if self.cur is not None:
            self.cur[1].append(data)
        elif self.in_title:
            self.title = (self.title or "") + data


def read_series(path):
    b = open(path, "rb").read()
    if b[:8] != b"THXSER01":
        fail(path + ": not a thorax raw series")
    n, m = (int(x) for x in np.frombuffer(b[8:24], "<u8"))
    return np.frombuffer(b[200 + 8 * m:], "<f8").reshape(m, n)


def main():
    args = sys.argv[1:]
    page_path, compare, leads_path, max_mb = args[0], {}, None, None
    i = 1
    while i < len(args):
        if args[i] == "--leads":
            leads_path = args[i + 1]
            i += 2
        elif args[i] == "--max-mb":
            max_mb = float(args[i + 1])
            i += 2
        else:
            k, v = args[i].split("=", 1)
            compare[k] = v
            i += 1
    raw = open(page_path, "rb").read()
    if max_mb is not None and len(raw) > max_mb * 1e6:
        fail("%s: %.2f MB, more than %.2f MB" % (page_path, len(raw) / 1e6, max_mb))
    p = Page()
    p.feed(raw.decode("utf-8"))
    s = p.scripts
    if len(s) < 2 or s[0][0].get("id") != "thorax-page" or s[0][0].get("type") != "application/json":
        fail("the description is not the first script")
    meta = json.loads(s[0][1])
    if meta.get("format") != "thorax-page" or meta.get("version") != 1:
        fail("not a version 1 page")
    blobs = []
    for k, (attrs, text) in enumerate(s[1:-1]):
        if attrs.get("id") != "thorax-blob-%d" % k or attrs.get("type") != "application/octet-stream":
            fail("script %d is not blob %d" % (k + 1, k))
        data = base64.b64decode(text, validate=True)
        if attrs["data-compression"] == "deflate-raw":
            d = zlib.decompressobj(-15)
            data = d.decompress(data) + d.flush()
            if not d.eof or d.unused_data:
                fail("blob %d: not one whole raw deflate stream" % k)
        elif attrs["data-compression"] != "none":
            fail("blob %d: compression %s" % (k, attrs["data-compression"]))
        if len(data) != int(attrs["data-bytes"]):
            fail("blob %d: %d bytes, data-bytes says %s" % (k, len(data), attrs["data-bytes"]))
        spec = meta["blobs"][k]
        a = np.frombuffer(data, TYPES[spec["type"]])
        if a.size != spec["count"]:
            fail("blob %d: %d %s, the description says %d" % (k, a.size, spec["type"], spec["count"]))
        blobs.append(a)
    if len(blobs) != len(meta["blobs"]):
        fail("%d blobs, the description lists %d" % (len(blobs), len(meta["blobs"])))
    if s[-1][0] or len(s[-1][1]) < 1000:
        fail("the last script is not the viewer")
    if p.title != meta["title"]:
        fail("title %r, the description's %r" % (p.title, meta["title"]))
    M = meta["frames"]
    if len(meta["time"]) != M:
        fail("%d times for %d frames" % (len(meta["time"]), M))
    cm = meta["colormaps"][0]
    if blobs[cm["blob"]].size != 3 * cm["n"]:
        fail("the colour map's table")
    worst = 0.0
    for surf in meta["surfaces"]:
        N, T = surf["nodes"], surf["triangles"]
        pts, tri, nrm = blobs[surf["points"]], blobs[surf["indices"]], blobs[surf["normals"]]
        if pts.size != 3 * N or tri.size != 3 * T or nrm.size != 3 * N or (T and tri.max() >= N):
            fail("surface %s: geometry sizes" % surf["name"])
        if not np.allclose(np.linalg.norm(nrm.reshape(-1, 3), axis=1), 1, atol=1e-5):
            fail("surface %s: normals not unit" % surf["name"])
        d = surf["data"]
        line = "%s: %d nodes, %d triangles" % (surf["name"], N, T)
        if d:
            Ms = 1 if surf.get("layer") else M  # a layer's data: the one frame it was made for
            codes = blobs[d["values"]].reshape(Ms, N).astype(np.uint32)
            codes = (np.cumsum(codes, axis=0) % 65536).astype(np.uint16)  # frame deltas undone
            v = d["origin"] + codes.astype(np.float64) * d["step"]
            v[codes == 65535] = np.nan
            bound = d["max_error"]
            if abs(bound - d["step"] / 2) > 1e-15 * max(1, abs(bound)):
                fail("surface %s: max_error is not half a step" % surf["name"])
            K, F = d["knots_n"], d["scale"]["frames"]
            kn = blobs[d["knots"]]
            if kn.size != 2 * K * F or F not in (1, Ms):
                fail("surface %s: knots" % surf["name"])
            for f in range(F):
                kv = kn[2 * K * f: 2 * K * f + K]
                if np.any(np.diff(kv) <= 0):
                    fail("surface %s: knots not ascending" % surf["name"])
            line += ", %d frame%s, step %.4g %s, bound %.4g" % (Ms, "s" if Ms > 1 else " (a layer)", d["step"], meta["unit"], bound)
            if surf["name"] in compare:
                ref = read_series(compare.pop(surf["name"]))
                if ref.shape != v.shape:
                    fail("surface %s: %s values, the series %s" % (surf["name"], v.shape, ref.shape))
                if np.any(np.isnan(ref) != np.isnan(v)):
                    fail("surface %s: NaN where the series has none, or the other way" % surf["name"])
                ok = ~np.isnan(ref)
                err = float(np.max(np.abs(v[ok] - ref[ok]))) if ok.any() else 0.0
                if err > bound * (1 + 1e-9) + 1e-300:
                    fail("surface %s: decoded values %g from the series, more than the bound %g" % (surf["name"], err, bound))
                worst = max(worst, err)
                line += ", decoded within %.4g of the series (%.3f of the bound)" % (err, err / bound if bound else 0)
        print(line)
    for k, pl in enumerate(meta.get("planes", [])):
        if blobs[pl["texels"]].size != 4 * pl["w"] * pl["h"]:
            fail("plane %d: %d texel bytes for %d x %d" % (k, blobs[pl["texels"]].size, pl["w"], pl["h"]))
        print("plane %d: %d x %d texels" % (k, pl["w"], pl["h"]))
    if compare:
        fail("no data on surface(s) %s in the page" % ", ".join(compare))
    if leads_path:
        L = meta["leads"]
        if not L:
            fail("the page has no leads")
        ref = read_series(leads_path)  # frames x leads
        got = blobs[L["values"]].reshape(len(L["names"]), M).T
        err = float(np.nanmax(np.abs(got - ref) / np.maximum(1e-3, np.nanmax(np.abs(ref)))))
        if got.shape != ref.shape or err > 1e-6:
            fail("the leads differ from %s (relative %g)" % (leads_path, err))
        print("leads: %s, the same as %s to %.2g (float32)" % (" ".join(L["names"]), leads_path, err))
    print("page: %.3f MB, %d frames, %d surfaces, %d blobs, %d electrodes; largest decoding error %.4g %s (the bound %.4g)"
          % (len(raw) / 1e6, M, len(meta["surfaces"]), len(blobs), len(meta["electrodes"]), worst, meta["unit"],
             meta["quantization"]["max_error"]))


main()
