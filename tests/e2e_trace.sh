#!/usr/bin/env bash
# thorax trace and --renderer trace (issue 27; RaySpray) on the phantom's model:
#  - render --renderer trace with the headlight alone and one sample sees what the OpenGL render
#    sees: the two pictures' foreground (not background) agree on >= 99.5 % of the pixels (up to the
#    silhouette's anti-aliased pixel), and their colours there within a few grey levels on average
#    (the same scale, colours and light);
#  - thorax trace with a glass torso shows the heart through it (red pixels the opaque picture has
#    none of), and the same bytes on 1 and 2 threads;
#  - bad lights and materials are refused by name (exit 2), nothing written.
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
echo "e2e_trace: ok"
