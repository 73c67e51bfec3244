#!/usr/bin/env bash
# thorax trace and --renderer trace (issue 27; RaySpray) on the phantom's model:
#  - render --renderer trace with the headlight alone and one sample sees what the OpenGL render
#    sees: the two pictures' foreground (not background) agree on >= 99.5 % of the pixels (up to the
#    silhouette's anti-aliased pixel), and their colours there within a few grey levels on average
#    (the same scale, colours and light);
#  - thorax trace with a glass torso shows the heart through it (red pixels the opaque picture has
#    none of), and the same bytes on 1 and 2 threads;
#  - bad lights and materials are refused by name (exit 2), nothing written;
#  - animate --renderer trace with a camera flight (--keys; 5 frames at 160x120, 1 sample, an
#    orthographic camera sliding sideways): every frame written, the movie when ffmpeg is there; a
#    second run redraws nothing (the frames' times unchanged), another --motion-blur redraws all; a
#    blurred frame differs from the unblurred one only near the edges that move between it and the
#    next frame; --motion-blur refused under OpenGL;
#  - thorax trace --frame F --motion-blur 1 on the phantom's solution: the potentials blurred towards
#    frame F + 1 (the picture differs), the last frame (nothing after it) the unblurred picture;
#  - on the medium phantom's solution: a scan's image plane (a label map of the model) traced as the
#    OpenGL renderer draws it (the same foreground, the same colours), current arrows traced as 3D
#    glyphs where the OpenGL renderer draws its own, and --volume potential --colorbar adds the
#    volume's bar (red to blue) to the surfaces' bars.
# Env: THORAX, SRC, WORK.
set -euo pipefail
: "${THORAX:?}" "${SRC:?}" "${WORK:?}"
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK"
PY=/usr/bin/python3
fail() { echo "e2e_trace: FAIL: $*" >&2; exit 1; }
"$THORAX" phantom -o c.txt -q
"$THORAX" surfaces c.txt -o m -q 2> /dev/null

"$THORAX" render m --size 320x320 -o gl.png -q || fail "render"
"$THORAX" render m --size 320x320 --renderer trace --samples 1 --ao 0 -o rt.png > rt.out || fail "render --renderer trace"
grep -q "traced with Embree 3" rt.out || fail "the traced picture's report: $(cat rt.out)"
OMP_NUM_THREADS=2 "$THORAX" trace m --size 320x320 --material torso=glass --material fat=transparent:0.9 \
    --material muscle=transparent:0.9 -o glass2.png -q || fail "trace, 2 threads"
OMP_NUM_THREADS=1 "$THORAX" trace m --size 320x320 --material torso=glass --material fat=transparent:0.9 \
    --material muscle=transparent:0.9 -o glass1.png -q || fail "trace, 1 thread"
cmp -s glass1.png glass2.png || fail "1 and 2 threads gave different pictures"
$PY - <<'EOF' || fail "the pictures"
import numpy as np
from PIL import Image
gl, rt, gs = [np.asarray(Image.open(f).convert('RGB')).astype(int) for f in ('gl.png', 'rt.png', 'glass1.png')]
bg = gl[0, 0]
fg_gl = np.abs(gl - bg).sum(axis=2) > 6
fg_rt = np.abs(rt - bg).sum(axis=2) > 6
# a silhouette pixel is part foreground in the anti-aliased OpenGL picture: a pixel disagrees only when
# no pixel next to it in the traced picture agrees with the OpenGL one
pad = np.pad(fg_rt, 1, mode='edge')
near = [pad[1 + dy:1 + dy + fg_rt.shape[0], 1 + dx:1 + dx + fg_rt.shape[1]] for dy in (-1, 0, 1) for dx in (-1, 0, 1)]
agree = 1 - ((fg_gl != fg_rt) & np.all([n != fg_gl for n in near], axis=0)).mean()
both = fg_gl & fg_rt
diff = np.abs(gl[both] - rt[both]).mean()
print("OpenGL and traced: foreground agrees on %.2f %% of the pixels, colours differ by %.1f levels on average" % (100 * agree, diff))
assert agree >= 0.995, agree
assert diff <= 6, diff
red = lambda im: ((im[..., 0] > im[..., 1] + 40) & (im[..., 0] > im[..., 2] + 40)).mean()
print("red (the heart): %.2f %% of the glass torso's picture, %.2f %% of the opaque one's" % (100 * red(gs), 100 * red(gl)))
assert red(gs) > 0.03 and red(gl) < 0.001
EOF
for bad in "--material torso=plastic" "--material =glass" "--light point:1,2" "--light spot:0,0,0" "--samples 0" "--material torso=glass:9"; do
    # shellcheck disable=SC2086
    if "$THORAX" trace m $bad -o bad.png 2> bad.err; then fail "'$bad' was taken"; fi
    [ ! -e bad.png ] || fail "'$bad' wrote a picture"
    grep -q -- "${bad%%[ =:]*}" bad.err || fail "'$bad': the message does not name the option: $(cat bad.err)"
