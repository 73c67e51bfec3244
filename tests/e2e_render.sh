#!/usr/bin/env bash
# thorax render / animate end to end, headless: pictures of the medium phantom with its
# forward solution (views, clip plane, colour bar, label, ECG trace, arrows, panels,
# orientation check), pixel facts read back with VTK's PNG reader, an animation whose
# MP4 ffprobe reads, resuming, and bad input (rows, NaN, unwritable path, no EGL).
set -euo pipefail
: "${THORAX:?}" "${WORK:?}" "${SRC:?}"
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK"
PY=/usr/bin/python3
fail() { echo "FAIL: $*"; exit 1; }

# the medium phantom meshed without the heart (tests/medium_phantom.sh)
. "$(dirname "$0")/medium_phantom.sh"
medium_phantom || fail "the medium phantom"
"$THORAX" electrodes model -q
"$THORAX" beat model -o beat.raw --frames 300 -q
"$THORAX" forward model --epicardial beat.raw -o sol --currents 193 -q
"$THORAX" leads sol -q

R=(--solution sol --frame 193 --size 400x480)
"$THORAX" render "${R[@]}" --view anterior -o ant.png -q
"$THORAX" render "${R[@]}" --view posterior --colorbar --label --trace II -o post.png -q
"$THORAX" render "${R[@]}" --view anterior --clip anterior:0.8 -o clip.png -q
"$THORAX" render "${R[@]}" --view left --style bands+contours --levels 10 -o bands.png -q
"$THORAX" render "${R[@]}" --view anterior --clip anterior:0.55 --arrows --surface torso=wire:0.2 -o arrows.png -q
"$THORAX" render "${R[@]}" --view anterior --clip anterior:0.55 --arrows --arrow-region lung_l --surface torso=wire:0.2 -o arrows_lung.png -q
"$THORAX" render "${R[@]}" --view anterior --clip anterior:0.55 --arrows --arrow-box -100:-50:80:0:60:140 --surface torso=wire:0.2 -o arrows_box.png -q
"$THORAX" render "${R[@]}" --view anterior --clip anterior:0.55 --arrows --arrow-spacing 0 --arrow-gap 15 --arrow-max 60 --surface torso=wire:0.2 -o arrows_gap.png -q
"$THORAX" render model --size 600x400 --panels --mode orientation -o orient.png -q
"$THORAX" render model --size 300x300 --mode wire --view superior -o wire.png -q
"$THORAX" render model --size 300x300 --surface lung_l=flat:1:#00ff00 --surface lung_r=flat:1:#ff00ff --only lung_l --only lung_r -o look.png -q
"$THORAX" render "${R[@]}" --view anterior --trace torso:100 -o node.png -q
"$THORAX" render "${R[@]}" --view anterior --only torso --only lung_l --surface torso=hidden -o grey.png -q

$PY - <<'EOF'
import vtk
from vtk.util.numpy_support import vtk_to_numpy
def png(p):
    r = vtk.vtkPNGReader(); r.SetFileName(p); r.Update()
    im = r.GetOutput(); w, h, _ = im.GetDimensions()
    a = vtk_to_numpy(im.GetPointData().GetScalars()).reshape(h, w, -1)[::-1]   # rows top to bottom
    return a[:, :, :3].astype(int)
a = png('ant.png'); h, w, _ = a.shape
assert (w, h) == (400, 480), (w, h)
bg = a[0, 0]
for y, x in ((0, 0), (0, w - 1), (h - 1, 0), (h - 1, w - 1)):
    assert (a[y, x] == bg).all(), 'corner not background'
