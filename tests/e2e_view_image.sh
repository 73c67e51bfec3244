#!/usr/bin/env bash
# thorax view --image (issue 25: the scan under the model) under Xvfb: a synthetic NIfTI (nibabel)
# with a bright square only in its plane k = 10 (z = 1 mm), seen from above through a hidden box:
#  - a scripted session: the plane z = -1 is dark where the square would be; action image-plane 1
#    moves it to z = 1 and the square appears there; image-window 2 doubles the window and the
#    grey values become (value - L + W/2) / W of the new window; the first screenshot equals
#    thorax render's picture of the same options;
#  - the session saved after the move reopens the plane where it was (--image-plane z=1);
#  - a real key: ] moves the plane one image plane up (the status line says z=1 mm), [ back.
. "$(dirname "$0")/image_fixture.sh"

# the square (tests/image_fixture.py: x -10..10, y 0..20) only in the plane k = 10 (z = 1); the box
square_image sq.nii.gz 10
box
OPTS=(--size 300x300 --camera 0,0,200:0,0,0:0,1,0:0:100 --surface box=hidden --image sq.nii.gz --image-plane z=-1)
"$THORAX" render box.pts "${OPTS[@]}" -o ref.png -q
{
    echo "$PWD/box.pts"
    printf '%s\n' --size 300x300 --camera 0,0,200:0,0,0:0,1,0:0:100 "--surface box=hidden" "--image $PWD/sq.nii.gz" \
        "--image-plane z=-1"
    echo "action screenshot $PWD/a.png"
    echo "action image-plane 1"
    echo "action screenshot $PWD/b.png"
    echo "action save-session $PWD/sess.txt"
    echo "action image-window 2"
    echo "action screenshot $PWD/c.png"
    echo "action image-plane -5"
    echo "action screenshot $PWD/d.png"
    echo "quit"
} > s.txt

cat > inside.sh <<'INNER'
set -euo pipefail
fail() { echo "FAIL: $*"; exit 1; }
timeout 120 "$THORAX" view --script s.txt > s.out 2> s.err || { cat s.err; fail "scripted session: exit $?"; }
T=60
waitfor() { local end=$((SECONDS + $1)); shift; until "$@" > /dev/null 2>&1; do [ $SECONDS -lt $end ] || return 1; sleep 0.1; done; }
gone() { ! kill -0 "$1" 2>/dev/null; }
"$THORAX" view box.pts --size 300x300 --surface box=hidden --image sq.nii.gz --image-plane z=-1 -v > k.out 2> k.err &
VP=$!
waitfor $T grep -q "window 1 drawn" k.err || { cat k.err; kill $VP; fail "no viewer window was drawn"; }
W=$(xdotool search --onlyvisible --name "^thorax " 2>/dev/null | head -1 || true)
[ -n "$W" ] || { kill $VP; fail "no viewer window appeared"; }
xdotool windowactivate --sync "$W" 2>/dev/null || xdotool windowfocus --sync "$W" || true
xdotool key --window "$W" bracketright
waitfor $T grep -q "image plane z=1 mm" k.err || { cat k.err; kill $VP; fail "] did not move the plane to z=1"; }
xdotool key --window "$W" bracketleft bracketleft
waitfor $T grep -q "image plane z=-3 mm" k.err || { cat k.err; kill $VP; fail "[ [ did not move the plane to z=-3"; }
grep "image plane" k.err | sed 's/^/keys: /'
# (the viewer may close its window between the key's press and release: the release then meets no
# window, which is not a failure; the wait below is the check)
xdotool key --window "$W" ctrl+q 2>/dev/null || true
waitfor $T gone $VP || { kill $VP; fail "ctrl+q did not quit"; }
wait $VP || fail "the viewer exited $?"
INNER
THORAX="$THORAX" xvfb-run -a -s "-screen 0 1024x768x24" bash inside.sh 2>&1 | grep -v "dbus\|session bus\|^$" || true
[ -s a.png ] && [ -s b.png ] && [ -s c.png ] && [ -s d.png ] || fail "the screenshots: $(ls; cat s.err 2>/dev/null)"
grep -q "image plane z=-3 mm" k.err || fail "the key session: $(cat k.err)"
grep -qx -- "--image-plane z=1" sess.txt && grep -qx -- "--image-window 900" sess.txt && grep -qx -- "--image-level 550" sess.txt ||
    fail "the saved session: $(cat sess.txt)"

$PY - <<'EOF'
import numpy as np
from image_fixture import png
a, b, c, d, ref = [png(f + '.png') for f in ('a', 'b', 'c', 'd', 'ref')]
# the window's drawing area may be a few pixels wider than asked (GTK's minimum width): the same
# scale (the camera's height fills the rows), centred; compare the middle
assert a.shape[0] == ref.shape[0] and a.shape[1] >= ref.shape[1], (a.shape, ref.shape)
x0 = (a.shape[1] - ref.shape[1]) // 2
a, b, c, d = (m[:, x0:x0 + ref.shape[1]] for m in (a, b, c, d))
diff = (abs(a - ref).sum(axis=2) > 30).sum()
assert diff <= 0.002 * a.shape[0] * a.shape[1], 'the viewer and render differ at %d pixels' % diff
# 300 px for 100 mm: RAS (x, y) at (row 150 - 3 y, column 150 + 3 x)
px = lambda x, y: (int(round(150 - 3 * y)), int(round(150 + 3 * x)))
def grey(v, W, L): return round(255 * min(max((v - (L - W / 2)) / W, 0), 1))
assert (a[px(0, 10)] == 0).all() and (a[px(-20, -20)] == 0).all(), (a[px(0, 10)], a[px(-20, -20)])
assert (b[px(0, 10)] == 255).all() and (b[px(-20, -20)] == 0).all(), (b[px(0, 10)], b[px(-20, -20)])
W, L = 1800, 550   # the label map's full range 100..1000 (W 900, L 550), the window doubled
assert (abs(c[px(0, 10)] - grey(1000, W, L)) <= 1).all() and (abs(c[px(-20, -20)] - grey(100, W, L)) <= 1).all(), (c[px(0, 10)], c[px(-20, -20)])
assert (abs(d[px(0, 10)] - grey(100, W, L)) <= 1).all(), d[px(0, 10)]
print('view: z=-1 dark (%d), image-plane 1 -> z=1 the square (%d), window x2: %d and %d (computed %d, %d); %d pixels differ from render'
      % (a[px(0, 10)][0], b[px(0, 10)][0], c[px(0, 10)][0], c[px(-20, -20)][0], grey(1000, W, L), grey(100, W, L), diff))
EOF
echo "e2e_view_image: OK"