done

# ---- animate --renderer trace with --keys, resuming, motion blur ----
# a flight sliding sideways: an orthographic camera, 60 mm in 4 frames (a few pixels a frame); lit
# from behind (the ambient term alone: each surface one flat colour), so that only what moves on
# the screen, the edges, changes from a frame to the next
read -r XL XR CY CZ EY HT < <($PY - <<'EOF'
import numpy as np
p = np.loadtxt('m/torso.pts')
c = (p.min(0) + p.max(0)) / 2
print('%.3f %.3f %.3f %.3f %.3f %.3f' % (c[0] - 30, c[0] + 30, c[1], c[2], c[1] + 1000, 1.3 * (p.max(0) - p.min(0))[2]))
EOF
)
cat > fly.keys <<EOF
# sideways, orthographic
1 eye $XL,$EY,$CZ target $XL,$CY,$CZ up 0,0,1 fov 0 height $HT
5 eye $XR,$EY,$CZ target $XR,$CY,$CZ
EOF
MOVIE=(--mp4 none)
if command -v ffmpeg > /dev/null; then MOVIE=(); fi
AN=(m --keys fly.keys --renderer trace --samples 1 --light directional:0,1,0 --size 160x120 -o fly "${MOVIE[@]}")
"$THORAX" animate "${AN[@]}" > fly1.log || fail "animate --renderer trace --keys: $(cat fly1.log)"
grep -q "5 frames (5 drawn, 0 kept" fly1.log || fail "the flight's frames: $(cat fly1.log)"
for f in 1 2 3 4 5; do [ -s "fly/frame_0000$f.png" ] || fail "frame $f missing"; done
[ ! -e fly/frame_00006.png ] || fail "a frame past the last key"
if command -v ffmpeg > /dev/null; then
    [ -s fly/animation.mp4 ] || fail "no movie"
    n=$(ffprobe -v error -count_frames -select_streams v:0 -show_entries stream=nb_read_frames -of csv=p=0 fly/animation.mp4)
    [ "$n" = 5 ] || fail "the movie has $n frames, not 5"
fi
stat -c '%n %y' fly/frame_*.png > times1
"$THORAX" animate "${AN[@]}" > fly2.log || fail "animate, resumed"
grep -q "5 frames (0 drawn, 5 kept" fly2.log || fail "the same settings redrew: $(cat fly2.log)"
stat -c '%n %y' fly/frame_*.png > times2
cmp -s times1 times2 || fail "frames rewritten by a resumed run"
mkdir still && cp fly/frame_*.png still/
"$THORAX" animate "${AN[@]}" --motion-blur 1 > fly3.log 2>&1 || fail "animate --motion-blur 1: $(cat fly3.log)"
grep -q "5 frames (5 drawn, 0 kept" fly3.log && grep -q "other settings" fly3.log || fail "another shutter kept frames: $(cat fly3.log)"
$PY - <<'EOF' || fail "the blurred frames"
import numpy as np
from PIL import Image
rd = lambda f: np.asarray(Image.open(f).convert('RGB')).astype(int)
total = 0
for k in range(1, 5):
    u0, u1, b = rd('still/frame_%05d.png' % k), rd('still/frame_%05d.png' % (k + 1)), rd('fly/frame_%05d.png' % k)
    moving = np.abs(u0 - u1).sum(axis=2) > 6           # what changes between this frame and the next
    near = moving.copy()                                # ... and the pixels next to it (2 pixels)
    for dy in range(-2, 3):
        for dx in range(-2, 3):
            near |= np.roll(np.roll(moving, dy, 0), dx, 1)
    blurred = np.abs(b - u0).sum(axis=2) > 6
    far = (blurred & ~near).sum()
    print("frame %d: %d pixels blurred, %d of them away from the moving edges (%d pixels change towards the next frame)"
          % (k, blurred.sum(), far, moving.sum()))
    assert far == 0, far
    total += blurred.sum()
    assert blurred.sum() > 0.3 * moving.sum()
