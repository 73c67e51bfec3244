#!/usr/bin/env python3
"""The peer's frame time for the interactive viewer (issue 13): VTK 9 (Debian's python3-vtk9) draws
the scene `thorax view` will draw — the phantom's torso and heart surfaces with per-node potentials
coloured (Gouraud, colours interpolated per pixel, a symmetric blue-white-red map) — in an on-screen
window, and measures:

  (a) rotate:     the camera turned 360 degrees about the view-up axis in 1-degree steps, one
                  Render() (and glFinish) a step: the mean time per frame;
  (b) frame-step: the scalars of both surfaces replaced by the next frame of the potentials each
                  step, then Render(): the mean time per step, over every frame of the series;
  (c) peak memory of the process (getrusage: Python and VTK's libraries included).

Run under Xvfb so that Mesa's llvmpipe draws (the GL renderer string is printed, and a warning if it
is not llvmpipe):

  xvfb-run -a -s '-screen 0 1400x900x24' python3 bench/vtk_view.py [--model DIR --solution DIR]

With --solution (a `thorax forward` output directory: torso.raw, and solution.json naming the model
and the heart's potentials) and --model, those files are drawn; without them the inputs are made
first in a temporary directory under /tmp (removed at the end; --keep keeps it) with the thorax CLI
($THORAX, else build/bin/thorax): phantom --resolution high, surfaces, mesh --no-heart, electrodes,
beat --frames 300, forward. The last line is the result, in a fixed format that bench/view.sh reads:

  vtk: rotate 12.3 ms/frame (81 fps), frame-step 20.1 ms (50 /s), peak 210 MB, llvmpipe (LLVM 15.0.6, 256 bits)
"""
import argparse
import json
import os
import resource
import shutil
import struct
import subprocess
import sys
import tempfile
import time

try:
    import numpy as np
    import vtk
    from vtk.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray, vtk_to_numpy
except ImportError:
    # Debian's python3-vtk9 and numpy are the system Python's: a `python3` found first on PATH
    # (pyenv, a virtual environment) may not have them
    if os.path.realpath(sys.executable) != os.path.realpath('/usr/bin/python3') and os.path.exists('/usr/bin/python3'):
        os.execv('/usr/bin/python3', ['/usr/bin/python3', *sys.argv])
    raise


def read_raw(path):
    """A thorax raw series (docs/formats.md): frames x rows float64, and the time axis."""
    b = open(path, 'rb').read()
    if b[:8] != b'THXSER01':
        sys.exit(f'vtk_view: {path}: not a thorax raw series')
    rows, frames = struct.unpack('<QQ', b[8:24])
    if len(b) != 200 + 8 * frames * (rows + 1):
        sys.exit(f'vtk_view: {path}: {len(b)} bytes, expected {200 + 8 * frames * (rows + 1)}')
    a = np.frombuffer(b, dtype='<f8', offset=200)
    return a[frames:].reshape(frames, rows), a[:frames]


def read_surface(model, name):
    """NAME.pts (x y z a line) and NAME.fac (1-based) of a model directory."""
    pts = np.loadtxt(os.path.join(model, name + '.pts'), ndmin=2)
    tri = np.loadtxt(os.path.join(model, name + '.fac'), dtype=np.int64, ndmin=2) - 1
    if tri.min() < 0 or tri.max() >= len(pts):
        sys.exit(f'vtk_view: {model}/{name}.fac: node numbers out of 1..{len(pts)}')
    return pts, tri


def make_inputs(work, thorax, frames):
    """The high-resolution phantom, its volume mesh and a forward solution of `frames` frames."""
    def run(*args):
        t0 = time.perf_counter()
        subprocess.run([thorax, *args, '-q'], check=True)
        print(f'  thorax {args[0]}: {time.perf_counter() - t0:.1f} s', flush=True)
    print(f'inputs: made in {work} with {thorax}', flush=True)
    run('phantom', '--resolution', 'high', '--seed', '1', '-o', f'{work}/c.txt')
    run('surfaces', f'{work}/c.txt', '-o', f'{work}/m')
    run('mesh', f'{work}/m', '--no-heart')
    run('electrodes', f'{work}/m')
    run('beat', f'{work}/m', '-o', f'{work}/beat.raw', '--frames', str(frames))
    run('forward', f'{work}/m', '--epicardial', f'{work}/beat.raw', '-o', f'{work}/sol')
    return f'{work}/m', f'{work}/sol'


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    ap.add_argument('--model', help='model directory (torso.pts/.fac, heart.pts/.fac)')
    ap.add_argument('--solution', help='thorax forward output directory (torso.raw, solution.json)')
    ap.add_argument('--torso', default='torso', help='name of the outer surface (default torso)')
    ap.add_argument('--heart', default='heart', help='name of the heart surface (default heart)')
    ap.add_argument('--size', default='1280x800', help='window size (default 1280x800)')
    ap.add_argument('--frames', type=int, default=300, help='frames of the beat when the inputs are made (300)')
    ap.add_argument('--keep', action='store_true', help='keep the inputs made under /tmp')
    a = ap.parse_args()
    w, h = (int(x) for x in a.size.split('x'))

    work = None
    if not a.solution:
        thorax = os.environ.get('THORAX') or os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'build',
                                                          'bin', 'thorax')
        if not os.access(thorax, os.X_OK):
            sys.exit(f'vtk_view: {thorax}: build first (make), or give --model and --solution')
        work = tempfile.mkdtemp(prefix='vtk_view.', dir='/tmp')
        a.model, a.solution = make_inputs(work, thorax, a.frames)
    try:
        sol = json.load(open(os.path.join(a.solution, 'solution.json')))
        model = a.model or sol['model']
        torso_v, torso_t = read_raw(os.path.join(a.solution, a.torso + '.raw'))
        epi = sol['epicardial']
        if not os.path.isabs(epi):
            epi = os.path.join(a.solution, epi)
        heart_v, heart_t = read_raw(epi)
        n_frames = min(len(torso_v), len(heart_v))
        run(model, a, w, h, [(a.torso, torso_v), (a.heart, heart_v)], n_frames)
    finally:
        if work and not a.keep:
            shutil.rmtree(work, ignore_errors=True)
        elif work:
            print(f'inputs kept in {work}')