# the QRS peak on the anterior torso: positive (red) at the subject's lower left (image right, low),
# negative (blue) at the upper right (image left, high)
red = (a[:, :, 0] > a[:, :, 2] + 60) & (a[:, :, 0] > a[:, :, 1] + 40)
blue = (a[:, :, 2] > a[:, :, 0] + 60)
ys, xs = red.nonzero(); yb, xb = blue.nonzero()
assert red.sum() > 500 and blue.sum() > 500, (red.sum(), blue.sum())
assert xs.mean() > xb.mean(), 'red should lie right of blue (the subject left) in the anterior view'
print('anterior: %d red, %d blue pixels; red centre x %.0f, blue %.0f' % (red.sum(), blue.sum(), xs.mean(), xb.mean()))
# the clip plane opens the front of the torso: the image differs where the heart shows
c = png('clip.png')
assert (abs(c - a).sum(axis=2) > 30).sum() > 2000, 'clip changed nothing'
# bands + contours: a handful of distinct colours on the torso plus dark contour pixels
b = png('bands.png')
dark = (b.sum(axis=2) < 120) & ~(b == bg).all(axis=2)
assert dark.sum() > 200, ('contour pixels', dark.sum())
# the annotated picture: colour bar and trace change the right and bottom strips
p = png('post.png')
assert (abs(p[-60:, :] - bg).sum(axis=2) > 40).sum() > 300, 'no trace'
# arrows (yellow): everywhere, and fewer when limited to the left lung or a box
def yellow(p):
    x = png(p); return (x[:, :, 0] > 200) & (x[:, :, 1] > 170) & (x[:, :, 2] < 90)
def arrows(p):
    return yellow(p).sum()
na, nl, nb = arrows('arrows.png'), arrows('arrows_lung.png'), arrows('arrows_box.png')
ng = arrows('arrows_gap.png')
assert na > 200 and nl > 50 and nb < na and 0 < ng < na, (na, nl, nb, ng)
# the left lung's arrows lie in the image's right half (anterior view), the whole set spreads over both
yl, ya = yellow('arrows_lung.png').nonzero()[1], yellow('arrows.png').nonzero()[1]
w2 = png('arrows.png').shape[1] / 2
assert (yl > w2).mean() > 0.8 and (ya > w2).mean() < 0.8, ((yl > w2).mean(), (ya > w2).mean())
print('arrow pixels: all %d, left lung %d, box %d, 60 per node 15 mm apart %d' % (na, nl, nb, ng))
o = png('orient.png')
assert (abs(o - o[0, 0]).sum(axis=2) > 40).sum() > 5000, 'orientation panels empty'
# per-surface colours: the left lung green, the right lung magenta, nothing else drawn
k = png('look.png')
green = (k[:, :, 1] > 60) & (k[:, :, 0] < 20) & (k[:, :, 2] < 20)
magenta = (k[:, :, 0] > 60) & (k[:, :, 2] > 60) & (k[:, :, 1] < 20)
other = ~(green | magenta) & (abs(k - k[0, 0]).sum(axis=2) > 30)
assert green.sum() > 2000 and magenta.sum() > 2000, (green.sum(), magenta.sum())
assert green.nonzero()[1].mean() > magenta.nonzero()[1].mean(), 'left lung should be at the image right (anterior view)'
assert other.sum() < 0.05 * (green.sum() + magenta.sum()), ('other colours', other.sum())
# a node's signal as the trace: the bottom strip is drawn
n = png('node.png')
assert (abs(n[-90:, :] - bg).sum(axis=2) > 40).sum() > 300, 'no node trace'
# beside data, surfaces without data are grey: colour means potential
g = png('grey.png')
drawn = abs(g - g[0, 0]).sum(axis=2) > 20
spread = g.max(axis=2) - g.min(axis=2)
assert drawn.sum() > 2000 and (spread[drawn] <= 8).mean() > 0.99, (drawn.sum(), spread[drawn].max())
print('render checks passed')
EOF

