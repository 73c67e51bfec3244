#!/usr/bin/env python3
"""The peer of bench/trace.sh's volume rendering: VTK 9's unstructured-grid ray caster
(vtkUnstructuredGridVolumeRayCastMapper, Bunyk's) on the tetrahedral mesh and potential thorax
exported (thorax export --solution --format vtu): the first .vtu of DIR, its point-data array
"potential" (else its first), an N x N offscreen window, a colour ramp cool-warm and an opacity
clear at zero and opaque at the extremes (as thorax's default). Prints the first render (the
mapper's setup included) and the median of the next 3, in ms, wall clock; writes
DIR/vtk_volume.png.
Usage: vtk_volume.py DIR [N]"""
import glob
import os
import sys
import time

import vtk

d = sys.argv[1]
n = int(sys.argv[2]) if len(sys.argv) > 2 else 1024
files = sorted(glob.glob(os.path.join(d, '**', '*.vtu'), recursive=True))
if not files:
    sys.exit('no .vtu in %s' % d)
r = vtk.vtkXMLUnstructuredGridReader()
r.SetFileName(files[0])
r.Update()
g = r.GetOutput()
pd = g.GetPointData()
arr = pd.GetArray('potential')  # not the node tables (surface, surface_node)
if arr is None:
    arr = pd.GetArray(0)
if arr is None:
    sys.exit('no point data in %s' % files[0])
g.GetPointData().SetActiveScalars(arr.GetName())
lo, hi = arr.GetRange()
m = max(abs(lo), abs(hi)) or 1
ctf = vtk.vtkColorTransferFunction()
ctf.AddRGBPoint(-m, 0.23, 0.30, 0.75)
ctf.AddRGBPoint(0, 0.87, 0.87, 0.87)
ctf.AddRGBPoint(m, 0.71, 0.02, 0.15)
otf = vtk.vtkPiecewiseFunction()
otf.AddPoint(-m, 1.0)
otf.AddPoint(0, 0.0)
otf.AddPoint(m, 1.0)
prop = vtk.vtkVolumeProperty()
prop.SetColor(ctf)
prop.SetScalarOpacity(otf)
prop.SetScalarOpacityUnitDistance(50.0)
tri = vtk.vtkDataSetTriangleFilter()
tri.SetInputData(g)
tri.Update()
mapper = vtk.vtkUnstructuredGridVolumeRayCastMapper()
mapper.SetInputConnection(tri.GetOutputPort())
vol = vtk.vtkVolume()
vol.SetMapper(mapper)
vol.SetProperty(prop)
ren = vtk.vtkRenderer()
ren.AddVolume(vol)
ren.SetBackground(0.09, 0.09, 0.11)
win = vtk.vtkRenderWindow()
win.SetOffScreenRendering(1)
win.AddRenderer(ren)
win.SetSize(n, n)
# thorax's anterior view: from +y (anterior), superior (+z) up
b = g.GetBounds()
c = [(b[0] + b[1]) / 2, (b[2] + b[3]) / 2, (b[4] + b[5]) / 2]
cam = ren.GetActiveCamera()
cam.SetFocalPoint(*c)
cam.SetPosition(c[0], c[1] + 4 * (b[3] - b[2] + b[5] - b[4]), c[2])
cam.SetViewUp(0, 0, 1)
ren.ResetCamera()
t0 = time.perf_counter()
win.Render()
first = time.perf_counter() - t0
times = []
for k in range(3):
    ren.GetActiveCamera().Azimuth(0.5)
    t0 = time.perf_counter()
    win.Render()
    times.append(time.perf_counter() - t0)
times.sort()
w2i = vtk.vtkWindowToImageFilter()
w2i.SetInput(win)
w2i.Update()
png = vtk.vtkPNGWriter()
png.SetFileName(os.path.join(d, 'vtk_volume.png'))
png.SetInputConnection(w2i.GetOutputPort())
png.Write()
print('vtkUnstructuredGridVolumeRayCastMapper, %d tetrahedra, point data "%s", %dx%d: first %.0f ms, then median %.0f ms' % (
    tri.GetOutput().GetNumberOfCells(), arr.GetName(), n, n, 1000 * first, 1000 * times[1]))