def run(model, a, w, h, surfaces, n_frames):
    vmax = max(float(np.nanmax(np.abs(v[:n_frames]))) for _, v in surfaces)
    lut = vtk.vtkLookupTable()
    lut.SetNumberOfTableValues(256)
    for i in range(256):
        t = i / 255.0
        lut.SetTableValue(i, *((2 * t, 2 * t, 1) if t < 0.5 else (1, 2 - 2 * t, 2 - 2 * t)), 1)
    lut.SetRange(-vmax, vmax)

    ren = vtk.vtkRenderer()
    ren.SetBackground(0.1, 0.1, 0.11)
    win = vtk.vtkRenderWindow()
    win.SetOffScreenRendering(0)
    win.SetSize(w, h)
    win.SetWindowName('vtk_view bench')
    win.AddRenderer(ren)
    arrays, n_nodes, n_tris = [], 0, 0
    for name, data in surfaces:
        P, T = read_surface(model, name)
        if data.shape[1] != len(P):
            sys.exit(f'vtk_view: the series for {name} has {data.shape[1]} rows, the surface {len(P)} nodes')
        pts = vtk.vtkPoints()
        pts.SetData(numpy_to_vtk(P, deep=1))
        cells = vtk.vtkCellArray()
        cells.SetCells(len(T), numpy_to_vtkIdTypeArray(np.hstack([np.full((len(T), 1), 3), T]).ravel(), deep=1))
        pd = vtk.vtkPolyData()
        pd.SetPoints(pts)
        pd.SetPolys(cells)
        nrm = vtk.vtkPolyDataNormals()  # normals once, as the viewer computes them once
        nrm.SetInputData(pd)
        nrm.SplittingOff()
        nrm.Update()
        out = nrm.GetOutput()
        arr = numpy_to_vtk(np.ascontiguousarray(data[0]), deep=1)
        arr.SetName('potential')
        out.GetPointData().SetScalars(arr)
        mp = vtk.vtkPolyDataMapper()
        mp.SetInputData(out)
        mp.SetLookupTable(lut)
        mp.SetScalarRange(-vmax, vmax)
        mp.SetInterpolateScalarsBeforeMapping(1)  # colours interpolated per pixel, as thorax draws them
        act = vtk.vtkActor()
        act.SetMapper(mp)
        act.GetProperty().SetInterpolationToGouraud()
        ren.AddActor(act)
        arrays.append((out, arr, data))
        n_nodes += len(P)
        n_tris += len(T)
    cam = ren.GetActiveCamera()
    c = np.loadtxt(os.path.join(model, a.torso + '.pts')).mean(0)
    cam.SetFocalPoint(*c)
    cam.SetPosition(c[0], c[1] + 1000, c[2])  # anterior view (+y anterior), head up
    cam.SetViewUp(0, 0, 1)
    ren.ResetCamera()
    win.Render()
    win.WaitForCompletion()
    caps = win.ReportCapabilities() or ''
    renderer = next((l.split(':', 1)[1].strip() for l in caps.splitlines() if l.startswith('OpenGL renderer string')), 'unknown')
    version = next((l.split(':', 1)[1].strip() for l in caps.splitlines() if l.startswith('OpenGL version string')), '?')
    sw, sh = win.GetSize()
    print(f'scene: {a.torso} and {a.heart}, {n_nodes} nodes, {n_tris} triangles, {n_frames} frames of potentials; '
          f'window {sw}x{sh} on screen ({"offscreen" if win.GetOffScreenRendering() else "mapped"}); '
          f'VTK {vtk.vtkVersion.GetVTKVersion()}, OpenGL {version}, renderer {renderer}', flush=True)
    if 'llvmpipe' not in renderer:
        print(f'vtk_view: warning: the renderer is "{renderer}", not Mesa llvmpipe', file=sys.stderr)

    # (a) rotation: 360 steps of 1 degree, Render and glFinish each
    for _ in range(5):  # warm-up
        cam.Azimuth(1)
        win.Render()
    win.WaitForCompletion()
    steps = []
    t_all = time.perf_counter()
    for _ in range(360):
        t0 = time.perf_counter()
        cam.Azimuth(1)
        ren.ResetCameraClippingRange()
        win.Render()
        win.WaitForCompletion()
        steps.append(time.perf_counter() - t0)
    rot = (time.perf_counter() - t_all) / 360

    # (b) frame steps: new scalars on both surfaces, then Render
    views = [(pd, arr, vtk_to_numpy(arr), data) for pd, arr, data in arrays]
    t_all = time.perf_counter()
    for f in range(n_frames):
        for pd, arr, buf, data in views:
            buf[:] = data[f]
            arr.Modified()
        win.Render()
        win.WaitForCompletion()
    step = (time.perf_counter() - t_all) / n_frames
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    steps.sort()
    print(f'rotation: median {1e3 * steps[180]:.1f} ms, fastest {1e3 * steps[0]:.1f}, slowest {1e3 * steps[-1]:.1f}')
    print(f'vtk: rotate {1e3 * rot:.1f} ms/frame ({1 / rot:.0f} fps), frame-step {1e3 * step:.1f} ms ({1 / step:.0f} /s), '
          f'peak {peak:.0f} MB, {renderer}', flush=True)


if __name__ == '__main__':
    main()