# animation: 6 frames + MP4, then resume (kept), then ffprobe counts the frames
"$THORAX" animate --solution sol --frames 180:185 --size 320x360 --colorbar --label --fps 10 -o anim -q
ls anim/frame_00180.png anim/frame_00185.png > /dev/null
[ "$(ls anim/frame_*.png | wc -l)" -eq 6 ] || fail "frame count"
rm anim/frame_00183.png
"$THORAX" animate --solution sol --frames 180:185 --size 320x360 --colorbar --label --fps 10 -o anim > resume.log
grep -q "1 drawn, 5 kept" resume.log || { cat resume.log; fail "not resumed"; }
# other settings: no frame of the earlier run is kept (they would mix two looks in one movie)
"$THORAX" animate --solution sol --frames 180:185 --size 320x360 --colorbar --label --cmap viridis --fps 10 -o anim --mp4 none > other.log 2>&1
grep -q "6 drawn, 0 kept" other.log || { cat other.log; fail "stale frames kept"; }
grep -q "other settings" other.log || { cat other.log; fail "no notice of the redraw"; }
n=$(ffprobe -v error -count_frames -select_streams v:0 -show_entries stream=nb_read_frames -of csv=p=0 anim/animation.mp4)
codec=$(ffprobe -v error -select_streams v:0 -show_entries stream=codec_name -of csv=p=0 anim/animation.mp4)
[ "$n" = 6 ] && [ "$codec" = h264 ] || fail "mp4: $n frames, codec $codec"
# the movie is thorax's own (its metadata comment, in the header by +faststart); a user's movie of
# that name stops the run before any frame is drawn, and is left as it was
# (read into a file first: grep -q leaving early would kill head with SIGPIPE, a failure under pipefail)
head -c 4194304 anim/animation.mp4 > movie_head.bin
grep -qa "thorax-movie" movie_head.bin || fail "the movie carries no signature in its header"
printf 'my holiday video' > anim/mine.mp4
if "$THORAX" animate --solution sol --frames 180:185 --size 320x360 --colorbar --label --fps 10 -o anim --mp4 anim/mine.mp4 -q 2> mine.err; then
    fail "animate replaced a user's movie"
fi
grep -q "is not thorax's own output of this kind" mine.err || { cat mine.err; fail "the refusal does not say why"; }
[ "$(cat anim/mine.mp4)" = "my holiday video" ] || fail "the user's movie changed"
ls anim | grep -q "\.tmp" && fail "a temporary file was left in anim/"

# bad input
refused() { local what=$1 file=$2; shift 2
    if "$@" > out.log 2> err.log; then fail "$what: accepted"; fi
    [ -s err.log ] || fail "$what: no message"; [ ! -e "$file" ] || fail "$what: $file written"
    echo "refused ($what): $(head -1 err.log)"; }
