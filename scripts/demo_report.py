#!/usr/bin/env python3
"""The demo's results page: OUT/index.html from the files scripts/demo.sh leaves in OUT.

    python3 scripts/demo_report.py OUT [FRAME]

Reads OUT/check.json (thorax check --json), OUT/solution/solution.json and ecg12.txt (thorax forward,
thorax leads), OUT/model/model.json (the conductivity table), OUT/beat.txt's label or OUT/beat.label
(the dipole), OUT/mesh.txt (thorax mesh --stats) and OUT/timings.txt (one "stage<TAB>seconds" a
line), and writes OUT/index.html naming the pictures beside it. FRAME (1-based) is the frame the maps
show (default: lead II's peak). Prints where the page is and lead II's peak.
Pictures that are missing are left out of the page, with a note saying so.
"""
import html
import json
import math
import os
import sys

# the region colours of thorax render --tetrahedra (src/picture/picture.c, REGION_RGB), by region index
REGION_RGB = [(0.93, 0.80, 0.62), (0.55, 0.72, 0.93), (0.98, 0.62, 0.62), (0.62, 0.87, 0.62),
              (0.85, 0.70, 0.93), (0.95, 0.90, 0.45), (0.55, 0.88, 0.88), (0.80, 0.80, 0.80)]
LEADS = ['I', 'II', 'III', 'aVR', 'aVL', 'aVF', 'V1', 'V2', 'V3', 'V4', 'V5', 'V6']


def read_series_text(path):
    """thorax's text series (docs/formats.md): header lines, then one line of values a row, 'end'."""
    head, rows = {}, []
    with open(path) as f:
        for line in f:
            t = line.split()
            if not t or t[0].startswith('#'):
                continue
            if t[0] == 'end':
                break
            if t[0][0].isalpha() and not rows and t[0] not in ('nan', 'inf'):
                head[t[0]] = line.strip()[len(t[0]):].strip()
                continue
            rows.append([float(x) for x in t])
    n = int(head['frames'])
    assert all(len(r) == n for r in rows), path
    return head, rows


def singular_values(rows):
    """Singular values of a few long rows (one-sided Jacobi: rotate pairs of rows until all are
    orthogonal; their norms are then the singular values, accurate to rounding even for the
    smallest, which forming the Gram matrix would lose), largest first."""
    r = [list(x) for x in rows]
    for _ in range(60):
        rotated = False
        for i in range(len(r) - 1):
            for j in range(i + 1, len(r)):
                a = sum(x * x for x in r[i])
                b = sum(x * x for x in r[j])
                g = sum(x * y for x, y in zip(r[i], r[j]))
                if g == 0 or abs(g) <= 1e-15 * math.sqrt(a * b):
                    continue
                rotated = True
                zeta = (b - a) / (2 * g)
                t = (1 if zeta >= 0 else -1) / (abs(zeta) + math.sqrt(1 + zeta * zeta))
                c = 1 / math.sqrt(1 + t * t)
                sn = c * t
                ri, rj = r[i], r[j]
                r[i] = [c * x - sn * y for x, y in zip(ri, rj)]
                r[j] = [sn * x + c * y for x, y in zip(ri, rj)]
        if not rotated:
            break
    return sorted((math.sqrt(sum(x * x for x in row)) for row in r), reverse=True)


def dipole_rank(ecg):
    """The 8 independent leads (I, II, V1..V6) over time: a single dipole source makes them span 3
    dimensions (each lead is a fixed lead vector dotted with p(t)). Returns the largest four
    singular values of the 8 x frames matrix."""
    return singular_values([ecg[0], ecg[1]] + ecg[6:12])[:4]


def esc(s):
    return html.escape(str(s))


