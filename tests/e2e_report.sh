#!/usr/bin/env bash
# The results report end to end on the medium phantom (what make demo's page is made of):
#  - the phantom's beat at its default strength gives a human ECG: lead II peaks within 1-2 mV on
#    the forward solution;
#  - thorax leads --plot: the SVG parses as XML (python's xml.etree), every lead's trace reaches
#    its series' extremes in grid units (10 mm/mV, 25 mm/s, 1 mm grid lines); the PNG is read back
#    by VTK at the SVG's size; a bad --plot name is refused before anything is written;
#  - thorax render --electrodes: the electrodes drawn (green) where they project; a missing file
#    refused; --tetrahedra: the clipped mesh in its region colours, refused without a volume mesh;
#  - scripts/demo_report.py on these files: the page parses, its figures at a glance are the
#    files' (nodes, tetrahedra, lead II peak, the leads' singular values against numpy's: rank 3
#    for one dipole), the conductivity table is the model's, every picture it names exists.
set -euo pipefail
: "${THORAX:?}" "${WORK:?}" "${SRC:?}"
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK"
PY=/usr/bin/python3
fail() { echo "FAIL: $*"; exit 1; }

"$THORAX" phantom --resolution medium --seed 1 -o c.txt -q
"$THORAX" surfaces c.txt -o model -q
cp -r model surfaces_only
"$THORAX" mesh model --no-heart --stats > mesh.txt
"$THORAX" check model --json > check.json
"$THORAX" electrodes model -q
"$THORAX" beat model -o beat.raw --frames 260 > beat.out
sed -n 2p beat.out > beat.label
"$THORAX" forward model --epicardial beat.raw -o solution -q
"$THORAX" leads solution --plot ecg12.svg > leads.log
grep -q "^plot: ecg12.svg$" leads.log || fail "leads --plot: $(cat leads.log)"
"$THORAX" leads solution --plot ecg12.png -q

# --- the ECG: amplitudes and the plot --------------------------------------------------
"$PY" - <<'EOF' || fail "ECG plot"
import math
import xml.etree.ElementTree as ET

def series(path):
    head, rows = {}, []
    for l in open(path):
        t = l.split()
        if not t: continue
        if t[0] == 'end': break
        if t[0][0].isalpha() and not rows: head[t[0]] = l.strip()[len(t[0]):].strip(); continue
        rows.append([float(x) for x in t])
    return head, rows

head, E = series('solution/ecg12.txt')
assert head['unit'] == 'mV' and len(E) == 12
peak = max(E[1])
assert 1.0 <= peak <= 2.0, 'lead II peaks at %.3f mV, not 1-2 mV' % peak

ns = {'s': 'http://www.w3.org/2000/svg'}
root = ET.parse('ecg12.svg').getroot()
assert root.tag == '{http://www.w3.org/2000/svg}svg'
gain, speed = float(root.get('data-mm-per-mv')), float(root.get('data-mm-per-s'))
assert (gain, speed) == (10.0, 25.0)
W, H = (float(x) for x in root.get('viewBox').split()[2:])
assert root.get('width') == '%.1fmm' % W and root.get('height') == '%.1fmm' % H
# the grid: a line every millimetre across the sheet, every fifth heavier
xs = sorted({round(float(l.get('x1')), 3) for l in root.iter('{http://www.w3.org/2000/svg}line')
             if l.get('x1') == l.get('x2') and float(l.get('y2')) - float(l.get('y1')) == H})
assert xs == [float(i) for i in range(0, int(W) + 1)], xs[:10]
heavy = {float(l.get('x1')) for l in root.iter('{http://www.w3.org/2000/svg}line')
         if l.get('x1') == l.get('x2') and float(l.get('stroke-width')) == 0.2 and float(l.get('y2')) - float(l.get('y1')) == H}
assert heavy == {float(i) for i in range(0, int(W) + 1, 5)}
names = ['I', 'II', 'III', 'aVR', 'aVL', 'aVF', 'V1', 'V2', 'V3', 'V4', 'V5', 'V6']
t = [float(head['t0']) + k * float(head['dt']) for k in range(int(head['frames']))]
worst = 0
for k, name in enumerate(names):
    g = root.find(".//s:g[@id='lead-%s']" % name, ns)
    assert g is not None, name
    x0, base = float(g.get('data-x0')), float(g.get('data-baseline'))
    pts = [tuple(map(float, p.split(','))) for pl in g.findall('s:polyline', ns) for p in pl.get('points').split()]
    assert len(pts) == len(t), (name, len(pts))
    ys = [y for _, y in pts]
    hi, lo = (base - min(ys)) / gain, (base - max(ys)) / gain      # mV, y downwards
    worst = max(worst, abs(hi - max(E[k])), abs(lo - min(E[k])))
    # the peak's time in grid units: x0 + t * 25 mm/s
    i = E[k].index(max(E[k]))
    assert abs(pts[i][0] - (x0 + (t[i] - t[0]) * speed / 1000)) < 1e-3
    assert base == round(base)
