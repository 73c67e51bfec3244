#!/usr/bin/env bash
# thorax animate --keys end to end (issue 16, item 4): a 24-frame closed flight round the medium
# phantom; the pictures at the key frames equal thorax render's with the key's camera (pixel
# comparison, VTK's PNG reader); the lungs swap sides as the camera goes round (pixel facts) and the
# orientation letters change; data frames follow the keys; named views; resuming (a changed key
# file redraws); the viewer flying the same file (action fly); real data (map3d's Dalhousie torso and
# its dipole series); bad key files refused with file:line, nothing written; the MP4 read by ffprobe.
set -euo pipefail
: "${THORAX:?}" "${WORK:?}" "${SRC:?}"
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK"
PY=/usr/bin/python3
fail() { echo "FAIL: $*"; exit 1; }

. "$(dirname "$0")/medium_phantom.sh"
medium_phantom || fail "the medium phantom"

# the torso's box centre, the flight's target; a series on the torso (rows = nodes, 5 frames):
# value = (z - zc) * (frame - 3), so frame 3 is zero everywhere and frames 1 and 5 opposite
read -r CX CY CZ N < <($PY - <<'EOF'
import numpy as np
p = np.loadtxt('model/torso.pts')
c = (p.min(0) + p.max(0)) / 2
print('%.6f %.6f %.6f %d' % (c[0], c[1], c[2], len(p)))
v = np.array([(p[:, 2] - c[2]) * (k - 3) for k in range(1, 6)]).T
np.savetxt('torso.csv', v, delimiter=',', fmt='%.6f')
EOF
)
R=1200
# keys every 90 degrees, 6 frames apart; the first key's fields carry on; closed: back where it began
$PY - "$CX" "$CY" "$CZ" "$R" > fly.keys <<'EOF'
import sys, math
cx, cy, cz, r = map(float, sys.argv[1:])
print('# a flight round the torso\nends closed')
for k, a in enumerate(range(0, 361, 90)):
    x, y = cx + r * math.sin(math.radians(a)), cy + r * math.cos(math.radians(a))
    extra = ' target %.6f,%.6f,%.6f up 0,0,1 fov 30' % (cx, cy, cz) if k == 0 else ''
    data = {0: ' data 1', 2: ' data 3', 4: ' data 5'}.get(k, '')
    print('%d eye %.6f,%.6f,%.6f%s%s' % (1 + 6 * k, x, y, cz, extra, data))
