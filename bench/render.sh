#!/usr/bin/env bash
# Benchmark of the renderer (paper 4.2) on this machine's Mesa llvmpipe: the
# high-resolution torso and heart with potentials, Gouraud shading with contour
# lines, 1024x1024, frames per second of thorax render beside VTK 9 (Debian's
# python3-vtk9, offscreen under Xvfb: Debian's VTK has no EGL build) drawing the same
# meshes and data in the same run, with the ratio; then a 300-frame animation of the
# high-resolution model (PNGs and MP4). Prints figures; never fails on time.
set -euo pipefail
cd "$(dirname "$0")/.."
THORAX=${THORAX:-$PWD/build/bin/thorax}
[ -x "$THORAX" ] || { echo "build first (make)"; exit 1; }
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')"
"$THORAX" phantom --resolution high --seed 1 -o "$W/c.txt" -q
"$THORAX" surfaces "$W/c.txt" -o "$W/m" -q
"$THORAX" mesh "$W/m" --no-heart -q
"$THORAX" beat "$W/m" -o "$W/beat.raw" --frames 300 -q
"$THORAX" forward "$W/m" --epicardial "$W/beat.raw" -o "$W/sol" -q
F=193
tris=$(python3 -c "
import json; m=json.load(open('$W/m/model.json'))
print(sum(s['n_tris'] for s in m['surfaces'] if s['name'] in ('torso','heart')))")
echo "scene: torso and heart, $tris triangles, potentials of frame $F, Gouraud + 12 contour lines, 1024x1024"
/usr/bin/time -f "%M" -o "$W/mem_ours" "$THORAX" render --solution "$W/sol" --frame $F --only torso --only heart --size 1024x1024 --mode gouraud \
    --style continuous+contours --levels 12 --repeat 30 -o "$W/thorax.png" | tee "$W/ours.txt"
cat > "$W/vtk_bench.py" <<'EOF'
import sys, time, json, numpy as np, vtk
from vtk.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray
m, sol, frame, out = sys.argv[1], sys.argv[2], int(sys.argv[3]) - 1, sys.argv[4]
def raw(p):
    b = open(p, 'rb').read(); r, f = np.frombuffer(b[8:24], dtype='<u8')
    return np.frombuffer(b[200:], dtype='<f8')[f:].reshape(f, r)
torso, epi = raw(sol + '/torso.raw'), raw(json.load(open(sol + '/solution.json'))['epicardial'])
ren = vtk.vtkRenderer(); ren.SetBackground(0.1, 0.1, 0.11)
win = vtk.vtkRenderWindow(); win.SetOffScreenRendering(1); win.SetSize(1024, 1024); win.AddRenderer(ren)
arrays = []
M = max(abs(torso).max(), abs(epi).max())
lut = vtk.vtkLookupTable(); lut.SetNumberOfTableValues(256)
for i in range(256):
    t = i / 255.0
    lut.SetTableValue(i, *((2 * t, 2 * t, 1) if t < 0.5 else (1, 2 - 2 * t, 2 - 2 * t)), 1)
lut.SetRange(-M, M)
for name, data in (('torso', torso), ('heart', epi)):
    P = np.loadtxt(f'{m}/{name}.pts'); T = np.loadtxt(f'{m}/{name}.fac', dtype=np.int64) - 1
    pts = vtk.vtkPoints(); pts.SetData(numpy_to_vtk(P, deep=1))
    cells = vtk.vtkCellArray()
    conn = np.hstack([np.full((len(T), 1), 3), T]).ravel()
    cells.SetCells(len(T), numpy_to_vtkIdTypeArray(conn, deep=1))
    pd = vtk.vtkPolyData(); pd.SetPoints(pts); pd.SetPolys(cells)
    arr = numpy_to_vtk(data[frame].copy(), deep=1); arr.SetName('phi'); pd.GetPointData().SetScalars(arr)
    nrm = vtk.vtkPolyDataNormals(); nrm.SetInputData(pd)
    mp = vtk.vtkPolyDataMapper(); mp.SetInputConnection(nrm.GetOutputPort()); mp.SetLookupTable(lut)
    mp.SetScalarRange(-M, M); mp.SetInterpolateScalarsBeforeMapping(1)   # per-pixel colour, like ours
    a = vtk.vtkActor(); a.SetMapper(mp); a.GetProperty().SetInterpolationToGouraud(); ren.AddActor(a)
    cf = vtk.vtkContourFilter(); cf.SetInputData(pd); cf.GenerateValues(11, -M * 11 / 12, M * 11 / 12)
    cm = vtk.vtkPolyDataMapper(); cm.SetInputConnection(cf.GetOutputPort()); cm.ScalarVisibilityOff()
    ca = vtk.vtkActor(); ca.SetMapper(cm); ca.GetProperty().SetColor(0, 0, 0); ca.GetProperty().SetLineWidth(1.5); ren.AddActor(ca)
    arrays.append((pd, arr, data))
c = np.loadtxt(f'{m}/torso.pts').mean(0)
cam = ren.GetActiveCamera(); cam.SetFocalPoint(*c); cam.SetPosition(c[0], c[1] + 1000, c[2]); cam.SetViewUp(0, 0, 1)
cam.ParallelProjectionOn(); ren.ResetCamera()
win.Render()
times = []
for k in range(30):
    # new values every frame (an animation): the scalars change, VTK re-uploads and re-contours
    f = frame + (k % 2)
    for pd, arr, data in arrays:
        arr.DeepCopy(numpy_to_vtk(data[f].copy())); arr.Modified(); pd.Modified()
    t0 = time.perf_counter(); win.Render()
    g = vtk.vtkUnsignedCharArray(); win.GetRGBACharPixelData(0, 0, 1023, 1023, 0, g)   # read back, as we do
    times.append(time.perf_counter() - t0)
times.sort()
med = times[len(times) // 2]
w2i = vtk.vtkWindowToImageFilter(); w2i.SetInput(win); pw = vtk.vtkPNGWriter(); pw.SetFileName(out)
pw.SetInputConnection(w2i.GetOutputPort()); pw.Write()
print("VTK %s: 30 repetitions, median %.1f ms a frame (min %.1f, max %.1f), %.1f frames per second; %s" %
      (vtk.vtkVersion.GetVTKVersion(), 1000 * med, 1000 * times[0], 1000 * times[-1], 1 / med,
       win.ReportCapabilities().splitlines()[1].strip() if win.ReportCapabilities() else ''))
EOF
xvfb-run -a -s "-screen 0 1280x1280x24" /usr/bin/time -f "%M" -o "$W/mem_vtk" /usr/bin/python3 "$W/vtk_bench.py" "$W/m" "$W/sol" $F "$W/vtk.png" | tee "$W/vtk.txt"
echo "peak memory of the whole process (30 frames): thorax $(( $(tail -1 "$W/mem_ours") / 1024 )) MB, VTK $(( $(tail -1 "$W/mem_vtk") / 1024 )) MB (Python and VTK's libraries included)"
python3 - "$W/ours.txt" "$W/vtk.txt" <<'EOF'
import re, sys
o = float(re.search(r'median ([0-9.]+) ms', open(sys.argv[1]).read()).group(1))
v = float(re.search(r'median ([0-9.]+) ms', open(sys.argv[2]).read()).group(1))
print("ratio: thorax %.1f ms, VTK %.1f ms a frame: thorax is %.2fx %s" % (o, v, v / o if o < v else o / v, "faster" if o < v else "slower"))
EOF
# a 300-frame animation of the high-resolution model: PNGs and an MP4
/usr/bin/time -f "%e %M" -o "$W/t" "$THORAX" animate --solution "$W/sol" --only torso --only heart --size 800x800 \
    --style continuous+contours --colorbar --label --frames 1:300 --fps 30 -o "$W/frames" --mp4 "$W/beat.mp4" -q
read -r wall rss < "$W/t"
echo "animation: 300 frames at 800x800 (PNGs + MP4): wall $wall s, peak $((rss / 1024)) MB; $(ffprobe -v error -count_frames -select_streams v:0 -show_entries stream=nb_read_frames,codec_name -of csv=p=0 "$W/beat.mp4")"
