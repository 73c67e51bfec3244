#!/usr/bin/env bash
# The demo (make demo): the whole pipeline on the built-in phantom, timed stage by
# stage, and out/demo/index.html with the pictures, the model's statistics and
# checks, the solver's figures and the timings.
set -euo pipefail
T=${THORAX:-build/bin/thorax}
O=${OUT:-out/demo}
mkdir -p "$O"
TIMES="$O/timings.txt"
: > "$TIMES"
stage() { # NAME CMD...
    local name=$1; shift
    echo "+ $*"
    local t0 t1
    t0=$(date +%s.%N)
    "$@"
    t1=$(date +%s.%N)
    awk -v n="$name" -v a="$t0" -v b="$t1" 'BEGIN { printf "%s\t%.2f\n", n, b - a }' >> "$TIMES"
}
QRS=193   # the QRS peak of the phantom's beat (frame 193 = 192 ms)
stage "contours (thorax phantom)" "$T" phantom --resolution medium --seed 1 -o "$O/contours.txt" -q
stage "surfaces" "$T" surfaces "$O/contours.txt" -o "$O/model" -q
stage "volume mesh" "$T" mesh "$O/model" --no-heart --stats > "$O/mesh.txt"
stage "checks" sh -c "'$T' check '$O/model' --json > '$O/check.json'"
stage "electrodes" "$T" electrodes "$O/model" -q
stage "heartbeat (500 frames)" "$T" beat "$O/model" -o "$O/beat.raw" -q
stage "forward solution (500 frames)" "$T" forward "$O/model" --epicardial "$O/beat.raw" -o "$O/solution" --currents $QRS -q
stage "12-lead ECG" "$T" leads "$O/solution" -q
R=(--solution "$O/solution" --size 800x900 --colorbar --orientation --label --trace II --only torso --only heart)
stage "anterior map" "$T" render "${R[@]}" --frame $QRS --view anterior -o "$O/anterior.png" -q
stage "posterior map" "$T" render "${R[@]}" --frame $QRS --view posterior -o "$O/posterior.png" -q
OPEN=(--view anterior --clip anterior:0.75 --no-clip heart)   # the chest opened, the heart whole
stage "heart through the clip plane" "$T" render "${R[@]}" --frame $QRS "${OPEN[@]}" -o "$O/heart.png" -q
stage "contours and bands" "$T" render --solution "$O/solution" --size 800x800 --frame $QRS --view left --style bands+contours --levels 16 --colorbar --orientation --label -o "$O/bands.png" -q
stage "current arrows" "$T" render --solution "$O/solution" --size 800x800 --frame $QRS --view anterior --clip anterior:0.55 --arrows --arrow-spacing 18 --surface torso=wire:0.15 --orientation -o "$O/currents.png" -q
stage "orientation check" "$T" render "$O/model" --size 900x600 --panels --mode orientation --orientation -o "$O/orientation.png" -q
stage "animation (300 frames + MP4)" "$T" animate "${R[@]}" --size 640x720 "${OPEN[@]}" --frames 101:400 --fps 30 -o "$O/frames" --mp4 "$O/beat.mp4" -q
# Measured data, when the shared data folder is beside the checkout (it is in CI; elsewhere this part
# is left out): map3d's recordings drawn from their own files, no model needed.
MD=${MAP3D_DATA:-../shared/data/map3d}
if [ -f "$MD/data/tank/cool1-atdr-run1.mat" ] && [ -f "$MD/data/socks/10jan01/rsm10jan01-cs-0004.mat" ]; then
    stage "measured: tank sock" "$T" render "$MD/geom/tank/25feb97_sock.pts" --data "$MD/data/tank/cool1-atdr-run1.mat" \
        --channels "$MD/geom/tank/sock128.channels" --frame 185 --scope frame --style continuous+contours --colorbar \
        --label --trace 60 --size 600x600 -o "$O/measured_tank.png" -q 2> /dev/null
    stage "measured: 490-lead sock" "$T" render "$MD/geom/socks/490sock.pts" --data "$MD/data/socks/10jan01/rsm10jan01-cs-0004.mat" \
        --frame 277 --scope frame --style continuous+contours --colorbar --label --trace 245 --size 600x600 \
        -o "$O/measured_sock.png" -q 2> /dev/null
    stage "measured: sock animation (120 frames + MP4)" "$T" animate "$MD/geom/socks/490sock.pts" \
        --data "$MD/data/socks/10jan01/rsm10jan01-cs-0004.mat" --frames 231:350 --scope fixed:-10:10 --colorbar --style continuous+contours --label \
        --trace 245 --size 480x480 --fps 20 -o "$O/measured_frames" --mp4 "$O/measured_sock.mp4" -q 2> /dev/null
else
    rm -rf "$O/measured_tank.png" "$O/measured_sock.png" "$O/measured_sock.mp4" "$O/measured_frames"
fi
stage "VTK export" sh -c "'$T' export '$O/model' --format vtp -o '$O/vtk' -q && '$T' export '$O/model' --format vtu -o '$O/vtk' -q"

python3 - "$O" <<'EOF'
import html, json, os, sys
o = sys.argv[1]
chk = json.load(open(os.path.join(o, 'check.json')))
sol = json.load(open(os.path.join(o, 'solution', 'solution.json')))
times = [l.rstrip('\n').split('\t') for l in open(os.path.join(o, 'timings.txt')) if l.strip()]
mesh = open(os.path.join(o, 'mesh.txt')).read()
rows = []
for s in chk.get('surfaces', []):
    q = s.get('quality', {})
    rows.append('<tr><td>%s</td><td>%d</td><td>%d</td><td>%s</td><td>%.2e</td><td>%d</td><td>%s</td></tr>' % (
        html.escape(s['name']), s['nodes'], s['triangles'], 'yes' if s.get('closed') else 'NO',
        s['solid_angle']['rel_error'] if 'solid_angle' in s else float('nan'),
        s.get('intersections', {}).get('pairs', -1), 'ok' if s.get('ok') else 'FAIL'))
