#!/usr/bin/env bash
# thorax view as a map3d user meets it (issue 26, item 5), under Xvfb, on map3d's own records:
#  a. `a` (action activation) on the Utah tank sock with the 2-beat run: from the .mat (no fiducials)
#     one beat's QRS found on the RMS curve, the times inside it (the whole series gave 88.9-589 ms),
#     and the label says so; from the .tsdf its qon..soff fiducials; on the 490-lead sock its own act
#     fiducials; `a` again shows the potentials (pixel for pixel the first picture), a third time the
#     same map; Shift+A (recovery) a map after the QRS and before the next beat;
#  b. a window of the sock alone (--window, as each window of --separate) frames the sock: it fills
#     the drawing area, centred (it sat small and off-centre beside the tank);
#  c. each picked node has a ring and its number in its trace's colour (the first green, the second
#     amber), where the node is in the picture;
#  d. six real clicks do not grow the window (110 pixels a pick before): its size is the same after;
#  e. a layer edit of a model saved elsewhere, opened from another folder, finds its contours.
set -euo pipefail
: "${THORAX:?}" "${WORK:?}" "${SRC:?}"
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK"
PY=/usr/bin/python3
fail() { echo "FAIL: $*"; exit 1; }
D="$SRC/../shared/data/map3d"
[ -d "$D" ] || fail "no map3d data at $D"
SOCK="$D/geom/tank/25feb97_sock.pts"
TANK="$D/geom/tank/tank_full_771.pts"
CH="$D/geom/tank/sock128.channels"

# a. activation and recovery maps; the key toggles
cat > a.txt <<EOF
$SOCK
--data $D/data/tank/cool1-atdr-run1.mat
--channels $CH
--size 420x360
--label
--colorbar
action screenshot p0.png
action activation
action screenshot a1.png
action activation
action screenshot p1.png
action activation
action screenshot a2.png
action recovery
action screenshot r1.png
action save-session sess.txt
quit
EOF
xvfb-run -a -s "-screen 0 1024x768x24" "$THORAX" view --script a.txt > a.out 2> a.err || { cat a.err; fail "activation session"; }
cat > t.txt <<EOF
$SOCK
--data $D/data/tank/cool1-atdr-run1.tsdf
--channels $CH
--size 300x300
action screenshot t0.png
action activation
action screenshot t1.png
quit
EOF
xvfb-run -a -s "-screen 0 1024x768x24" "$THORAX" view --script t.txt > t.out 2> t.err || { cat t.err; fail "tsdf session"; }
cat > s.txt <<EOF
$D/geom/socks/490sock.pts
--data $D/data/socks/10jan01/rsm10jan01-cs-0004.mat
--size 300x300
action activation
action recovery
quit
EOF
xvfb-run -a -s "-screen 0 1024x768x24" "$THORAX" view --script s.txt > s.out 2> s.err || { cat s.err; fail "490 sock session"; }
grep "^activation\|^recovery" a.out t.out s.out
grep -q "^--recovery 25feb97_sock$" sess.txt || { cat sess.txt; fail "the session does not keep the recovery map"; }
# thorax render draws the same maps (--recovery), from the .tsdf's fiducials: qon..soff, then soff..toff
"$THORAX" render "$SOCK" --data "$D/data/tank/cool1-atdr-run1.tsdf" --channels "$CH" --recovery 25feb97_sock \
    --label --size 300x300 -o rec.png -q -v 2> rec.err || { cat rec.err; fail "render --recovery"; }

# b, c. the sock alone in a window; two scripted picks marked
cat > b.txt <<EOF
$TANK
$SOCK
--data $D/data/tank/cool1-atdr-run1.mat
--data-surface 25feb97_sock
--channels $CH
--window 25feb97_sock
--size 400x400
--frame 185
action screenshot b0.png
action pick 200,200
action screenshot b1.png
action pick 170,150
action screenshot b2.png
quit
EOF
xvfb-run -a -s "-screen 0 1024x900x24" "$THORAX" view --script b.txt > b.out 2> b.err || { cat b.err; fail "sock window session"; }
grep "^pick" b.out