assert worst < 1e-3, worst
print('e2e_report: lead II peak %.3f mV; the SVG (%.0f x %.0f mm) parses, its 12 traces within %.1e mV of the series' % (peak, W, H, worst))

import vtk
r = vtk.vtkPNGReader(); r.SetFileName('ecg12.png'); r.Update()
dims = r.GetOutput().GetDimensions()
assert dims[:2] == (math.ceil(W * 8), math.ceil(H * 8)), (dims, W, H)
print('e2e_report: VTK reads ecg12.png, %d x %d pixels (8 a millimetre)' % dims[:2])
EOF
# a bad plot name: refused before anything is written (the solution's ECG is not rewritten either)
before=$(stat -c %Y.%s solution/ecg12.txt)
if "$THORAX" leads solution --plot ecg.pdf 2> err.log; then fail "leads --plot ecg.pdf accepted"; fi
grep -q "\.svg or \.png" err.log || fail "--plot ecg.pdf: $(cat err.log)"
[ ! -e ecg.pdf ] && [ "$(stat -c %Y.%s solution/ecg12.txt)" = "$before" ] || fail "--plot ecg.pdf wrote something"
# a file thorax did not write is not replaced
echo '<svg>mine</svg>' > mine.svg
if "$THORAX" leads solution --plot mine.svg -q 2> err.log; then fail "leads --plot over a user's file accepted"; fi
grep -q '^<svg>mine</svg>$' mine.svg || fail "a user's SVG was overwritten"

# --- render --electrodes and --tetrahedra -------------------------------------------------
"$THORAX" render --solution solution --frame 193 --size 500x600 --only torso --electrodes model/electrodes/12lead.txt \
    -o electrodes_anterior.png -q
"$THORAX" render --solution solution --frame 193 --size 500x600 --only torso -o plain.png -q
"$THORAX" render model --size 500x600 --mode hidden --tetrahedra --clip anterior:0.5 -o tetrahedra.png -q
"$THORAX" render model --size 500x600 --mode hidden --tetrahedra -o tetrahedra_all.png -q
if "$THORAX" render model --electrodes nothere.txt -o bad1.png 2> err.log; then fail "--electrodes nothere.txt accepted"; fi
grep -q "nothere.txt" err.log && [ ! -e bad1.png ] || fail "--electrodes nothere.txt: $(cat err.log)"
if "$THORAX" render surfaces_only --tetrahedra -o bad2.png 2> err.log; then fail "--tetrahedra without a volume accepted"; fi
grep -q "no volume mesh" err.log && [ ! -e bad2.png ] || fail "--tetrahedra without a volume: $(cat err.log)"
"$PY" - <<'EOF' || fail "electrode and mesh pictures"
import vtk
from vtk.util.numpy_support import vtk_to_numpy
import numpy as np
def png(p):
    r = vtk.vtkPNGReader(); r.SetFileName(p); r.Update()
    im = r.GetOutput(); w, h, _ = im.GetDimensions()
    a = vtk_to_numpy(im.GetPointData().GetScalars()).reshape(h, w, -1)[::-1, :, :3].astype(int)
    return a
e, p = png('electrodes_anterior.png'), png('plain.png')
green = (e[:, :, 1] > e[:, :, 0] + 40) & (e[:, :, 1] > e[:, :, 2] + 40)
assert green.sum() > 9 * 20 and not ((p[:, :, 1] > p[:, :, 0] + 40) & (p[:, :, 1] > p[:, :, 2] + 40)).any(), green.sum()
# the green blobs: at least 7 of the 9 electrodes seen from the front (V5/V6 on the side may merge)
lab = np.zeros(green.shape, int); n = 0
for y, x in zip(*np.nonzero(green)):
    if lab[y, x]: continue
    n += 1; stack = [(y, x)]; lab[y, x] = n
    while stack:
        cy, cx = stack.pop()
        for dy in (-1, 0, 1):
            for dx in (-1, 0, 1):
                yy, xx = cy + dy, cx + dx
                if 0 <= yy < green.shape[0] and 0 <= xx < green.shape[1] and green[yy, xx] and not lab[yy, xx]:
                    lab[yy, xx] = n; stack.append((yy, xx))
