#!/usr/bin/env bash
# thorax view's side panel (issue 26, item 4) under Xvfb, on the medium phantom's forward solution
# with its volume potentials (12 frames):
#  a. scripted: a changed --isosurface option line, isovalue-add/-remove, slice-add/-move/-remove,
#     seed-density, range: each shows in the very next screenshot, with no frame step (the picture
#     after is thorax render's of the new options, not of the old ones); removing what was added
#     gives the same pixels; saved sessions hold the new --isosurface, --slice, --streamlines and
#     --scope fixed:LO:HI; a value outside the potentials and a slice missing the volume stop the
#     script naming the line; a viewer opened without a cut reads the volume potentials at the first;
#  b. real input (xdotool): F9 shows the panel (the window grows by it, the drawing area keeps its
#     size) and hides it (the window back to its size); a value typed into the panel's field is the
#     field's (6 is not the inferior view); the colour bar's top end dragged fixes the range, a
#     value's mark dragged moves the value, Ctrl+Shift+drag moves the selected slice, a click with
#     the seed tool seeds a streamline inside the volume (two clicks a rake), a drag across the
#     traces is the activation window (nine windows in turn: each replaces the last); the session
#     saved by Ctrl+Shift+S has them all;
#  c. the keys window (`?`): nothing cut off at the default Xvfb screen (the list as wide as its
#     view, the window on the screen), no text selected, the mouse's gestures listed; and every
#     action of the table is in docs/cli.md.
set -euo pipefail
: "${THORAX:?}" "${WORK:?}" "${SRC:?}"
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK"
PY=/usr/bin/python3
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
fail() { echo "FAIL: $*"; exit 1; }

. "$(dirname "$0")/medium_phantom.sh"
medium_phantom || fail "the medium phantom"
"$THORAX" beat model -o beat.raw --frames 12 --dt 30 -q
"$THORAX" forward model --epicardial beat.raw --volume -o sol -q
# one colour scale for every surface and cut (one bar, its ends at -1.5 and 1.5 mV)
R=(--solution sol --frame 7 --size 400x400 --colorbar --scope fixed:-1.5:1.5)
"$THORAX" render "${R[@]}" --isosurface 0.3 -o r0.png -q
"$THORAX" render "${R[@]}" --isosurface -0.3,0.3 -o r1.png -q
"$THORAX" render "${R[@]}" --isosurface -0.3,0.3,0.9 -o r2.png -q
"$THORAX" render "${R[@]}" --isosurface -0.3,0.3 --slice y=0 -o r4.png -q

# ---- a. scripted ----
{
    printf '%s\n' "--solution $PWD/sol" --frame\ 7 --size\ 400x400 --colorbar "--scope fixed:-1.5:1.5" "--isosurface 0.3"
    echo "action screenshot $PWD/a0.png"
    echo "--isosurface -0.3,0.3"
    echo "action screenshot $PWD/a1.png"
    echo "action isovalue-add 0.9"
    echo "action screenshot $PWD/a2.png"
    echo "action isovalue-remove 0.9"
    echo "action screenshot $PWD/a3.png"
    echo "action slice-add y=0"
    echo "action screenshot $PWD/a4.png"
    echo "action slice-move 15"
    echo "action save-session $PWD/s1.txt"
    echo "action slice-remove 1"
    echo "action seed-density 40"
    echo "action range -1:1"
    echo "action save-session $PWD/s2.txt"
    echo "action isosurface none"
    echo "action seed-density 0"
    echo "action range auto"
    echo "action save-session $PWD/s3.txt"
    echo "quit"
} > a.txt
# opened without a cut: the first one reads the volume potentials then
{ head -5 a.txt; echo "action isovalue-add 0.3"; echo "action screenshot $PWD/c1.png"; echo quit; } > c.txt
# nine activation windows one after another (a surface holds eight data sets: each replaces the last)
{ head -5 a.txt; for t in 30 40 50 60 70 80 90 100 110; do echo "action activation $t:$((t + 120))"; done; echo quit; } > w.txt
{ head -6 a.txt; echo "action isovalue-add 5"; echo quit; } > bad1.txt
{ head -6 a.txt; echo "action slice-add z=9999"; echo quit; } > bad2.txt

