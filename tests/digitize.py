#!/usr/bin/python3
"""Makes hand-digitized-like contours from exact ones (issue 11 item 6: "inevitably jagged"
hand-digitized points, paper 3.1).

usage: digitize.py IN.txt OUT.txt [--jitter MM] [--seed N] [--every MM]
  --jitter MM  move every point by a random offset of length up to MM, uniform over the disc
               of that radius (default 0.5)
  --every MM   first thin every loop to points about MM apart along it (a sparse polygon,
               as digitized by hand at a coarse step; default: keep every point)
  --seed N     random seed (default 1): the same arguments give the same file
Lines other than points are copied as they are; a loop keeps at least 3 points.
"""
import math
import random
import sys


def main():
    a = sys.argv[1:]
    if len(a) < 2:
        print(__doc__)
        return 2
    src, dst = a[0], a[1]
    opt = {a[i]: float(a[i + 1]) for i in range(2, len(a), 2)}
    jitter = opt.get("--jitter", 0.5)
    every = opt.get("--every", 0.0)
    rng = random.Random(int(opt.get("--seed", 1)))
    out, loop = [], None

    def flush():
        if loop is None:
            return
        pts = loop
        if every > 0 and len(pts) > 3:
            kept, acc = [pts[0]], 0.0
            for i in range(1, len(pts)):
                acc += math.dist(pts[i], pts[i - 1])
                if acc >= every:
                    kept.append(pts[i])
                    acc = 0.0
            pts = kept if len(kept) >= 3 else [pts[0], pts[len(pts) // 3], pts[2 * len(pts) // 3]]
        for x, y in pts:
            r, t = jitter * math.sqrt(rng.random()), 2 * math.pi * rng.random()
            out.append("%.6f %.6f" % (x + r * math.cos(t), y + r * math.sin(t)))

    for line in open(src).read().split("\n"):
        f = line.split()
        if len(f) == 2 and f[0][0] in "0123456789+-.":
            loop.append((float(f[0]), float(f[1])))
            continue
        flush()
        loop = [] if f and f[0] == "loop" else None
        out.append(line)
    flush()
    open(dst, "w").write("\n".join(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