# d. real clicks: the window keeps its size
cat > inside.sh <<'INNER'
set -euo pipefail
fail() { echo "FAIL: $*"; exit 1; }
T=60
waitfor() { local end=$((SECONDS + $1)); shift; until "$@" > /dev/null 2>&1; do [ $SECONDS -lt $end ] || return 1; sleep 0.1; done; }
picks() { [ "$(grep -c '^pick: surface' d.out)" -ge "$1" ]; }
titled() { xdotool getwindowname "$1" | grep -q "$2"; }
"$THORAX" view "$SOCK" --data "$DATA" --channels "$CH" --size 400x400 -v > d.out 2> d.err &
VP=$!
waitfor $T grep -q "window 1 drawn" d.err || { cat d.err; fail "no window"; }
W=$(xdotool search --onlyvisible --name "^thorax " | head -1)
xdotool windowactivate --sync "$W" 2>/dev/null || xdotool windowfocus --sync "$W" || true
G0=$(xdotool getwindowgeometry "$W" | grep Geometry)
n=0
for xy in "200 230" "180 200" "220 260" "160 240" "240 220" "200 180"; do
    n=$((n + 1))
    xdotool mousemove --window "$W" $xy click 1
    waitfor $T picks $n || { cat d.out; fail "click $n did not pick"; }
done
# a key after the clicks: when its effect shows, the clicks' layout is done
xdotool key --window "$W" Right
waitfor $T titled "$W" "frame 2 of" || fail "Right: $(xdotool getwindowname "$W")"
G6=$(xdotool getwindowgeometry "$W" | grep Geometry)
echo "window before the picks: $G0; after six: $G6"
[ "$G0" = "$G6" ] || fail "six picks changed the window's size: $G0 -> $G6"
# (the viewer may close its window between the key's press and release: the release then meets no
# window, which is not a failure; the wait below is the check)
xdotool key --window "$W" ctrl+q 2>/dev/null || true
waitfor $T eval '! kill -0 $VP' || { kill $VP; fail "ctrl+q did not quit"; }
echo "inside: passed"
INNER
SOCK="$SOCK" DATA="$D/data/tank/cool1-atdr-run1.mat" CH="$CH" THORAX="$THORAX" \
    xvfb-run -a -s "-screen 0 1024x900x24" bash inside.sh 2>&1 | grep -v "dbus\|session bus\|^$" | tee inside.out || true
grep -q "inside: passed" inside.out || fail "the window size part"

# e. a layer edit of a model saved elsewhere, opened from another folder
mkdir -p build saved/deep elsewhere
(cd build && "$THORAX" phantom --resolution medium --seed 1 -o c.txt -q && "$THORAX" surfaces c.txt -o m -q 2> /dev/null)
printf '%s\n--size 200x200\naction edit layer_move heart layer=3 2 1\naction save-model %s\nquit\n' "$WORK/build/m" "$WORK/saved/deep/edited" > e1.txt
(cd build && xvfb-run -a "$THORAX" view --script "$WORK/e1.txt" > "$WORK/e1.out" 2> "$WORK/e1.err") || { cat e1.err; fail "edit and save"; }
printf '%s\n--size 200x200\naction edit layer_move heart layer=4 1 1\nquit\n' "$WORK/saved/deep/edited" > e2.txt
(cd elsewhere && xvfb-run -a "$THORAX" view --script "$WORK/e2.txt" > "$WORK/e2.out" 2> "$WORK/e2.err") || { cat e2.err; fail "a layer edit of the saved model from another folder"; }
grep -q "^edit: layer_move heart layer=4 1 1 -> heart: passes" e2.out || { cat e2.out e2.err; fail "the saved model's layer edit"; }

# ---- numbers and pixels ----
$PY - <<'EOF'
import re, numpy as np
from PIL import Image
def png(p): return np.asarray(Image.open(p).convert("RGB")).astype(int)
def line(path, what):
    for l in open(path):
        if l.startswith(what + ":"): return l
    raise SystemExit(f"FAIL: no '{what}' line in {path}")
def rng(l):
    m = re.match(r"\w+: \S+ (\S+) (\S+) (\S+) \| (.*)", l)
    return float(m.group(1)), float(m.group(2)), m.group(4)