cat > xwd.py <<'EOF'
import struct
import numpy as np
def xwd(path):
    """An xwd screenshot (ZPixmap, 32 bits a pixel) as rows x columns x RGB."""
    b = open(path, "rb").read()
    h = struct.unpack(">25I", b[:100])
    w, hh, bpl, ncol = h[4], h[5], h[12], h[19]
    off = h[0] + 12 * ncol
    px = np.frombuffer(b[off:off + bpl * hh], dtype=np.uint8).reshape(hh, bpl)[:, :w * 4].reshape(hh, w, 4)
    return (px[:, :, [2, 1, 0]] if h[7] == 0 else px[:, :, [1, 2, 3]]).astype(int)
EOF
cat > inside.sh <<'INNER'
set -euo pipefail
fail() { echo "FAIL: $*"; exit 1; }
T=60
waitfor() { local end=$((SECONDS + $1)); shift; until "$@" > /dev/null 2>&1; do [ $SECONDS -lt $end ] || return 1; sleep 0.1; done; }
gone() { ! kill -0 "$1" 2>/dev/null; }
said() { grep -q -- "$2" "$1"; }
# (a failure's own commands must not fail: under set -e that would end the script with no word)
stop() { if kill -0 "$VP" 2>/dev/null; then kill "$VP" 2>/dev/null || true; else echo "(the viewer had ended: $(tail -3 k.err r.err 2>/dev/null | tr '\n' ' '))"; fi; }
timeout 120 "$THORAX" view --script a.txt > a.out 2> a.err || { cat a.err; fail "the scripted session: exit $?"; }
timeout 120 "$THORAX" view --script c.txt > c.out 2> c.err || { cat c.err; fail "a first cut without the volume potentials read: exit $?"; }
timeout 120 "$THORAX" view --script w.txt > w.out 2> w.err || { cat w.err; fail "nine activation windows: exit $?"; }
for b in bad1 bad2; do
    if timeout 60 "$THORAX" view --script $b.txt > $b.out 2> $b.err; then fail "$b.txt: exit 0"; fi
done