def main(o, frame=None):
    chk = json.load(open(os.path.join(o, 'check.json')))
    sol = json.load(open(os.path.join(o, 'solution', 'solution.json')))
    model = json.load(open(os.path.join(o, 'model', 'model.json')))
    times = [l.rstrip('\n').split('\t') for l in open(os.path.join(o, 'timings.txt')) if l.strip()]
    mesh = open(os.path.join(o, 'mesh.txt')).read() if os.path.exists(os.path.join(o, 'mesh.txt')) else ''
    head, ecg = read_series_text(os.path.join(o, 'solution', sol['files'].get('ecg12', 'ecg12.txt')))
    beat_label = ''
    if os.path.exists(os.path.join(o, 'beat.label')):
        beat_label = open(os.path.join(o, 'beat.label')).read().strip()
    seconds = {a: float(b) for a, b in times}
    total = sum(seconds.values())
    have = lambda f: os.path.exists(os.path.join(o, f))

    # ---- the figures at a glance
    v = chk.get('volume', {})
    vq = v.get('quality', {})
    sv = sol['solver']
    ii = ecg[1]
    ii_peak, ii_min = max(ii), min(ii)
    k_ii = ii.index(ii_peak)
    t0, dt = float(head.get('t0', 0)), float(head.get('dt', 1))
    einthoven = max(abs(ecg[1][f] - ecg[0][f] - ecg[2][f]) for f in range(len(ii)))
    goldberger = max(abs(ecg[3][f] + ecg[4][f] + ecg[5][f]) for f in range(len(ii)))
    ecg_max = max(max(abs(x) for x in r) for r in ecg)
    sv4 = dipole_rank(ecg)
    closure = max((s['solid_angle']['rel_error'] for s in chk.get('surfaces', []) if 'solid_angle' in s),
                  default=float('nan'))
    region_diff = max((abs(r['rel_diff']) for r in v.get('regions', [])), default=float('nan'))
    n_surf_nodes = sum(s['nodes'] for s in chk.get('surfaces', []))
    n_surf_tris = sum(s['triangles'] for s in chk.get('surfaces', []))
    glance = [
        ('surfaces', '%d (%s nodes, %s triangles)' % (len(chk.get('surfaces', [])), f'{n_surf_nodes:,}', f'{n_surf_tris:,}')),
        ('volume mesh', '%s nodes, %s tetrahedra, %d tissue regions' % (f"{v.get('nodes', 0):,}", f"{v.get('tetrahedra', 0):,}",
                                                                         len(v.get('regions', [])))),
        ('mesh quality', 'smallest dihedral angle %.1f&deg;, mean radius ratio %.2f (1 = regular)' % (
            vq.get('min_dihedral_deg', float('nan')), vq.get('radius_ratio', {}).get('mean', float('nan')))),
        ('checks', '%s: surfaces closed and not intersecting, worst solid-angle closure |&Omega;/4&pi; &minus; 1| = %.1e, '
                   'region volumes within %.1e of their surfaces' % ('all passed' if chk.get('ok') else 'FAILED',
                                                                     closure, region_diff)),
        ('forward solution', '%d frames, %s unknowns, %s + %s; %.1f s (assembly %.2f, setup %.2f, solves %.1f); '
                             'largest relative residual %.0e' % (
            sol.get('frames'), f"{sv['free_nodes']:,}", esc(sv['ksp']), esc(sv['pc']), sv['seconds_total'],
            sv['seconds_assembly'], sv['seconds_setup'], sv['seconds_solve'], sv['max_relative_residual'])),
        ('source', esc(beat_label) if beat_label else 'the phantom beat'),
        ('lead II', 'peak %.2f mV at %g ms (clinical R wave 0.5&ndash;2 mV), lowest %.2f mV' % (ii_peak, t0 + k_ii * dt, ii_min)),
        ('lead identities', 'Einthoven II = I + III within %.0e mV, Goldberger aVR + aVL + aVF = 0 within %.0e mV '
                            '(of %.2f mV)' % (einthoven, goldberger, ecg_max)),
        ('one dipole', 'the 8 independent leads (I, II, V1&ndash;V6) span 3 dimensions over the beat, as a single '
                       'dipole source requires: singular values %.3g, %.3g, %.3g, then %.1e (relative %.0e)' % (
            sv4[0], sv4[1], sv4[2], sv4[3], sv4[3] / sv4[0])),
        ('run time', '%.0f s for the whole demo (table at the end)' % total),
    ]

    # ---- conductivity table (the model's)
    regions = model.get('regions', [])
    vreg = {r['name']: r for r in v.get('regions', [])}
    crows = []
    for i, r in enumerate(regions):
        s = r['sigma']
        if isinstance(s, list):
            diag = [s[k][k] for k in range(3)]
            sig = 'tensor diag(%s)' % ', '.join('%g' % x for x in diag)
        else:
            sig = '%g' % s
        c = REGION_RGB[i % len(REGION_RGB)]
        sw = '<span class="sw" style="background:rgb(%d,%d,%d)"></span>' % tuple(round(255 * x) for x in c)
        vr = vreg.get(r['name'], {})
        crows.append('<tr><td>%s %s</td><td>%s</td><td>%s</td><td>%s</td><td class="src">%s</td></tr>' % (
            sw, esc(r['name']), sig, f"{vr.get('tetrahedra', 0):,}",
            '%.0f' % (vr['volume'] / 1000) if 'volume' in vr else '', esc(r.get('source', ''))))

    srows = []
    for s in chk.get('surfaces', []):
        srows.append('<tr><td>%s</td><td>%s</td><td>%d</td><td>%d</td><td>%s</td><td>%.1e</td><td>%d</td><td>%s</td></tr>' % (
            esc(s['name']), esc(s.get('role', '')), s['nodes'], s['triangles'], 'yes' if s.get('closed') else 'NO',
            s['solid_angle']['rel_error'] if 'solid_angle' in s else float('nan'),
            s.get('intersections', {}).get('pairs', -1), 'ok' if s.get('ok') else 'FAIL'))

    def img(f, alt, cls=''):
        if not have(f):
            return '<p class="missing">(%s: not made in this run)</p>' % esc(f)
        return '<img src="%s" alt="%s"%s>' % (esc(f), esc(alt), ' class="%s"' % cls if cls else '')

    measured = ''
    if have('measured_tank.png'):
        measured = '''<h2>Measured recordings (map3d's data)</h2>
<div class="row">%s%s</div>
<p>Drawn from the files as they are, no model: left, the Utah torso-tank experiment's 512-channel recording
(&micro;V) on its 128-lead epicardial sock through map3d's channel map, 184 ms; right, a 490-lead sock recording
(mV) at 276 ms, map3d's time axis from its sample frequency. Both socks are open surfaces.</p>
%s
<p>The 490-lead sock from 230 to 349 ms: activation sweeping the epicardium (one colour scale, &minus;10 to 10 mV, for all frames).</p>''' % (
            img('measured_tank.png', 'tank sock'), img('measured_sock.png', '490-lead sock'),
            '<video src="measured_sock.mp4" controls loop></video>' if have('measured_sock.mp4') else '')

    qrs_ms = t0 + ((frame - 1) if frame else k_ii) * dt
    page = f"""<!doctype html><html><head><meta charset="utf-8"><title>thorax demo: results</title>
<style>
body{{font-family:sans-serif;max-width:1200px;margin:1.5em auto;color:#222;line-height:1.35}}
h1{{font-size:1.6em;margin-bottom:0.2em}} h2{{border-bottom:1px solid #ddd;padding-bottom:0.15em;margin-top:1.6em}}
.row{{display:flex;gap:1%;align-items:flex-start}} .row img,.row video{{flex:1;min-width:0;max-width:49.5%}}
img.wide{{display:block;width:100%;max-width:820px;margin:0 auto}} video{{max-width:49.5%}}
table{{border-collapse:collapse;margin:0.6em 0}} td,th{{border:1px solid #ccc;padding:3px 8px;text-align:right;vertical-align:top}}
td:first-child,th:first-child{{text-align:left}} td.src,th.src{{text-align:left;font-size:0.85em;color:#555;max-width:520px}}
table.glance td{{text-align:left}} table.glance td:first-child{{font-weight:bold;white-space:nowrap;background:#f6f6f6}}
.sw{{display:inline-block;width:0.9em;height:0.9em;border:1px solid #888;vertical-align:middle;margin-right:4px}}
.missing{{color:#a00}} pre{{background:#f8f8f8;padding:0.6em;overflow-x:auto;font-size:0.85em}}
</style></head><body>
<h1>thorax: the built-in phantom, from the scan to the ECG</h1>
<p>A scan of a synthetic thorax (its label map, as a segmentation tool writes one) is traced plane by plane into
contours, which are spline-resampled and laced into closed surfaces, meshed into
tetrahedra with tissue regions and their conductivities; a heartbeat on the epicardium (one current dipole tracing a
vectorcardiogram loop) drives the finite-element forward solution of every frame; the 12-lead ECG is taken from the
body surface. Colours follow the field's convention: red positive, blue negative, white zero.</p>
<h2>At a glance</h2>
<table class="glance">{''.join('<tr><td>%s</td><td>%s</td></tr>' % (a, b) for a, b in glance)}</table>
<h2>The scan and its contours</h2>
{img('scan.png', 'the simulated CT with the traced contours')}
<p>The phantom as a simulated CT (2 mm voxels, Hounsfield units, noise 20 HU; window 400/40), the plane
z&nbsp;=&nbsp;100&nbsp;mm, and on it the contours <code>thorax digitize</code> traced from the phantom's label map
(torso, fat, muscle, lungs, heart; one colour a surface): the model below is built from them.</p>
{'<h2>The beat, interactive</h2>' if have('page.html') else ''}
{'<p><a href="page.html"><b>Open the interactive page</b></a> (page.html, one file that opens offline in a browser): turn the torso '
 'with the mouse, step or play through the %d frames, hide the torso or make it translucent to see the heart, click the '
 '12-lead ECG to go to that instant, click the torso or the heart to plot that node&apos;s signal. '
 'Written by <code>thorax export --solution solution --format html</code>; send it to a colleague as it is.</p>' % len(ii) if have('page.html') else ''}
<h2>The 12-lead ECG</h2>
{img('ecg12.svg', '12-lead ECG', 'wide')}
<p>The standard 3 &times; 4 layout on ECG paper: 25 mm/s and 10 mm/mV, small squares 1 mm = 40 ms &times; 0.1 mV,
large squares 200 ms &times; 0.5 mV, a 1 mV &times; 200 ms calibration pulse at the start of each row. Every column
shows the whole simulated beat ({len(ii)} frames). Drawn by <code>thorax leads --plot ecg12.svg</code>.</p>
<h2>Electrode positions</h2>
<div class="row">{img('electrodes_anterior.png', 'electrodes, anterior')}{img('electrodes_left.png', 'electrodes, left')}</div>
<p>The 12-lead electrodes on the torso (green, named), over the body-surface potentials at the QRS peak
({qrs_ms:g} ms): left, anterior view; right, left lateral view (V5, V6 on the axillary lines). RA, LA and LL
are Mason&ndash;Likar positions on the torso. <code>thorax render --electrodes MODEL/electrodes/12lead.txt</code>.</p>
<h2>Body-surface maps at the QRS peak ({qrs_ms:g} ms)</h2>
<div class="row">{img('anterior.png', 'anterior')}{img('posterior.png', 'posterior')}</div>
<p>Left: anterior view; right: posterior view. Lead II below, the marker at the frame shown.</p>
<div class="row">{img('heart.png', 'heart')}{img('bands.png', 'bands')}</div>
<p>Left: the chest opened by an anterior clip plane, the heart left whole: the epicardial potentials in front of the
torso's posterior wall, seen from inside. Right: left lateral view, 16 bands with contour lines.</p>
<h2>The beat and the currents</h2>
<div class="row">{'<video src="beat.mp4" controls loop></video>' if have('beat.mp4') else ''}{img('currents.png', 'currents')}</div>
<p>Left: frames 101 to 400 of the beat in the opened chest, with lead II. Right: current density at the QRS peak,
averaged on an 18 mm grid (the torso as a wire mesh).</p>
<h2>Inside the volume</h2>
<div class="row">{img('equipotentials.png', 'equipotential surfaces')}{img('slices.png', 'slice')}</div>
<p>Left: four equipotential surfaces of the volume potentials at the QRS peak (12%, 30%, 70% and 88% of the series'
range), translucent, with the heart; the body surface faint. <code>thorax render --solution DIR --isosurface
12%,30%,70%,88%</code> (the solution made with <code>thorax forward --volume</code>). Right: the horizontal slice
z = 110 mm through the heart, seen from above through the translucent heart, with 16 contour lines. <code>thorax render --slice z=110</code>.</p>
<div class="row">{'<video src="equipotentials.mp4" controls loop></video>' if have('equipotentials.mp4') else ''}{img('streamlines.png', 'current streamlines')}</div>
<p>Left: the equipotential surfaces through frames 101 to 400 of the beat: they grow from the heart and turn as the
heart's dipole turns. Right: the heart's current loops at the QRS peak: 220 streamlines of J = &minus;&sigma;&nabla;&phi;
from seeds drawn where the current is strong, traced both ways by second-order Runge&ndash;Kutta (the paper's
recipe), leaving the heart's positive side and returning to its negative side through the torso, coloured by |J|.
<code>thorax render --streamlines density:220</code>.</p>
<h2>Ray traced (RaySpray)</h2>
<div class="row">{img('traced.png', 'ray traced')}{img('volume.png', 'volume rendered')}</div>
<p>The paper's second renderer (4.3, "an integrated ray tracer/volume renderer"), on Embree. Left: the same
picture as the maps above, ray traced: the torso glass (refracting, Fresnel reflections), fat and muscle
transparent, the heart, lungs and their shadows under a key light, a sky behind. <code>thorax trace --material
torso=glass</code>. Right: the potential inside the torso at the QRS peak, rendered by emission and absorption
along each ray through the tetrahedra (each piece integrated exactly for the field, linear in its tetrahedron):
clear near zero, opaque towards the extremes. <code>thorax trace --volume potential</code>.</p>
<div class="row">{'<video src="flight.mp4" controls loop></video>' if have('flight.mp4') else ''}</div>
<p>A key-framed camera flight (paper 4.3, "Animation methods"): five keys a quarter turn apart
(scripts/demo_flight.keys), the camera's position on an interpolating C2 cubic B-spline and its
orientation on a C2 quaternion curve through the keys, once round the torso while the QRS plays
(data frames 150 to 250). <code>thorax animate --keys FILE</code>.</p>
{measured}
<h2>The volume mesh and its conductivities</h2>
<div class="row">{img('tetrahedra.png', 'tetrahedra')}{img('orientation.png', 'orientation')}</div>
<p>Left: the tetrahedra of the back half of the torso (every tetrahedron whose four nodes lie behind the mid-coronal
plane, seen from the front), coloured by tissue region as in the table below; the hole is the heart, whose surface
potentials are prescribed. <code>thorax render MODEL --tetrahedra --clip anterior:0.5</code>. Right: the orientation
check (paper 4.2): each surface in its own panel, triangles drawn only where their outward side faces the viewer,
the nodes behind drawn as points.</p>
<table><tr><th>region</th><th>&sigma; (S/m)</th><th>tetrahedra</th><th>volume (cm&sup3;)</th><th class="src">source</th></tr>{''.join(crows)}</table>
<table><tr><th>surface</th><th>role</th><th>nodes</th><th>triangles</th><th>closed</th><th>|&Omega;/4&pi; &minus; 1|</th><th>intersecting pairs</th><th>check</th></tr>{''.join(srows)}</table>
<p>Volume: {v.get('nodes')} nodes, {v.get('tetrahedra')} tetrahedra; volume against the torso surface
{100 * v.get('volume', {}).get('rel_diff', float('nan')):+.3f}%; smallest dihedral angle
{vq.get('min_dihedral_deg', float('nan')):.2f}&deg;; conforming: {v.get('conforming')}; checks: {'passed' if chk.get('ok') else 'FAILED'}.</p>
<pre>{esc(mesh)}</pre>
<h2>Timings</h2>
<table><tr><th>stage</th><th>seconds</th></tr>{''.join('<tr><td>%s</td><td>%s</td></tr>' % (esc(a), b) for a, b in times)}
<tr><th>total</th><th>{total:.1f}</th></tr></table>
<p>Files: <code>model/</code> (surfaces, volume mesh, electrodes), <code>solution/</code> (torso potentials, currents,
ECG), <code>vtk/</code> (the model for ParaView), <code>paraview/</code> (the beat's potentials on torso and heart, every 5th frame: open <code>torso.pvd</code> and <code>heart.pvd</code> in ParaView for the time axis), <code>frames/</code>; <code>demo.log</code> holds every command and its output.</p>
</body></html>
"""
    tmp = os.path.join(o, '.index.html.tmp')
    with open(tmp, 'w') as f:
        f.write(page)
    os.replace(tmp, os.path.join(o, 'index.html'))
    return ii_peak, total


if __name__ == '__main__':
    if len(sys.argv) not in (2, 3):
        sys.exit('usage: demo_report.py OUT [FRAME]')
    peak, total = main(sys.argv[1], int(sys.argv[2]) if len(sys.argv) == 3 else None)
    print('demo: wrote %s/index.html (lead II peak %.2f mV; total %.1f s)' % (sys.argv[1], peak, total))