sizes = np.bincount(lab.ravel())[1:]
assert (sizes > 10).sum() >= 7, sizes
t, ta = png('tetrahedra.png'), png('tetrahedra_all.png')
bg = t[0, 0]
drawn = (abs(t - bg).sum(axis=2) > 30)
# region 1 (mean_thorax, tan) and the lungs (green, violet) all show in the cut; the whole mesh shows only its outside
tan = (t[:, :, 0] > t[:, :, 2] + 40) & (t[:, :, 1] > t[:, :, 2] + 20)
lungr = (t[:, :, 1] > t[:, :, 0] + 20) & (t[:, :, 1] > t[:, :, 2] + 20)
assert drawn.sum() > 0.3 * drawn.size and tan.sum() > 2000 and lungr.sum() > 2000, (drawn.sum(), tan.sum(), lungr.sum())
lungr_all = (ta[:, :, 1] > ta[:, :, 0] + 20) & (ta[:, :, 1] > ta[:, :, 2] + 20)
assert lungr_all.sum() < 0.05 * lungr.sum(), lungr_all.sum()
print('e2e_report: %d electrode spheres seen; the clipped mesh shows the torso and lung regions (%d, %d pixels)' %
      ((sizes > 10).sum(), tan.sum(), lungr.sum()))
EOF

# --- the results page ------------------------------------------------------------------------
printf 'contours\t1.00\nforward solution\t2.50\n' > timings.txt
cp tetrahedra.png electrodes_left.png
"$PY" "$SRC/scripts/demo_report.py" . > report.log
grep -q "^demo: wrote ./index.html (lead II peak" report.log || fail "demo_report.py: $(cat report.log)"
"$PY" - <<'EOF' || fail "results page"
import html.parser, json, os, re
class P(html.parser.HTMLParser):
    def __init__(s):
        super().__init__(); s.imgs = []; s.text = []; s.rows = []; s.cell = None; s.row = None
    def handle_starttag(s, tag, a):
        a = dict(a)
        if tag == 'img': s.imgs.append(a['src'])
        if tag == 'tr': s.row = []
        if tag in ('td', 'th'): s.cell = ''
    def handle_endtag(s, tag):
        if tag in ('td', 'th') and s.row is not None: s.row.append(s.cell.strip()); s.cell = None
        if tag == 'tr': s.rows.append(s.row); s.row = None
    def handle_data(s, d):
        s.text.append(d)
        if s.cell is not None: s.cell += d
p = P(); p.feed(open('index.html').read())
text = ''.join(p.text)
chk = json.load(open('check.json')); model = json.load(open('model/model.json'))
for src in p.imgs: assert os.path.exists(src), src
assert 'ecg12.svg' in p.imgs and 'electrodes_anterior.png' in p.imgs and 'tetrahedra.png' in p.imgs, p.imgs
glance = {r[0]: r[1] for r in p.rows if r and len(r) == 2}
v = chk['volume']
assert '{:,} nodes, {:,} tetrahedra'.format(v['nodes'], v['tetrahedra']) in glance['volume mesh'], glance['volume mesh']
E = [[float(x) for x in l.split()] for l in open('solution/ecg12.txt') if l[:1] in '-0123456789' and len(l.split()) > 20]
assert ('peak %.2f mV' % max(E[1])) in glance['lead II'], glance['lead II']
assert 'dipole 0.016 mA m' in glance['source'], glance['source']
assert glance['checks'].startswith('all passed')
# one dipole: the 8 independent leads have rank 3; the page's singular values are numpy's
import numpy as np
sv = np.linalg.svd(np.array([E[0], E[1]] + E[6:12]), compute_uv=False)
m = re.search(r'singular values (\S+), (\S+), (\S+), then (\S+) \(relative (\S+)\)', glance['one dipole'])
assert m, glance['one dipole']
page_sv = [float(x) for x in m.groups()[:4]]
assert all(abs(a - b) < 2e-3 * sv[0] for a, b in zip(page_sv[:3], sv[:3])), (page_sv, sv)
assert page_sv[3] < 1e-9 * sv[0] and sv[3] < 1e-9 * sv[0], (page_sv, sv)
# the conductivity table: one row a region, sigma as in model.json
cond = {r[0]: r[1] for r in p.rows if r and len(r) == 5 and r[0] != 'region'}
assert set(cond) == {r['name'] for r in model['regions']}, cond
for r in model['regions']:
    s = r['sigma']
    want = ('%g' % s) if not isinstance(s, list) else 'tensor diag(%s)' % ', '.join('%g' % s[k][k] for k in range(3))
    assert cond[r['name']] == want, (r['name'], cond[r['name']], want)
missing = re.findall(r'\(([^)]*): not made in this run\)', text)
print('e2e_report: the page names %d pictures, all present; missing noted: %s; glance and conductivity table match the files'
      % (len(p.imgs), ', '.join(missing) or 'none'))
EOF
echo "e2e_report: ok"