assert total > 100, total
# the last frame (the flight's camera stays after its last key): the unblurred picture
assert (rd('fly/frame_00005.png') == rd('still/frame_00005.png')).all()
EOF
if "$THORAX" animate "${AN[@]}" --renderer gl --motion-blur 0.5 -o flygl 2> gl.err; then fail "--motion-blur taken under OpenGL"; fi
grep -q -- "--motion-blur" gl.err || fail "the refusal does not name the option: $(cat gl.err)"
[ ! -e flygl ] || fail "a refused animate wrote its directory"

# ---- thorax trace --frame F --motion-blur 1 on the solution: the values blurred towards F + 1 ----
"$THORAX" mesh m --no-heart -q
"$THORAX" beat m -o beat.raw --frames 40 -q
"$THORAX" forward m --epicardial beat.raw -o sol -q
T=(--solution sol --size 160x160 --samples 2 --ao 0)
"$THORAX" trace "${T[@]}" --frame 20 -o f20.png -q || fail "trace --frame 20"
"$THORAX" trace "${T[@]}" --frame 20 --motion-blur 1 -o f20b.png -q || fail "trace --frame 20 --motion-blur 1"
"$THORAX" trace "${T[@]}" --frame 40 -o f40.png -q || fail "trace --frame 40"
"$THORAX" trace "${T[@]}" --frame 40 --motion-blur 1 -o f40b.png -q || fail "trace --frame 40 --motion-blur 1"
if cmp -s f20.png f20b.png; then fail "frame 20 blurred towards frame 21 is frame 20 alone"; fi
cmp -s f40.png f40b.png || fail "the last frame blurred (nothing after it) differs from the unblurred one"
$PY - <<'EOF' || fail "the blurred potentials"
import numpy as np
from PIL import Image
a, b = [np.asarray(Image.open(f).convert('RGB')).astype(int) for f in ('f20.png', 'f20b.png')]
d = np.abs(a - b).sum(axis=2)
print("trace --frame 20 --motion-blur 1: %.1f %% of the pixels differ from frame 20 alone (at most %d levels)" % (100 * (d > 0).mean(), d.max()))
assert (d > 0).mean() > 0.01
EOF

# Image planes, arrows and the volume's colour bar, on the medium phantom's forward solution (the shared
# fixture's model, tests/medium_phantom.sh) and a label map of its surfaces.
mkdir -p med
cd med
. "$SRC/tests/medium_phantom.sh"
medium_phantom || fail "the medium phantom"
"$THORAX" beat model -o beat.raw --frames 300 -q
"$THORAX" forward model --epicardial beat.raw --volume --currents 193 -o sol -q || fail "forward"
"$THORAX" phantom --image scan.nii.gz --from model --voxel 4 -q > /dev/null || fail "the label map"
R=(--solution sol --frame 193 --size 300x300)
T=(--renderer trace --samples 1 --ao 0)
P=(--view anterior --only heart --image scan.nii.gz --image-labels --image-plane y=10)
A=(--view anterior --only heart --arrows)
"$THORAX" render "${R[@]}" "${P[@]}" -o plane_gl.png -q || fail "render --image"
"$THORAX" render "${R[@]}" "${P[@]}" "${T[@]}" -o plane_rt.png -q || fail "render --image --renderer trace"
"$THORAX" render "${R[@]}" "${A[@]}" -o arrows_gl.png -q || fail "render --arrows"
"$THORAX" render "${R[@]}" "${A[@]}" "${T[@]}" -o arrows_rt.png -q || fail "render --arrows --renderer trace"
"$THORAX" trace "${R[@]}" --view anterior --colorbar --samples 1 -o bars.png -q || fail "trace --colorbar"
"$THORAX" trace "${R[@]}" --view anterior --colorbar --samples 1 --volume potential -o vbars.png -q || fail "trace --volume --colorbar"
$PY - <<'EOF' || fail "the planes, arrows and bars"
import numpy as np
from PIL import Image
load = lambda f: np.asarray(Image.open(f).convert('RGB')).astype(int)
def near(m):   # m, or a pixel next to one of m
    p = np.pad(m, 1)
    return np.any([p[1 + dy:1 + dy + m.shape[0], 1 + dx:1 + dx + m.shape[1]] for dy in (-1, 0, 1) for dx in (-1, 0, 1)], axis=0)