head -c 200 beat.raw > /dev/null
refused "rows" bad1.png "$THORAX" render model --data beat.raw --data-surface torso -o bad1.png
refused "unwritable" /nonexistent/x.png "$THORAX" render model -o /nonexistent/x.png
refused "surface name" bad4.png "$THORAX" render model --surface liver=flat -o bad4.png
refused "surface spec" bad4.png "$THORAX" render model --surface torso=flat:0.5:#12 -o bad4.png
refused "trace lead" bad4.png "$THORAX" render --solution sol --trace X7 -o bad4.png
refused "trace node" bad4.png "$THORAX" render --solution sol --trace torso:99999 -o bad4.png
refused "arrows frame" bad4.png "$THORAX" render --solution sol --frame 100 --arrows -o bad4.png
refused "arrow region" bad4.png "$THORAX" render "${R[@]}" --arrows --arrow-region liver -o bad4.png
refused "frame" bad2.png "$THORAX" render --solution sol --frame 999 -o bad2.png
refused "no EGL" bad3.png env EGL_PLATFORM=none LIBGL_DRIVERS_PATH=/nonexistent __EGL_VENDOR_LIBRARY_FILENAMES=/nonexistent.json "$THORAX" render model -o bad3.png
grep -qi "egl" err.log || fail "EGL message"
# NaN values: drawn in the NaN colour, counted in a warning, no crash
$PY - <<'EOF'
import numpy as np
b = open('beat.raw', 'rb').read(); r, f = (int(x) for x in np.frombuffer(b[8:24], dtype='<u8'))
d = np.frombuffer(b[200:], dtype='<f8').copy(); d[f + 10: f + 20] = np.nan
open('nan.raw', 'wb').write(b[:200] + d.tobytes())
EOF
"$THORAX" render model --data nan.raw --data-surface heart --size 200x200 --only heart -o nan.png 2> nan.log
grep -q "10 values are not numbers" nan.log || { cat nan.log; fail "NaN warning"; }
# The symmetric colour range is the largest magnitude, whichever side it is on (issue 11, item 9):
# values -5..2 (the negative side dominates) draw exactly as the fixed range -5..5, not as -2..2
# (the range a rule taking the largest value would give). `thorax render` takes its range from the
# library's one rule (thx_scale_from_range).
nheart=$($PY -c "import json; print([s['n_nodes'] for s in json.load(open('model/model.json'))['surfaces'] if s['role'] == 'heart'][0])")
$PY - "$nheart" <<'EOF2'
import sys
n = int(sys.argv[1])
rows = ['2'] * n
for k in range(0, n, 3): rows[k] = '-5'
open('neg.txt', 'w').write('thorax-series 1\nrows %d\nframes 1\nunit mV\ntime_unit ms\nlabel negative side dominates\nt0 0\ndt 1\n%s\nend\n' % (n, '\n'.join(rows)))
EOF2
for r in sym:--symmetric f55:--scope=fixed:-5:5 f22:--scope=fixed:-2:2; do
    name=${r%%:*}; opt=${r#*:}
    "$THORAX" render model --data neg.txt --data-surface heart --only heart --size 160x160 ${opt/=/ } -o neg_$name.png -q ||
        fail "render of the -5..2 data ($opt)"
done
cmp -s neg_sym.png neg_f55.png || fail "symmetric range of -5..2 data is not -5..5"
cmp -s neg_sym.png neg_f22.png && fail "symmetric range of -5..2 data drawn as -2..2"
echo "e2e_render: symmetric range of -5..2 data = -5..5 (image identical to --scope fixed:-5:5)"
# red_blue PNG MIN WHAT: at least MIN red (positive) and MIN blue (negative) pixels; prints the counts
red_blue() {
    $PY - "$1" "$2" "$3" <<'EOF2'
import sys, vtk
from vtk.util.numpy_support import vtk_to_numpy
r = vtk.vtkPNGReader(); r.SetFileName(sys.argv[1]); r.Update()
im = r.GetOutput(); w, h, _ = im.GetDimensions()
a = vtk_to_numpy(im.GetPointData().GetScalars()).reshape(h, w, -1)[::-1, :, :3].astype(int)
red = ((a[:, :, 0] > a[:, :, 2] + 60) & (a[:, :, 0] > a[:, :, 1] + 40)).sum()
blue = (a[:, :, 2] > a[:, :, 0] + 60).sum()
assert red > int(sys.argv[2]) and blue > int(sys.argv[2]), (red, blue)
print('%s: %d red, %d blue pixels' % (sys.argv[3], red, blue))
EOF2
}

# real measured data: the 490-electrode epicardial sock (an open surface, drawn with a warning)
# and its recording (map3d's ts struct: potvals in mV, samplefrequency 1000 Hz), no model needed
SOCK="$SRC/../shared/data/map3d/geom/socks/490sock.pts"
REC="$SRC/../shared/data/map3d/data/socks/10jan01/rsm10jan01-cs-0004.mat"
"$THORAX" series info "$REC" > rec.txt
grep -q "0 .. 711 ms" rec.txt || { cat rec.txt; fail "sock recording's time axis"; }
"$THORAX" render "$SOCK" --data "$REC" --frame 277 --scope frame --style continuous+contours --colorbar --label \
    --trace 245 --size 400x400 -o sock.png 2> sock.log
grep -q "drawn as it is, although not closed" sock.log || { cat sock.log; fail "open sock warning"; }
red_blue sock.png 300 "measured sock at 276 ms"
# the Utah tank experiment: 512-channel recording, the epicardial sock's 128 leads on channels
# 193..320 (map3d's .channels file)
TANK="$SRC/../shared/data/map3d"
"$THORAX" render "$TANK/geom/tank/25feb97_sock.pts" --data "$TANK/data/tank/cool1-atdr-run1.mat" \
    --channels "$TANK/geom/tank/sock128.channels" --frame 185 --scope frame --colorbar --size 300x300 -o tank.png -q 2> /dev/null
red_blue tank.png 200 "tank sock by channel, frame 185"
printf '2 leads\n1 5\n2 999\n' > bad.channels
refused "channels" bad5.png "$THORAX" render "$TANK/geom/tank/25feb97_sock.pts" --data "$TANK/data/tank/cool1-atdr-run1.mat" --channels bad.channels -o bad5.png
grep -q "bad.channels:3: channel 999 is not in 1..512" err.log || { cat err.log; fail "channels message"; }

# map3d's Dalhousie torso with one of its dipole .pot frames (a one-frame series)
DAL="$SRC/../shared/data/map3d"
# (its long axis is y, head at -y, anterior -z: --up and --front give the anatomical frame)
"$THORAX" render "$DAL/geom/torso/daltorso.pts" --data "$DAL/data/torso/dipole2_003.pot" --up -y --front -z \
    --style bands+contours --size 300x300 -o dal.png -q
"$THORAX" render "$DAL/geom/torso/daltorso.pts" --data "$DAL/data/torso/dipole2_003.pot" --up +y --front +z \
    --style bands+contours --size 300x300 -o dal_flip.png -q
"$THORAX" render "$DAL/geom/torso/daltorso.pts" --data "$DAL/data/torso/dipole2_003.pot" --up -y --front -z \
    --view left --clip anterior:0.5 --size 300x300 -o dal_clip.png -q
"$THORAX" render "$DAL/geom/torso/daltorso.pts" --data "$DAL/data/torso/dipole2_003.pot" --up -y --front -z \
    --view left --size 300x300 -o dal_left.png -q
$PY - <<'EOF2'
import vtk
from vtk.util.numpy_support import vtk_to_numpy
r = vtk.vtkPNGReader(); r.SetFileName('dal.png'); r.Update()
im = r.GetOutput(); w, h, _ = im.GetDimensions()
a = vtk_to_numpy(im.GetPointData().GetScalars()).reshape(h, w, -1)[::-1, :, :3].astype(int)
red = ((a[:, :, 0] > a[:, :, 2] + 60) & (a[:, :, 0] > a[:, :, 1] + 40)).sum()
blue = (a[:, :, 2] > a[:, :, 0] + 60).sum()
assert red > 200 and blue > 200, (red, blue)
print('Dalhousie torso, dipole frame 3: %d red, %d blue pixels' % (red, blue))
def load(p):
    r = vtk.vtkPNGReader(); r.SetFileName(p); r.Update()
    im = r.GetOutput(); w, h, _ = im.GetDimensions()
    return vtk_to_numpy(im.GetPointData().GetScalars()).reshape(h, w, -1)[::-1, :, :3].astype(int)
def widest_row(x):   # where the silhouette is widest, as a fraction of its height from the top
    drawn = abs(x - x[0, 0]).sum(axis=2) > 30
    rows = [r for r in range(x.shape[0]) if drawn[r].any()]
    top, bottom = rows[0], rows[-1]
    wmax = max(drawn[r].sum() for r in rows)
    r = [r for r in rows if drawn[r].sum() >= 0.97 * wmax]
    return (sum(r) / len(r) - top) / (bottom - top)
up, flip = widest_row(a), widest_row(load('dal_flip.png'))
assert up < 0.5 < flip, (up, flip)   # the shoulders in the upper half; upside down, in the lower
print('Dalhousie torso: widest at %.2f of the height from the top; with the axes reversed at %.2f' % (up, flip))
# the anterior half clipped away, seen from the left: the depth drawn is about half
def depth(p):   # columns drawn, and their mean (the left view has the posterior side at the right)
    x = load(p); cols = (abs(x - x[0, 0]).sum(axis=2) > 30).any(axis=0).nonzero()[0]
    return len(cols), cols.mean()
(dc, mc), (df, mf) = depth('dal_clip.png'), depth('dal_left.png')
assert 0.35 * df < dc < 0.7 * df and mc > mf, (dc, df, mc, mf)   # the posterior half is what is left
print('Dalhousie torso from the left: depth %d px, %d with the anterior half clipped' % (df, dc))
EOF2
# colour bars: one per distinct scale (the torso's and the heart's), one when they share a scale,
# and a picture too small for both refused with nothing written
"$THORAX" render "${R[@]}" --view anterior --colorbar -o bars2.png -q
"$THORAX" render "${R[@]}" --view anterior --colorbar --scope all -o bars1.png -q
"$THORAX" render "${R[@]}" --view anterior --clip anterior:0.55 --arrows --arrow-unit --colorbar -o bars3.png -q
if "$THORAX" render --solution sol --frame 193 --size 400x110 --colorbar -o bars_small.png 2> small.err; then fail "two bars in 110 rows accepted"; fi
[ ! -e bars_small.png ] || fail "refused picture written"
grep -q "2 different scales" small.err || { cat small.err; fail "refusal message"; }
"$THORAX" render --solution sol --frame 193 --size 400x110 --colorbar --scope all -o bars_small.png -q
# orientation letters on the Dalhousie torso (its own axes: up -y, front -z): anterior and posterior
DALO=("$DAL/geom/torso/daltorso.pts" --data "$DAL/data/torso/dipole2_003.pot" --up -y --front -z --size 300x300)
"$THORAX" render "${DALO[@]}" -o dal_plain.png -q
"$THORAX" render "${DALO[@]}" --orientation -o dal_ant.png -q
"$THORAX" render "${DALO[@]}" --orientation --view posterior -o dal_post.png -q
$PY - <<'EOF3'
import vtk, numpy as np
from vtk.util.numpy_support import vtk_to_numpy
def load(p):
    r = vtk.vtkPNGReader(); r.SetFileName(p); r.Update()
    im = r.GetOutput(); w, h, _ = im.GetDimensions()
    return vtk_to_numpy(im.GetPointData().GetScalars()).reshape(h, w, -1)[::-1, :, :3].astype(int)
def runs(p):   # the bars' strips: runs of 16 rows or more drawn over the background in the column
    a = load(p); w = a.shape[1]    # of the right sixth with the most saturated pixels
    sat = (a.max(axis=2) - a.min(axis=2)) > 60
    col = max(range(w - w // 6, w), key=lambda x: sat[:, x].sum())
    drawn = (abs(a[:, col] - a[0, 0]).sum(axis=1) > 30).astype(int)
    edges = np.flatnonzero(np.diff(np.concatenate([[0], drawn, [0]])))
    lengths = edges[1::2] - edges[0::2]
    return (lengths >= 16).sum(), lengths.max()
(n2, l2), (n1, l1), (n3, l3) = runs('bars2.png'), runs('bars1.png'), runs('bars3.png')
assert n2 == 2 and n1 == 1 and n3 == 3, (n2, n1, n3)   # arrows coloured by |J|: a third bar
print('colour bars: %d strips (%d rows) for the torso and heart scales, %d (%d rows) sharing one' % (n2, l2, n1, l1))
plain, ant, post = load('dal_plain.png'), load('dal_ant.png'), load('dal_post.png')
h, w, _ = plain.shape
def patch(img, x0, x1, y0, y1):   # the letter's pixels: the tight box of what differs from the plain picture
    d = (abs(img - plain).sum(axis=2) > 60)[y0:y1, x0:x1]
    ys, xs = d.nonzero()
    assert len(ys) > 5, ('no letter', x0, y0)
    return d[ys.min():ys.max() + 1, xs.min():xs.max() + 1]
aL, aR = patch(ant, 0, 30, h // 2 - 20, h // 2 + 20), patch(ant, w - 30, w, h // 2 - 20, h // 2 + 20)
pL, pR = patch(post, 0, 30, h // 2 - 20, h // 2 + 20), patch(post, w - 30, w, h // 2 - 20, h // 2 + 20)
# the anterior view's left letter (R) is the posterior view's right one, and not the anterior's right (L)
assert aL.shape == pR.shape and (aL == pR).all(), 'anterior left != posterior right'
assert aR.shape == pL.shape and (aR == pL).all(), 'anterior right != posterior left'
assert aL.shape != aR.shape or (aL != aR).any(), 'R and L drawn alike'
top, bottom = patch(ant, w // 2 - 20, w // 2 + 20, 0, 30), patch(ant, w // 2 - 20, w // 2 + 20, h - 30, h)
assert top.shape != bottom.shape or (top != bottom).any(), 'S and I drawn alike'
print('orientation letters on the Dalhousie torso: left %s, right %s, top %s, bottom %s pixels' % (aL.shape, aR.shape, top.shape, bottom.shape))
EOF3
echo "e2e_render: all checks passed"
