#!/usr/bin/env python3
# VTK's vtkCameraInterpolator (spline) on the flights of tests/test_camera_path.c, for the comparison in
# docs/decisions.md, "Key-framed camera flights (issue 16)": the 360-degree flight at 800 mm with keys
# every 90 degrees (distance error), a flight over the top, and a 170-degree roll between two keys
# (the roll's largest step per sample against the even one). thorax's figures for the same flights
# are printed by build/tests/test_camera_path. Run: /usr/bin/python3 bench/camera_vtk.py
import vtk, math, numpy as np
def flight(keys, n=200):
    ci = vtk.vtkCameraInterpolator(); ci.SetInterpolationTypeToSpline()
    for t, eye, c, up in keys:
        cam = vtk.vtkCamera(); cam.SetPosition(*eye); cam.SetFocalPoint(*c); cam.SetViewUp(*up); cam.SetViewAngle(30)
        ci.AddCamera(t, cam)
    out = []
    t0, t1 = keys[0][0], keys[-1][0]
    for t in np.linspace(t0, t1, n):
        cam = vtk.vtkCamera(); ci.InterpolateCamera(t, cam)
        out.append((np.array(cam.GetPosition()), np.array(cam.GetFocalPoint()), np.array(cam.GetViewUp())))
    return out
R = 800
circ = [(1 + 12 * k, (R * math.sin(math.radians(a)), -R * math.cos(math.radians(a)), 50), (0, 0, 50), (0, 0, 1)) for k, a in enumerate(range(0, 361, 90))]
o = flight(circ)
print('circle 90-degree keys: VTK distance off by %.2f%%' % (100 * max(abs(math.hypot(p[0], p[1]) - R) / R for p, c, u in o)))
# anterior -> superior -> posterior over the top: up z, then y (looking down), then -z... (up as a user writes it)
over = [(1, (0, 800, 0), (0, 0, 0), (0, 0, 1)), (13, (0, 0, 800), (0, 0, 0), (0, -1, 0)), (25, (0, -800, 0), (0, 0, 0), (0, 0, -1))]
o = flight(over)
ul = [np.linalg.norm(u) for p, c, u in o]
# how square the up is to the view, and its length, as VTK reports it
dots = [abs(np.dot(u / np.linalg.norm(u), (c - p) / np.linalg.norm(c - p))) for p, c, u in o]
print('over the top: VTK view-up length %.3f..%.3f, |cos(up, view)| up to %.3f' % (min(ul), max(ul), max(dots)))
# a roll of 170 degrees about the view axis between two keys
roll = [(1, (0, -800, 0), (0, 0, 0), (0, 0, 1)), (11, (0, -800, 0), (0, 0, 0), (math.sin(math.radians(170)), 0, math.cos(math.radians(170))))]
o = flight(roll)
ul = [np.linalg.norm(u) for p, c, u in o]
ang = [math.degrees(math.atan2(u[0], u[2])) for p, c, u in o]
print('roll 170 degrees: VTK view-up length min %.3f; roll angle steps max %.2f deg per 1/20 frame (even: %.2f)' % (min(ul), max(abs(np.diff(ang))), 170 / 199))