# the image plane (unlit label colours) and the heart: the same foreground, the same colours mostly
gl, rt = load('plane_gl.png'), load('plane_rt.png')
bg = gl[0, 0]
fg_gl, fg_rt = np.abs(gl - bg).sum(axis=2) > 6, np.abs(rt - bg).sum(axis=2) > 6
agree = 1 - ((fg_gl != fg_rt) & ~(near(fg_rt) & near(~fg_rt))).mean()
same = (np.abs(gl - rt).sum(axis=2) <= 12)[fg_gl & fg_rt].mean()
print("image plane: foreground the same on %.2f %% of the pixels (%.1f %% of the picture); %.1f %% of it the same colour within 12 levels"
      % (100 * agree, 100 * fg_gl.mean(), 100 * same))
assert fg_gl.mean() > 0.2 and agree >= 0.99 and same >= 0.9, (fg_gl.mean(), agree, same)
# the arrows (yellow, lit in the traced picture): where the OpenGL renderer draws them, give or take a pixel
gl, rt = load('arrows_gl.png'), load('arrows_rt.png')
yel = lambda a: (a[..., 0] > 90) & (a[..., 1] > 0.7 * a[..., 0]) & (a[..., 2] < 0.5 * a[..., 0])
ygl, yrt = yel(gl), yel(rt)
hit, back = (ygl & near(yrt)).sum() / max(ygl.sum(), 1), (yrt & near(ygl)).sum() / max(yrt.sum(), 1)
print("arrows: %d yellow pixels OpenGL, %d traced; %.1f %% of OpenGL's next to traced ones, %.1f %% of the traced next to OpenGL's"
      % (ygl.sum(), yrt.sum(), 100 * hit, 100 * back))
assert ygl.sum() > 200 and 0.6 < yrt.sum() / ygl.sum() < 1.6 and hit > 0.8 and back > 0.8, (ygl.sum(), yrt.sum(), hit, back)
# the colour bars: the volume-rendered potential (the frame's own range) adds one, red to blue
def strips(a):   # runs of 16 rows or more over the background in the bar column (the right sixth's most saturated)
    w = a.shape[1]
    sat = (a.max(axis=2) - a.min(axis=2)) > 60
    col = max(range(w - w // 6, w), key=lambda x: sat[:, x].sum())
    drawn = (abs(a[:, col] - a[0, 0]).sum(axis=1) > 30).astype(int)
    e = np.flatnonzero(np.diff(np.concatenate([[0], drawn, [0]])))
    return [(s, t) for s, t in zip(e[0::2], e[1::2]) if t - s >= 16], col
(b0, _), (b1, col) = strips(load('bars.png')), strips(load('vbars.png'))
v = load('vbars.png')
s, t = b1[-1]
box = v[s:t, v.shape[1] - v.shape[1] // 3:]   # the last bar (three bars are laid out across, not down)
red = ((box[..., 0] > box[..., 1] + 60) & (box[..., 0] > box[..., 2] + 60)).sum()
blue = ((box[..., 2] > box[..., 0] + 60) & (box[..., 2] > box[..., 1] + 20)).sum()
print("colour bars: %d without the volume, %d with it; the last (rows %d..%d) has %d red and %d blue pixels"
      % (len(b0), len(b1), s, t, red, blue))
assert len(b1) == len(b0) + 1, (b0, b1)
assert red > 20 and blue > 20, (red, blue)
EOF
cd ..
echo "e2e_trace: ok"
