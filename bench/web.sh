#!/usr/bin/env bash
# The web page (thorax export --format html; docs/design/web.md, issue 29): the medium phantom's
# 500-frame beat on the torso and the heart with the 12-lead ECG, the demo's page.
#  - size: the page beside the same data as ParaView's .vtp series (thorax export --format vtp, every
#    frame of both surfaces) and that series compressed (tar | gzip -9);
#  - in Chromium (SwiftShader) and Firefox (llvmpipe), RUNS fresh browsers each: the first picture of
#    the browser's first WebGL page (cold) and of a second tab (warm), and a frame step (the values
#    of the next frame through the scale into the vertex attribute, drawn and finished), medians;
#  - beside it VTK 9 (Debian's python3-vtk9, offscreen under Xvfb) stepping the same meshes through
#    the same frames (new point scalars, Render, read back), median per frame.
# Prints figures; never fails on time.   RUNS=N (default 5); SIZE=WxH of the 3D view (default 640x720)
set -euo pipefail
cd "$(dirname "$0")/.."
THORAX=${THORAX:-$PWD/build/bin/thorax}
RUNS=${RUNS:-5}
SIZE=${SIZE:-640x720}
W=${SIZE%x*}
H=${SIZE#*x}
NM=$PWD/build/web/npm/node_modules
[ -x "$THORAX" ] || { echo "build first (make)"; exit 1; }
[ -d "$NM/puppeteer-core" ] || { echo "no puppeteer-core in $NM (the build's scripts/web.sh installs it)"; exit 1; }
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), load $(cut -d' ' -f1-3 /proc/loadavg)"
cd "$T"
"$THORAX" phantom --resolution medium --seed 1 -o c.txt -q
"$THORAX" surfaces c.txt -o m -q
"$THORAX" mesh m --no-heart -q
"$THORAX" electrodes m -q
"$THORAX" beat m -o beat.raw -q
"$THORAX" forward m --epicardial beat.raw -o sol -q
"$THORAX" leads sol -q
"$THORAX" export --solution sol --format html -o page.html --only torso --only heart --size "$SIZE" --frame 193 | tee export.txt
"$THORAX" export m --solution sol --format vtp --surface torso --surface heart -o vtp -q
page=$(stat -c %s page.html)
vtp=$(du -sb vtp | cut -f1)
tgz=$(tar -C vtp -cf - . | gzip -9 | wc -c)
nodes=$(python3 -c "import json; m=json.load(open('m/model.json')); print(' and '.join('%s %d nodes' % (s['name'], s['n_nodes']) for s in m['surfaces'] if s['name'] in ('torso','heart')))")
printf 'size: the page %.2f MB (the viewer 0.58 MB inside); the same 500 frames as .vtp files %.2f MB, gzipped %.2f MB (%s)\n' \
    "$(echo "$page / 1000000" | bc -l)" "$(echo "$vtp / 1000000" | bc -l)" "$(echo "$tgz / 1000000" | bc -l)" "$nodes"
ln -s "$NM" node_modules
cp "$OLDPWD/bench/web_timing.mjs" "$OLDPWD/tests/web_common.mjs" .
for b in chromium firefox; do
    node web_timing.mjs "$T/page.html" $b "$RUNS" "$W" "$H" > $b.jsonl
    python3 - $b.jsonl "$SIZE" <<'PY'
import json, sys, statistics as S
r = [json.loads(l) for l in open(sys.argv[1])]
med = lambda k: S.median(x[k] for x in r)
rng = lambda k: "%.0f-%.0f" % (min(x[k] for x in r), max(x[k] for x in r))
print("%s, %d runs: first picture cold %.0f ms (%s; shown %.0f ms; the WebGL context made at %.0f ms), warm %.0f ms (%s; shown %.0f ms; data decoded at %.0f ms); a frame step %.2f ms (%.2f-%.2f) at %s"
      % (r[0]["browser"], len(r), med("cold"), rng("cold"), med("cold_shown"), med("cold_context"), med("warm"), rng("warm"), med("warm_shown"), med("warm_decoded"), med("step"),
         min(x["step"] for x in r), max(x["step"] for x in r), sys.argv[2]))
PY
done
cat > vtk_step.py <<'PY'
import sys, time, numpy as np, vtk
from vtk.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray
m, sol, w, h = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
def raw(p):
    b = open(p, 'rb').read(); r, f = (int(x) for x in np.frombuffer(b[8:24], dtype='<u8'))
    return np.frombuffer(b[200 + 8 * f:], dtype='<f8').reshape(f, r)
torso, heart = raw(sol + '/torso.raw'), raw('beat.raw')
ren = vtk.vtkRenderer(); ren.SetBackground(24 / 255, 24 / 255, 28 / 255)
win = vtk.vtkRenderWindow(); win.SetOffScreenRendering(1); win.SetSize(w, h); win.AddRenderer(ren)
arrays = []
for name, data in (('torso', torso), ('heart', heart)):
    P = np.loadtxt(f'{m}/{name}.pts'); T = np.loadtxt(f'{m}/{name}.fac', dtype=np.int64) - 1
    pts = vtk.vtkPoints(); pts.SetData(numpy_to_vtk(P, deep=1))
    cells = vtk.vtkCellArray(); cells.SetCells(len(T), numpy_to_vtkIdTypeArray(np.hstack([np.full((len(T), 1), 3), T]).ravel(), deep=1))
    pd = vtk.vtkPolyData(); pd.SetPoints(pts); pd.SetPolys(cells)
    M = abs(data).max()
    arr = numpy_to_vtk(data[0].copy(), deep=1); pd.GetPointData().SetScalars(arr)
    mp = vtk.vtkPolyDataMapper(); mp.SetInputData(pd); mp.SetScalarRange(-M, M); mp.SetInterpolateScalarsBeforeMapping(1)
    a = vtk.vtkActor(); a.SetMapper(mp); ren.AddActor(a)
    arrays.append((pd, arr, data))
cam = ren.GetActiveCamera(); c = np.loadtxt(f'{m}/torso.pts').mean(0)
cam.SetFocalPoint(*c); cam.SetPosition(c[0], c[1] + 1000, c[2]); cam.SetViewUp(0, 0, 1); cam.ParallelProjectionOn(); ren.ResetCamera()
win.Render()
times = []
for f in range(1, 201):
    t0 = time.perf_counter()
    for pd, arr, data in arrays:
        arr.DeepCopy(numpy_to_vtk(data[f].copy())); arr.Modified(); pd.Modified()
    win.Render()
    g = vtk.vtkUnsignedCharArray(); win.GetRGBACharPixelData(0, 0, 0, 0, 0, g)  # finished, as the page's step
    times.append(time.perf_counter() - t0)
times.sort()
print("VTK %s (the peer): a frame step %.2f ms (median of 200; %.2f-%.2f) at %dx%d, %s" % (vtk.vtkVersion.GetVTKVersion(),
      1000 * times[100], 1000 * times[0], 1000 * times[-1], w, h, (win.ReportCapabilities() or '').splitlines()[1].strip()))
PY
xvfb-run -a -s "-screen 0 1280x1024x24" /usr/bin/python3 vtk_step.py m sol "$W" "$H" 2>/dev/null || echo "VTK: not run (python3-vtk9 or xvfb-run missing)"