# ---- b. real input: a script sets up (a trace, the seed tool), then waits for the mouse ----
cat > k.txt <<EOF
--solution $PWD/sol
--frame 7
--size 400x400
--colorbar
--scope fixed:-1.5:1.5
--isosurface -0.3,0.3
--slice z=110
action pick 200,200
action seed-tool point
wait 300000
EOF
"$THORAX" view --script k.txt -v > k.out 2> k.err &
VP=$!
waitfor $T said k.err "window 1 drawn" || { cat k.err; stop; fail "no viewer window was drawn"; }
waitfor $T said k.err "seed tool: a click" || { cat k.err; stop; fail "the script's set-up"; }
OX=$(sed -n 's/.*window 1 drawn .* at \([0-9]*\),\([0-9]*\) in the window.*/\1/p' k.err)
OY=$(sed -n 's/.*window 1 drawn .* at \([0-9]*\),\([0-9]*\) in the window.*/\2/p' k.err)
W=$(xdotool search --onlyvisible --name "^thorax " 2>/dev/null | head -1 || true)
[ -n "$W" ] || { stop; fail "no viewer window appeared"; }
geom() { xdotool getwindowgeometry "$W" | sed -n 's/.*Geometry: //p'; }
key() { xdotool windowfocus --sync "$W" 2>/dev/null || true; xdotool key --window "$W" "$@"; }
at() { echo $((OX + $1)) $((OY + $2)); }   # drawing-area pixels to the window's
G0=$(geom)
# the keys window
key question
waitfor $T said k.err "keys window" || { stop; fail "? did not open the keys window"; }
K=$(xdotool search --onlyvisible --name "keys" 2>/dev/null | head -1 || true)
[ -n "$K" ] || { stop; fail "no keys window"; }
xwd -id "$K" -out keys.xwd
xdotool getwindowgeometry "$K" | sed -n 's/.*Geometry: /keys window geometry /p' > keys.geom
closed() { ! xdotool search --onlyvisible --name "keys" > /dev/null 2>&1; }
end=$((SECONDS + T)); until closed; do xdotool key --window "$K" Escape 2>/dev/null || true; [ $SECONDS -lt $end ] || { stop; fail "Escape did not close the keys window"; }; sleep 0.3; done
# the panel: shown, typed into, hidden
key F9
waitfor $T said k.err "side panel shown" || { stop; fail "F9 did not show the panel"; }
waitfor $T eval '[ "$(geom)" != "$G0" ]' || { stop; fail "the window did not grow by the panel: $(geom)"; }
G1=$(geom)
painted() { xwd -id "$W" -out panel.xwd && $PY -c 'import sys; sys.path.insert(0, "."); from xwd import xwd; sys.exit(0 if xwd("panel.xwd")[:, -200:].mean() > 100 else 1)'; }
waitfor $T painted || { stop; fail "the panel was not drawn"; }
# the drawing area on the screen (rows OY.. of the window, 400 x 267 after the trace pane took its
# room) before the value is typed, and after: it changes with no other event (redrawn at once)
area() { xwd -id "$W" -out area.xwd && $PY -c 'import sys, numpy as np; sys.path.insert(0, "."); from xwd import xwd
np.save(sys.argv[1], xwd("area.xwd")[int(sys.argv[2]):int(sys.argv[2]) + 267, :400])' "$1" "$OY"; }
changed() { area after.npy && $PY -c 'import sys, numpy as np; a, b = np.load("before.npy"), np.load("after.npy")
sys.exit(0 if (np.abs(a - b).sum(axis=2) > 30).sum() > 100 else 1)'; }
area before.npy
xdotool mousemove --window "$W" $((OX + 490)) $((OY + 120)) click 1
waitfor $T said k.err "a field of the panel has the keyboard" || { stop; fail "a click on the panel's value field"; }
xdotool type --window "$W" "0.6"
xdotool key --window "$W" Return
waitfor $T said k.err "equipotentials: -0.3,0.3,0.6" || { cat k.err; stop; fail "0.6 typed into the panel did not add the value"; }
waitfor $T changed || { stop; fail "the window did not show the new equipotential"; }
! said k.err "inferior view" || { stop; fail "6 typed into the panel's field turned the view"; }
key F9
waitfor $T said k.err "side panel hidden" || { stop; fail "F9 did not hide the panel"; }
waitfor $T eval '[ "$(geom)" = "$G0" ]' || { stop; fail "the window kept the panel's width: $G0 -> $G1 -> $(geom)"; }
echo "window $G0, with the panel $G1, without it again $(geom)"
# the drags below find the colour bar where the last picture put it: wait until the drawing area
# shows the bar in its place and two screenshots agree (the window's relayout done; under load a
# press during it lands on a picture of a passing size)
bar_shown() { area bar1.npy && $PY -c 'import sys, numpy as np; a = np.load("bar1.npy")
s = a[40:220, 330:350]; b = np.load("bar0.npy") if len(sys.argv) > 1 else None
lit = (s.sum(axis=2) > 300).mean()   # (the bar light on the dark background)
sys.exit(0 if lit > 0.5 and b is not None and np.array_equal(a, b) else 1)' x || { cp bar1.npy bar0.npy; false; }; }
area bar0.npy
waitfor $T bar_shown || { tail -5 k.err; stop; fail "the drawing area did not settle with its colour bar after the panel was hidden"; }
drag() { # X0 Y0 DX DY [MODIFIERS]: a press, two moves and a release (drawing-area pixels)
    local x=$(($OX + $1)) y=$(($OY + $2))
    [ -n "${5:-}" ] && xdotool keydown $5
    xdotool mousemove --window "$W" $x $y mousedown 1
    sleep 0.2
    xdotool mousemove --window "$W" $((x + $3 / 2)) $((y + $4 / 2))
    sleep 0.2
    xdotool mousemove --window "$W" $((x + $3)) $((y + $4))
    sleep 0.2
    xdotool mouseup 1
    [ -n "${5:-}" ] && xdotool keyup $5
    sleep 0.2
}
# the drawing area is 400x267 (the trace pane took a third): one bar, its strip at x 328-352,
# y 33-233, its ends -1.5 and 1.5; the top end 50 pixels down is 0.75 mV (symmetric mapping: -0.75
# to 0.75)
drag 340 40 0 50
waitfor $T said k.err "colour range fixed: -0.75 to 0.75" || { grep "colour range" k.err || tail -5 k.err; stop; fail "the bar's end dragged"; }
# the mark of 0.3 on the bar of -0.75..0.75 is at t = 0.7, row 233 - 140 = 93; 20 up: t 0.8, 0.45 mV
drag 340 93 0 -20
waitfor $T said k.err "equipotential 0.45 (was 0.3)" || { grep "equipotential" k.err || tail -5 k.err; stop; fail "the value's mark dragged"; }
# the slice z=110 seen from the front: 20 pixels up moves it up by 20 pixels' worth of mm
drag 150 130 0 -20 "ctrl+shift"
waitfor $T said k.err "slice 1: z=" || { tail k.err; stop; fail "Ctrl+Shift+drag did not move the slice"; }
key ctrl+shift+s   # (the camera of this picture: the map below turns the label line on, which changes it)
waitfor $T test -s thorax-view-session.txt || { stop; fail "Ctrl+Shift+S"; }
mv thorax-view-session.txt slice-session.txt
# the seed tool's click
xdotool mousemove --window "$W" $(at 150 140) click 1
waitfor $T said k.out "^seed: point:" || { tail k.err; stop; fail "the seed tool's click"; }
# a drag across the trace under the picture (pane: the last third of the 400 rows)
drag 100 340 150 0
waitfor $T said k.err "activation window .* dragged on the traces" || { tail k.err; stop; fail "the drag across the traces"; }
key ctrl+shift+s
waitfor $T test -s thorax-view-session.txt || { stop; fail "Ctrl+Shift+S"; }
key ctrl+q 2>/dev/null || true
waitfor $T gone $VP || { stop; fail "ctrl+q did not quit"; }
# a rake: two clicks, its ends
{ head -7 k.txt; echo "action seed-tool rake"; echo "wait 300000"; } > r.txt
"$THORAX" view --script r.txt -v > r.out 2> r.err &
VP=$!
waitfor $T said r.err "seed tool: two clicks" || { cat r.err; stop; fail "the rake's set-up"; }
W=$(xdotool search --onlyvisible --name "^thorax " 2>/dev/null | head -1 || true)
xdotool mousemove --window "$W" $(at 120 200) click 1
waitfor $T said r.err "rake: one end at" || { tail r.err; stop; fail "the rake's first click"; }
xdotool mousemove --window "$W" $(at 200 120) click 1
waitfor $T said r.out "^seed: line:" || { tail r.err; stop; fail "the rake's second click"; }
key ctrl+q 2>/dev/null || true
waitfor $T gone $VP || { stop; fail "ctrl+q did not quit the rake's viewer"; }
echo "inside: passed"
INNER
PY="$PY" THORAX="$THORAX" xvfb-run -a bash inside.sh 2>&1 | grep -v "dbus\|session bus\|^$" | tee inside.out || true
grep -q "inside: passed" inside.out || fail "the sessions under Xvfb (above)"
grep -q "bad1.txt:7: .*isovalue-add.*outside the volume potentials" bad1.err || fail "a value outside the potentials: $(cat bad1.err)"
grep -q "bad2.txt:7: .*slice-add.*misses the volume" bad2.err || fail "a slice missing the volume: $(cat bad2.err)"
sed 's/^/refused: /' bad1.err bad2.err | grep -v Gtk

# ---- the session files, the pixels, the keys window ----
# the table's actions with a handler of their own (the other rows are keys giving one of them a value)
ACTIONS=$(sed -n 's/^    {"\([a-z0-9-]*\)", \(NULL\|"[a-z]"\), \(NULL\|"[a-z]"\), \(do_\|view_panel_action\).*/\1/p' "$SRC/src/view/view_actions.c")
missing=""
for a in $ACTIONS; do grep -q "\`$a[ \`]" "$SRC/docs/cli.md" || missing="$missing $a"; done
[ -z "$missing" ] || fail "docs/cli.md does not name the actions:$missing"
echo "docs/cli.md names all $(echo $ACTIONS | wc -w) actions"
$PY - "$SRC" <<'EOF'
import re, sys
import numpy as np
from PIL import Image
def png(p): return np.asarray(Image.open(p).convert("RGB")).astype(int)
sys.path.insert(0, ".")
from xwd import xwd
def opts(path): return [l.strip() for l in open(path) if l.startswith("--")]
def diff(a, b, x1=304):   # pixels differing (by more than 30 in sum) left of the colour bar's column
    return int((np.abs(a[:, :x1] - b[:, :x1]).sum(axis=2) > 30).sum())
a = {k: png(f"a{k}.png") for k in range(5)}
r = {k: png(f"r{k}.png") for k in (0, 1, 2, 4)}
# a. each change in the next screenshot, no frame step: the picture is render's of the new options
for k, new, old, what in ((1, 1, 0, "--isosurface line"), (2, 2, 1, "isovalue-add"), (4, 4, 1, "slice-add")):
    dn, do = diff(a[k], r[new]), diff(a[k], r[old])
    print(f"a. {what}: {dn} pixels differ from render of the new options, {do} from the old")
    assert do > 400 and dn < do / 4 and dn < 0.02 * 304 * 400, (what, dn, do)   # (the edges: no FXAA in the window)
assert np.array_equal(a[3], a[1]), "isovalue-remove did not give the picture before isovalue-add"
assert np.array_equal(png("c1.png"), a[0]), "the first cut of a viewer opened without one is not the picture opened with it"
s1, s2, s3 = opts("s1.txt"), opts("s2.txt"), opts("s3.txt")
assert "--isosurface -0.3,0.3" in s1 and "--slice y=15" in s1, s1
assert "--scope fixed:-1:1" in s2 and "--streamlines density:40" in s2 and not any(o.startswith("--slice") for o in s2), s2
assert not any(o.startswith(("--isosurface", "--streamlines", "--slice")) for o in s3) and "--scope series" in s3, s3
print("a. sessions:", [o for o in s1 + s2 if o.startswith(("--isosurface", "--slice", "--streamlines", "--scope"))])
# b. what the mouse did, in the session saved after
k = opts("thorax-view-session.txt")
get = lambda name: [o.split(" ", 1)[1] for o in k if o.startswith(name + " ")]
lo, hi = map(float, get("--scope")[0].split(":")[1:])
assert abs(lo + 0.75) < 1e-5 and abs(hi - 0.75) < 1e-5, (lo, hi)   # (the bar's scale in float)
iso = sorted(map(float, get("--isosurface")[0].split(",")))
assert len(iso) == 3 and abs(iso[0] + 0.3) < 1e-9 and abs(iso[1] - 0.45) < 1e-5 and abs(iso[2] - 0.6) < 1e-9, iso
ks = opts("slice-session.txt")
cam = [o for o in ks if o.startswith("--camera ")][0].split(":")
rows = int([o for o in ks if o.startswith("--size ")][0].split("x")[1])
mmpp = float(cam[4]) / rows                     # orthographic height over the drawing area's rows
z = float(get("--slice")[0].split("=")[1])
assert abs(z - (110 + 20 * mmpp)) < 1.5 * mmpp, (z, mmpp)
seed = get("--streamlines")
assert len(seed) == 1 and seed[0].startswith("point:"), seed
rake = [l for l in open("r.out") if l.startswith("seed: line:")][0]
assert rake.split()[1].endswith(":10"), rake            # the panel's default: 10 seeds along it
wins = [l for l in open("w.out") if l.startswith("activation:")]
assert len(wins) == 9 and "window 110-230" in wins[-1], wins
print(f"b. a rake: {rake.split()[1]}; nine activation windows in turn, the last {wins[-1].split('|')[1].strip()}")
act = [l for l in open("k.out") if l.startswith("activation:")]
m = re.search(r"window ([-\d.]+)-([-\d.]+) ms \(as given\)", act[-1])
t0, t1 = float(m.group(1)), float(m.group(2))
# the pane's image: x 10.5 + i 379 / 11 for frame i (30 ms apart); the drag from x 100 to 250
e0, e1 = (100 - 10.5) / 379 * 330, (250 - 10.5) / 379 * 330
assert abs(t0 - e0) < 6 and abs(t1 - e1) < 6, (t0, t1, e0, e1)
print(f"b. mouse: range {lo:g}..{hi:g}, values {iso}, slice z={z:.2f} (20 px = {20 * mmpp:.2f} mm), {seed[0]}, "
      f"activation window {t0:g}-{t1:g} ms (expected {e0:.0f}-{e1:.0f})")
# c. the keys window: no horizontal cut, on the screen, nothing selected, the gestures listed
line = [l for l in open("k.err") if "keys window" in l][-1]
m = re.search(r"keys window (\d+)x(\d+), its list (\d+)x(\d+) \(needs at least (\d+) wide\), in view (\d+)x(\d+)", line)
ww, wh, lw, lh, lmin, vw, vh = map(int, m.groups())
assert lw <= vw and lmin <= ww and wh <= 1024 and ww <= 1280, line
keys = xwd("keys.xwd")
sel = (np.abs(keys - np.array([53, 132, 228])).sum(axis=2) < 40).sum()   # Adwaita's selection blue
dark = (keys[:40].sum(axis=2) < 200).sum()
assert sel < 20 and dark > 100, (sel, dark)
print(f"c. keys window {ww}x{wh}: list {lw} wide in a view {vw} wide ({lh} high, {vh} shown, scrolled), {sel} selected pixels")
panel = xwd("panel.xwd")
assert panel[:, -200:].mean() > 100 and panel.shape[1] >= 400 + 250, panel.shape   # the panel, light, at the right
print(f"b. the window with the panel {panel.shape[1]}x{panel.shape[0]} (its right part's mean grey {panel[:, -200:].mean():.0f})")
EOF
grep -q "drag across the traces" "$SRC/docs/cli.md" || fail "docs/cli.md does not list the gestures"
echo "e2e_view_panel: passed"