EOF
cat fly.keys
A=(model --size 240x240 --surface lung_l=flat:1:#00ff00 --surface lung_r=flat:1:#ff00ff --only lung_l --only lung_r)
"$THORAX" animate "${A[@]}" --keys fly.keys -o fly -q
for f in $(seq 1 25); do [ -s "fly/$(printf 'frame_%05d.png' "$f")" ] || fail "frame $f missing"; done
[ ! -e fly/frame_00026.png ] || fail "a frame past the last key"
n=$(ffprobe -v error -count_frames -select_streams v:0 -show_entries stream=nb_read_frames -of csv=p=0 fly/animation.mp4)
[ "$n" = 25 ] || fail "the movie has $n frames, not 25"

# the key frames against thorax render with each key's camera
for k in 0 1 2 3; do
    cam=$($PY -c "
import math; a = math.radians(90 * $k)
print('%.6f,%.6f,%.6f:%s,%s,%s:0,0,1:30' % ($CX + $R * math.sin(a), $CY + $R * math.cos(a), $CZ, '$CX', '$CY', '$CZ'))")
    "$THORAX" render "${A[@]}" --camera "$cam" -o "key$k.png" -q
done
# the data keys: movie frame 13 (a key, data 3) as render --frame 3 with --data, and frame 7 (data 2)
DA=(model --size 240x240 --data torso.csv --only torso --scope fixed:-400:400)
"$THORAX" animate "${DA[@]}" --keys fly.keys -o flyd --mp4 none -q
cam2=$($PY -c "print('%.6f,%.6f,%.6f:$CX,$CY,$CZ:0,0,1:30' % ($CX, $CY - $R, $CZ))")
"$THORAX" render "${DA[@]}" --camera "$cam2" --frame 3 -o data3.png -q
"$THORAX" render "${DA[@]}" --camera "$cam2" --frame 5 -o data5.png -q
# named views: the same flight written with view names lands on the standard views' sides
cat > views.keys <<EOF
ends closed
1 view anterior distance $R fov 30
7 view left
13 view posterior
19 view right
25 view anterior
EOF
"$THORAX" animate "${A[@]}" --keys views.keys --orientation --frames 1:13 --mp4 none -o flyv -q
"$THORAX" animate "${A[@]}" --orientation --camera "$($PY -c "print('%.6f,%.6f,%.6f:$CX,$CY,$CZ:0,0,1:30' % ($CX, $CY + 1, $CZ))")" \
    --keys fly.keys -o never -q 2>err.txt && fail "--keys with --camera accepted"
grep -q "the key file gives the camera" err.txt || fail "--keys with --camera: $(cat err.txt)"

$PY - <<'EOF'
import vtk, numpy as np
from vtk.util.numpy_support import vtk_to_numpy
def png(p):
    r = vtk.vtkPNGReader(); r.SetFileName(p); r.Update()
    im = r.GetOutput(); w, h, _ = im.GetDimensions()
    return vtk_to_numpy(im.GetPointData().GetScalars()).reshape(h, w, -1)[::-1][:, :, :3].astype(int)
def differ(a, b):
    return int((np.abs(a - b).max(axis=2) > 8).sum())
# key frames 1, 7, 13, 19 (and 25, the first again) equal thorax render's pictures of the key's camera
for k in range(4):
    a, b = png('fly/frame_%05d.png' % (1 + 6 * k)), png('key%d.png' % k)
    d = differ(a, b)
    assert d <= 5, 'key %d: %d pixels differ from thorax render' % (k, d)
    print('key frame %d: %d pixels differ from thorax render --camera' % (1 + 6 * k, d))
assert differ(png('fly/frame_00025.png'), png('key0.png')) <= 5, 'the closed flight ends where it began'
# the lungs as the camera goes round: green (left lung) right of magenta (right lung) from the front,
# left of it from the back; from the sides one hides the other
def lungs(p):
    a = png(p)
    g = (a[:, :, 1] > 150) & (a[:, :, 0] < 100)
    m = (a[:, :, 0] > 150) & (a[:, :, 2] > 150) & (a[:, :, 1] < 100)
    xs = np.arange(a.shape[1])[None, :]
    gx = (g * xs).sum() / max(g.sum(), 1); mx = (m * xs).sum() / max(m.sum(), 1)
    return g.sum(), m.sum(), gx, mx
sep = []
for f in range(1, 26):
    g, m, gx, mx = lungs('fly/frame_%05d.png' % f)
    sep.append(gx - mx if g > 50 and m > 50 else 0.0)
    if f in (1, 7, 13, 19): print('frame %2d: green %5d px at x %.0f, magenta %5d px at x %.0f' % (f, g, gx, m, mx))
assert sep[0] > 20, 'anterior: the left lung should be on the image right: %.0f' % sep[0]
assert sep[12] < -20, 'posterior: the left lung should be on the image left: %.0f' % sep[12]
assert lungs('fly/frame_00007.png')[0] < 0.5 * lungs('fly/frame_00001.png')[0], 'right view: the left lung hidden behind the right'
# the separation shrinks smoothly from front to back (no jumps between frames)
steps = np.abs(np.diff(sep[:13]))
assert steps.max() < 0.6 * abs(sep[0] - sep[12]), steps
# data frames: frame 13 shows data frame 3 (zero: white), frame 1 data frame 1, frame 25 data frame 5
d13, d3 = png('flyd/frame_00013.png'), png('data3.png')
assert differ(d13, d3) <= 5, 'movie frame 13 is not data frame 3: %d' % differ(d13, d3)
assert differ(d13, png('data5.png')) > 1000, 'data frames 3 and 5 alike'
assert differ(d13, png('flyd/frame_00012.png')) > 100, 'frames 12 and 13 alike'
# the named-view flight: its posterior key is the orientation letters' L ... R, its anterior R ... L
v1, v13 = png('flyv/frame_00001.png'), png('flyv/frame_00013.png')
assert differ(v1, v13) > 1000
w = v1.shape[1]
def letters(a):  # bright text pixels at the left and right edges
    t = (a.min(axis=2) > 200)
    return t[:, :20].sum(), t[:, w - 20:].sum()
assert sum(letters(v1)) > 10 and sum(letters(v13)) > 10, 'orientation letters'
l1, l13 = v1[:, :20], v13[:, :20]
assert differ(l1, l13) > 10, 'the letter at the left edge is the same from the front and the back'
print('named views: letters drawn, left edge changes from the front to the back')
EOF

# resuming: the same run keeps every frame; a changed key file redraws them all
out=$("$THORAX" animate "${A[@]}" --keys fly.keys -o fly --mp4 none)
echo "$out" | grep -q "25 frames (0 drawn, 25 kept" || fail "resume: $out"
sed -i 's/fov 30/fov 28/' fly.keys
out=$("$THORAX" animate "${A[@]}" --keys fly.keys -o fly --mp4 none 2>&1)
echo "$out" | grep -q "25 frames (25 drawn, 0 kept" || fail "a changed key file reused frames: $out"
echo "$out" | grep -q "other settings" || fail "no word of the changed settings: $out"
# a key file copied over with its old time kept (cp -p) is still told apart by its content
cp -p fly.keys fly.keys.orig
sed 's/fov 28/fov 26/' fly.keys.orig > fly.keys.new
touch -r fly.keys.orig fly.keys.new
cp -p fly.keys.new fly.keys
out=$("$THORAX" animate "${A[@]}" --keys fly.keys -o fly --mp4 none 2>&1)
echo "$out" | grep -q "25 frames (25 drawn, 0 kept" || fail "a key file of the same size and time reused frames: $out"
cp -p fly.keys.orig fly.keys
out=$("$THORAX" animate "${A[@]}" --keys fly.keys -o fly --mp4 none 2>&1)
echo "$out" | grep -q "25 frames (25 drawn, 0 kept" || fail "the key file put back reused frames: $out"

# the viewer flies the same key file (action fly), recording each frame: its pictures are animate's
# (the viewer's part is left out under the sanitizers, THORAX_QUICK: e2e_view covers the viewer)
if [ -z "${THORAX_QUICK:-}" ]; then
cat > fly.txt <<EOF
$PWD/model
--size 240x240
--surface lung_l=flat:1:#00ff00
--surface lung_r=flat:1:#ff00ff
--only lung_l
--only lung_r
action record $PWD/vrec
action fly $PWD/fly.keys
action record-stop
quit
EOF
xvfb-run -a -s "-screen 0 800x600x24" "$THORAX" view --script fly.txt > fly.out 2> fly.err || { cat fly.err; fail "view: action fly"; }
printf '1 eye 0,-900,100 target 0,0,100 up 0,0,1 fov 30\n5 eye 0,-900,100 up 0,1,0\n' > vbad.keys
printf '%s\naction fly %s\nquit\n' "$PWD/model" "$PWD/vbad.keys" > vbad.txt
xvfb-run -a -s "-screen 0 800x600x24" "$THORAX" view --script vbad.txt > /dev/null 2> vbad.err && fail "view: a bad key file flown"
grep -q "vbad.txt:2: .*vbad.keys:2: up 0,1,0 is along the view direction" vbad.err || fail "view: bad keys: $(cat vbad.err)"
$PY - <<'EOF'
import vtk, numpy as np, glob
from vtk.util.numpy_support import vtk_to_numpy
def png(p):
    r = vtk.vtkPNGReader(); r.SetFileName(p); r.Update()
    im = r.GetOutput(); w, h, _ = im.GetDimensions()
    return vtk_to_numpy(im.GetPointData().GetScalars()).reshape(h, w, -1)[::-1][:, :, :3].astype(int)
rec = sorted(glob.glob('vrec/frame_*.png'))
assert len(rec) >= 25, 'the viewer recorded %d frames' % len(rec)
rec = rec[-25:]   # the flight's 25 frames are the last ones drawn
worst = 0
for f in (1, 4, 7, 13, 22):
    a, b = png(rec[f - 1]), png('fly/frame_%05d.png' % f)
    if a.shape != b.shape:  # the window may be wider than asked: the same vertical field, the middle compared
        assert a.shape[0] == b.shape[0] and a.shape[1] >= b.shape[1], (a.shape, b.shape)
        x0 = (a.shape[1] - b.shape[1]) // 2
        a = a[:, x0:x0 + b.shape[1]]
    d = int((np.abs(a - b).max(axis=2) > 24).sum())
    worst = max(worst, d)
    assert d < 0.01 * a.shape[0] * a.shape[1], 'viewer frame %d differs from animate in %d pixels' % (f, d)
print('viewer flight: %d frames recorded; at most %d pixels differ from thorax animate --keys' % (len(rec), worst))
EOF
fi

# real data: map3d's Dalhousie torso (no anatomical frame in the file: --up and --front) round which
# the camera flies while its six dipole frames play; the closed flight ends on the picture it began with
if [ -z "${THORAX_QUICK:-}" ]; then # (not under the sanitizers: the plain suite flies it)
DAL="$SRC/../shared/data/map3d"
cat > dal.keys <<EOF
ends closed
1  view anterior distance 1500 fov 30 data 1
13 view left
25 view posterior data 6
37 view right
49 view anterior data 1
EOF
"$THORAX" animate "$DAL/geom/torso/daltorso.pts" --data "$DAL/data/torso/dipole2.tsdf" --up -y --front -z \
    --keys dal.keys --orientation --colorbar --size 200x200 --mp4 none -o dal -q
[ "$(ls dal/frame_*.png | wc -l)" = 49 ] || fail "the Dalhousie flight: $(ls dal | wc -l) files"
cmp -s dal/frame_00001.png dal/frame_00049.png || fail "the closed flight does not end on its first picture"
cmp -s dal/frame_00001.png dal/frame_00025.png && fail "the flight's posterior frame is its anterior one"
fi

# bad key files: the file, the line and the field named; exit non-zero; no output directory
bad() { # FILE-TEXT EXPECTED
    printf '%b' "$1" > bad.keys
    if "$THORAX" animate "${A[@]}" --keys bad.keys -o badout -q 2>err.txt; then fail "accepted: $1"; fi
    grep -qF "$2" err.txt || fail "expected '$2', got: $(cat err.txt)"
    [ ! -e badout ] || fail "badout written for: $1"
}
K1="1 eye 0,-900,100 target 0,0,100 up 0,0,1 fov 30\n"
bad "${K1}5 eye 900,0,100\n5 eye 0,900,100\n" "bad.keys:3: frame 5: not after the previous key's frame 5 (line 2)"
bad "${K1}5 eye 900,0,100 up 1,0,0\n" "bad.keys:2: up 1,0,0 is along the view direction"
bad "$K1" "bad.keys: 1 key: a camera flight needs at least 2"
bad "${K1}5 eye nan,0,100\n" "bad.keys:2: eye 'nan,0,100': three finite numbers"
bad "${K1}5 view sideways\n" "bad.keys:2: view 'sideways'"
bad "${K1}5 eye 0,900,100\n" "bad.keys:2: the camera turns 180.0 degrees"
printf '1 eye 0,-900,100 target 0,0,100 up 0,0,1 fov 30\n5 eye 900,0,100 data 9\n' > bad.keys
"$THORAX" animate "${DA[@]}" --keys bad.keys -o badout -q 2>err.txt && fail "data frame 9 of 5 accepted"
grep -qF "bad.keys: movie frame 1 shows data frame 9: the data has 5 frames" err.txt || fail "data 9: $(cat err.txt)"
[ ! -e badout ] || fail "badout written for data 9"
"$THORAX" animate "${A[@]}" --keys missing.keys -o badout -q 2>err.txt && fail "a missing key file accepted"
grep -q "missing.keys" err.txt || fail "missing key file: $(cat err.txt)"
echo "e2e_camera_keys: OK"
