#!/usr/bin/env python3
"""OpenCV's intelligent scissors (cv2.segmentation.IntelligentScissorsMB: Mortensen & Barrett's
livewire, zero-crossing, gradient magnitude and direction costs, the paper's weights 0.43/0.43/0.14)
timed on the same synthetic 512 x 512 torso-like plane bench/livewire.c times ours on (an ellipse
400 x 300 px, blurred, with an inner ellipse, uniform noise of 30), so that bench/digitize.sh prints the
two side by side. OpenCV takes an 8-bit image (the plane scaled to 0..255); buildMap(seed) runs
Dijkstra over the whole plane (no search on the fly), getContour(target) reads a path off the map.
Prints the median of RUNS runs in milliseconds (wall clock). Timing only."""
import math
import sys
import time

import cv2
import numpy as np

runs = int(sys.argv[1]) if len(sys.argv) > 1 else 15
W = H = 512
cx, cy, A, B = 256, 250, 200, 150
b, a = np.mgrid[0:H, 0:W].astype(np.float64)
q = np.sqrt(((a - cx) / A) ** 2 + ((b - cy) / B) ** 2)
erf = np.vectorize(math.erf)
val = 600 * 0.5 * (1 + erf((1 - q) * 170 / 2.0))
val -= np.where(q < 0.9, 250 * 0.5 * (1 + erf((0.9 - q) * 170 / 2.0)), 0)
rng = np.random.default_rng(1)
val += 30 * (rng.random((H, W)) - 0.5)
img = np.clip((val - val.min()) / (val.max() - val.min()) * 255, 0, 255).astype(np.uint8)

seed = (int(cx + A), int(cy))
sixth = (int(cx + A * math.cos(math.pi / 3)), int(cy + B * math.sin(math.pi / 3)))
half = (int(cx - A), int(cy))
tc, tb, t6, t2 = [], [], [], []
n6 = n2 = 0
for r in range(runs):
    t0 = time.perf_counter()
    tool = cv2.segmentation.IntelligentScissorsMB()
    tool.setEdgeFeatureZeroCrossingParameters(0)
    tool.setGradientMagnitudeMaxLimit(200)
    tool.applyImage(img)
    t1 = time.perf_counter()
    tool.buildMap(seed)
    t2a = time.perf_counter()
    c6 = tool.getContour(sixth)
    t3 = time.perf_counter()
    c2 = tool.getContour(half)
    t4 = time.perf_counter()
    tc.append(t1 - t0)
    tb.append(t2a - t1)
    t6.append(t3 - t2a)
    t2.append(t4 - t3)
    n6, n2 = len(c6), len(c2)
med = lambda x: 1e3 * sorted(x)[len(x) // 2]
print("opencv %s intelligent scissors on a 512 x 512 plane, median of %d runs (ms, wall clock):" % (cv2.__version__, runs))
print("  plane features (applyImage, once per plane)   %8.2f" % med(tc))
print("  seed (buildMap: the whole plane)              %8.2f" % med(tb))
print("  path, a sixth of the outline (getContour)     %8.2f  (%d points)" % (med(t6), n6))
print("  path, half the outline (getContour)           %8.2f  (%d points)" % (med(t2), n2))
print("  seed + path, a sixth of the outline           %8.2f" % (med(tb) + med(t6)))