v = chk.get('volume', {})
vq = v.get('quality', {})
regions = ''.join('<tr><td>%s</td><td>%d</td><td>%.4g</td><td>%+.3f%%</td></tr>' % (
    html.escape(r['name']), r['tetrahedra'], r['volume'], 100 * r['rel_diff']) for r in v.get('regions', []))
sv = sol['solver']
total = sum(float(t[1]) for t in times)
measured = ''
if os.path.exists(os.path.join(o, 'measured_tank.png')):
    measured = '''<h2>Measured recordings (map3d's data)</h2>
<img src="measured_tank.png" alt="tank sock"><img src="measured_sock.png" alt="490-lead sock">
<p>Drawn from the files as they are, no model: left, the Utah torso-tank experiment's 512-channel recording
(&micro;V) on its 128-lead epicardial sock through map3d's channel map, 184 ms; right, a 490-lead sock recording
(mV) at 276 ms, map3d's time axis from its sample frequency. Both socks are open surfaces.</p>
<video src="measured_sock.mp4" controls loop></video>
<p>The 490-lead sock from 230 to 349 ms: activation sweeping the epicardium (one colour scale, -10 to 10 mV, for all frames).</p>'''
page = f"""<!doctype html><html><head><meta charset="utf-8"><title>thorax demo</title>
<style>body{{font-family:sans-serif;max-width:1100px;margin:2em auto;color:#222}} img,video{{max-width:48%;margin:0.5%}}
table{{border-collapse:collapse;margin:1em 0}} td,th{{border:1px solid #ccc;padding:3px 8px;text-align:right}}
td:first-child,th:first-child{{text-align:left}}</style></head><body>
<h1>thorax: the built-in phantom, from contours to the ECG</h1>
<p>Digitized contours of a synthetic thorax, spline-resampled and laced into closed surfaces, meshed into tetrahedra with
tissue regions and conductivities, a heartbeat on the epicardium (a dipole tracing a vectorcardiogram loop), the
finite-element forward solution for every frame, the 12-lead ECG, and pictures following the field's conventions
(red positive, blue negative, white zero).</p>
<h2>Body-surface maps at the QRS peak (192 ms)</h2>
<img src="anterior.png" alt="anterior"><img src="posterior.png" alt="posterior">
<p>Left: anterior view; right: posterior view. Lead II below, the marker at the frame shown.</p>
<img src="heart.png" alt="heart"><img src="bands.png" alt="bands">
<p>Left: the chest opened by an anterior clip plane, the heart left whole: the epicardial potentials in front of the
torso's posterior wall, seen from inside. Right: left lateral view, 16 bands with contour lines.</p>
<h2>The beat and the currents</h2>
<video src="beat.mp4" controls loop></video><img src="currents.png" alt="currents">
<p>Left: frames 101 to 400 of the beat in the opened chest, with lead II. Right: current density at the QRS peak,
averaged on an 18 mm grid (the torso as a wire mesh).</p>
{measured}
<h2>The orientation check (paper 4.2)</h2>
<img src="orientation.png" alt="orientation" style="max-width:97%">
<p>Each surface in its own panel: triangles are drawn only where their outward side faces the viewer; the nodes
behind are drawn as points.</p>
<h2>Model</h2>
<table><tr><th>surface</th><th>nodes</th><th>triangles</th><th>closed</th><th>|&Omega;/4&pi; - 1|</th><th>intersecting pairs</th><th>check</th></tr>{''.join(rows)}</table>
<p>Volume: {v.get('nodes')} nodes, {v.get('tetrahedra')} tetrahedra; volume against the torso surface
{100 * v.get('volume', {}).get('rel_diff', float('nan')):+.3f}%; smallest dihedral angle
{vq.get('min_dihedral_deg', float('nan')):.2f}&deg;; conforming: {v.get('conforming')}; checks: {'passed' if chk.get('ok') else 'FAILED'}.</p>
<table><tr><th>region</th><th>tetrahedra</th><th>volume mm&sup3;</th><th>against its surfaces</th></tr>{regions}</table>
<pre>{html.escape(mesh)}</pre>
<h2>Forward solution</h2>
<p>{sol.get('frames')} frames; {sv['free_nodes']} free nodes, {sv['prescribed_nodes']} prescribed (the heart surface);
{sv['ksp']} + {sv['pc']} on {sv['ranks']} rank(s); assembly {sv['seconds_assembly']:.2f} s, setup {sv['seconds_setup']:.2f} s,
solves {sv['seconds_solve']:.2f} s; largest relative residual {sv['max_relative_residual']:.1e}.</p>
<h2>Timings</h2>
<table><tr><th>stage</th><th>seconds</th></tr>{''.join('<tr><td>%s</td><td>%s</td></tr>' % (html.escape(a), b) for a, b in times)}
<tr><th>total</th><th>{total:.1f}</th></tr></table>
<p>Files: <code>model/</code> (surfaces, volume mesh, electrodes), <code>solution/</code> (torso potentials, currents,
ECG), <code>vtk/</code> (for ParaView), <code>frames/</code>.</p>
</body></html>
"""
open(os.path.join(o, 'index.html'), 'w').write(page)
print('demo: wrote %s/index.html (total %.1f s)' % (o, total))
EOF