# a. the tank's .mat: one beat's QRS found on the RMS curve; map3d's .tsdf fiducials mark 155..196
lo, hi, why = rng(line("a.out", "activation"))
assert "(RMS curve, beat 1 of 2)" in why and 150 <= lo and hi <= 210 and hi - lo < 40, (lo, hi, why)
lo_t, hi_t, why_t = rng(line("t.out", "activation"))
assert "activation, QRS 155-196 frame (fiducials qon-soff)" in why_t and 155 <= lo_t and hi_t <= 196, (lo_t, hi_t, why_t)
r_lo, r_hi, r_why = rng(line("a.out", "recovery"))
assert r_lo > hi and r_hi < 560, (r_lo, r_hi, r_why)   # after the QRS, before the second beat
s_lo, s_hi, s_why = rng(line("s.out", "activation"))
assert "the record's act fiducials" in s_why and 263 < s_lo and s_hi < 291, (s_lo, s_hi, s_why)
s_rlo, s_rhi, s_rwhy = rng(line("s.out", "recovery"))
assert "the record's rec fiducials" in s_rwhy and 315 < s_rlo and s_rhi < 505, (s_rlo, s_rhi, s_rwhy)
p0, a1, p1, a2, r1 = (png(f + ".png") for f in ("p0", "a1", "p1", "a2", "r1"))
# without --label, the map turns the label line on: text (light pixels) in the top strip
t0, t1 = png("t0.png"), png("t1.png")
light0, light1 = ((t[:16].min(axis=2) > 180).sum() for t in (t0, t1))   # (the sock's top reaches the strip in t0)
assert light1 > 200 and light1 > 4 * light0, ("the map's window is not said in the picture", light0, light1)
assert np.array_equal(p0, p1), "a twice: not the potentials' picture again"
assert np.array_equal(a1, a2), "a a third time: not the same map"
assert np.abs(p0 - a1).sum(axis=2).astype(bool).mean() > 0.05 and not np.array_equal(a1, r1), "the maps look like the potentials"
print(f"e2e_view_habits: activation {lo:g}-{hi:g} ms ({why.strip()}); .tsdf {lo_t:g}-{hi_t:g}; recovery {r_lo:g}-{r_hi:g}; "
      f"490 sock act {s_lo:g}-{s_hi:g}, rec {s_rlo:g}-{s_rhi:g}")
# b. the sock framed: its pixels (not the background) span most of the area, centred
b0 = png("b0.png")
bg = b0[2, 2]
mask = np.abs(b0 - bg).sum(axis=2) > 30
ys, xs = np.nonzero(mask)
h, w = mask.shape
span = max((xs.max() - xs.min()) / w, (ys.max() - ys.min()) / h)
cx, cy = (xs.max() + xs.min()) / 2 / w, (ys.max() + ys.min()) / 2 / h
assert span > 0.6 and abs(cx - 0.5) < 0.1 and abs(cy - 0.5) < 0.1, (span, cx, cy)
print(f"e2e_view_habits: the sock's window: it spans {span:.2f} of the area, centre ({cx:.2f}, {cy:.2f})")
# c. the picks' marks in their traces' colours (the drawing area gave the trace pane its room,
#    so the nodes moved in it): a compact ring with the number beside it, none before any pick
green, amber = np.array([120, 230, 120]), np.array([250, 200, 80])
def blob(img, col):
    ys, xs = np.nonzero(np.abs(img - col).sum(axis=2) <= 6)
    if len(xs) == 0: return 0, 0, 0
    return len(xs), xs.max() - xs.min(), ys.max() - ys.min()
b1, b2 = png("b1.png"), png("b2.png")
assert blob(b0, green)[0] == 0 and blob(b0, amber)[0] == 0, "marker colours before any pick"
g, a = blob(b1, green), blob(b2, amber)
assert blob(b2, green)[0] >= 30 and g[0] >= 30 and a[0] >= 30, (g, a)
# a ring 13 pixels across and a number of up to 3 digits beside it: within 60 x 20 pixels
assert g[1] <= 60 and g[2] <= 20 and a[1] <= 60 and a[2] <= 20, (g, a)
assert g[1] > 16 and a[1] > 16, ("no number beside the ring", g, a)
print(f"e2e_view_habits: pick marks: {g[0]} green pixels ({g[1]}x{g[2]}), {a[0]} amber ({a[1]}x{a[2]})")
EOF
echo "e2e_view_habits: passed"
