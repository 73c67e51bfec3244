#!/usr/bin/env bash
# Tracing a real scan in the viewer (issue 26 items 1, 2, 7), under Xvfb, on InVesalius's example CT
# (Cranium.inv3, Debian package invesalius-examples; tests/inv3_to_nifti.py):
#  1. a scripted session: the skin traced with the threshold tool (values from -400 HU, a seed in
#     the head) on 10 axial planes 7.5 mm apart gives a closed surface that passes thorax check; the
#     model, the contour file (the image's line and frame) and the label map are written, and
#     nibabel reads the label map on the CT's grid;
#  2. real gestures (xdotool): clicks in the slice pane lay points, a click on the first point closes
#     the loop, a drag moves a point, Shift+click inserts one, Ctrl+click deletes one, the wheel
#     steps the plane, a right-button drag changes the grey window; the session saved
#     afterwards holds the lines those gestures became, and replaying it gives the same contours;
#  3. thorax digitize SCAN (no --label) opens the same viewer.
# Env: THORAX (built CLI), SRC, WORK.
set -euo pipefail
: "${THORAX:?}" "${SRC:?}" "${WORK:?}"
INV=/usr/share/doc/invesalius-examples/examples/Cranium.inv3
[ -r "$INV" ] || { echo "e2e_view_trace: $INV missing (Debian package invesalius-examples); skipped"; exit 77; }
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK"
PY=/usr/bin/python3
fail() { echo "e2e_view_trace: FAIL: $*" >&2; exit 1; }
$PY -B "$SRC/tests/inv3_to_nifti.py" "$INV" ct.nii.gz > conv.log || fail "inv3_to_nifti: $(cat conv.log)"

# 1. the skin by threshold and seed on 10 planes
{
    printf -- '--image %s/ct.nii.gz\n--size 560x560\naction trace surface scalp:outer\n' "$WORK"
    for k in 0 1 2 3 4 5 6 7 8 9; do
        printf 'action trace plane z=%s\naction trace region -400 4000 122 122\n' "$(echo "90 + $k * 7.5" | bc)"
    done
    printf 'action trace-screenshot ct.png\naction trace-save skin\nquit\n'
} > skin.txt
cat > inside.sh <<'INNER'
set -euo pipefail
fail() { echo "FAIL: $*"; exit 1; }
timeout 120 "$THORAX" view --script skin.txt > skin.out 2> skin.err || { cat skin.err; fail "the skin session: exit $?"; }

# 2. real gestures
cat > g.txt <<EOF
--image $PWD/ct.nii.gz
--size 560x560
action trace surface scalp:outer
action trace plane z=120
wait 15000
action trace-save gest
quit
EOF
"$THORAX" view --script g.txt -v > g.out 2> g.err &
VP=$!
T=60
waitfor() { local end=$((SECONDS + $1)); shift; until "$@" > /dev/null 2>&1; do [ $SECONDS -lt $end ] || return 1; sleep 0.1; done; }
waitfor $T grep -q "window 1 drawn" g.err || { cat g.err; kill $VP; fail "no viewer window was drawn"; }
W=$(xdotool search --onlyvisible --name "^thorax " 2>/dev/null | head -1 || true)
[ -n "$W" ] || { kill $VP; fail "no viewer window appeared"; }
xdotool windowactivate --sync "$W" 2>/dev/null || true
# the pane is the window's left part (560 x 560 below the menu bar): four clicks round its middle,
# then a double click on the first point closes the loop
for xy in "200 200" "360 200" "360 380" "200 380"; do
    set -- $xy
    xdotool mousemove --window "$W" "$1" "$2" click 1
    sleep 0.6
done
xdotool mousemove --window "$W" 200 200 click 1
sleep 0.6
# a point dragged, a point inserted on an edge (Shift+click), a point deleted (Ctrl+click)
xdotool mousemove --window "$W" 360 380 mousedown 1 mousemove --window "$W" 370 390 mousemove --window "$W" 380 400 mouseup 1
sleep 0.6
xdotool mousemove --window "$W" 280 200 keydown shift click 1 keyup shift
sleep 0.6
xdotool mousemove --window "$W" 200 380 keydown ctrl click 1 keyup ctrl
sleep 0.6
# the wheel up one notch: the next plane; a right-button drag to the right: a wider window
xdotool mousemove --window "$W" 280 300 click 4
sleep 0.4
xdotool mousemove --window "$W" 280 300 mousedown 3 mousemove --window "$W" 380 300 mouseup 3
waitfor 40 grep -q "trace-save gest" g.out || { cat g.err; kill $VP; fail "the session was not saved"; }
wait $VP || fail "the viewer exited $?"
INNER
THORAX="$THORAX" xvfb-run -a -s "-screen 0 1600x1000x24" bash inside.sh 2>&1 | grep -v "dbus\|session bus\|^$\|allocation" || true

grep -q "trace: scalp: passes thorax check: 10 planes" skin.out || fail "the skin's surface: $(tail -3 skin.out; tail -3 skin.err)"
grep -q "trace-save skin: contours.txt, model/, labels.nii.gz, session.txt" skin.out || fail "skin not saved: $(tail -3 skin.out)"
"$THORAX" check skin/model -q || fail "thorax check skin/model"
grep -q "^frame +z +y" skin/contours.txt && grep -q "^image sha256:[0-9a-f]\{64\} .*ct.nii.gz" skin/contours.txt ||
    fail "the contour file's frame and image lines: $(head -6 skin/contours.txt)"
[ "$(grep -c '^layer' skin/contours.txt)" = 10 ] || fail "10 layers expected: $(grep -c '^layer' skin/contours.txt)"
$PY - <<'EOF' || fail "the label map"
import nibabel as nib, numpy as np
ct, lab = nib.load("ct.nii.gz"), nib.load("skin/labels.nii.gz")
assert lab.shape == ct.shape, (lab.shape, ct.shape)
assert np.allclose(lab.affine, ct.affine, atol=1e-4), (lab.affine, ct.affine)
a = np.asarray(lab.dataobj)
# inside the traced head (label 1) only between the first and the last traced plane (z 90 .. 157.5)
ks = np.nonzero(a.reshape(-1, a.shape[2]).max(axis=0))[0]
assert ks.min() >= 59 and ks.max() <= 106, (ks.min(), ks.max())
assert set(np.unique(a)) == {0, 1}, np.unique(a)
print("label map: %d voxels inside the head, planes %d..%d" % ((a == 1).sum(), ks.min(), ks.max()))
EOF
echo "skin: $(grep 'passes thorax check: 10 planes' skin.out | tail -1)"

# 2. what the gestures became
[ -s gest/session.txt ] || fail "no session from the gestures: $(cat g.out)"
grep -c "^action trace point " gest/session.txt | grep -qx 4 || fail "4 points expected: $(grep 'action trace' gest/session.txt)"
grep -q "^action trace close" gest/session.txt || fail "the click on the first point did not close the loop: $(grep 'action trace' gest/session.txt)"
grep -q "^action trace move 1 3 " gest/session.txt || fail "the drag did not move point 3: $(grep 'action trace' gest/session.txt)"
grep -q "^action trace insert 1 1 " gest/session.txt || fail "Shift+click did not insert after point 1: $(grep 'action trace' gest/session.txt)"
grep -q "^action trace delete 1 5$" gest/session.txt || fail "Ctrl+click did not delete point 5: $(grep 'action trace' gest/session.txt)"
grep -q "^action trace plane +1" gest/session.txt || fail "the wheel did not step the plane: $(grep 'action trace' gest/session.txt)"
w=$(sed -n 's/^--image-window //p' gest/session.txt)
$PY -c "import sys; sys.exit(0 if float('$w') > 500 else 1)" || fail "the right-button drag did not widen the window (400 -> $w)"
grep -q "^layer 120" gest/contours.txt || fail "the loop's layer: $(grep '^layer' gest/contours.txt)"
# the saved session replays to the same contours
{ cat gest/session.txt; printf 'action trace-save again\nquit\n'; } > replay.txt
xvfb-run -a -s "-screen 0 1600x1000x24" "$THORAX" view --script replay.txt > replay.out 2> replay.err || fail "replay: $(tail -3 replay.err)"
cmp gest/contours.txt again/contours.txt || fail "the replayed session's contours differ"
echo "gestures: $(grep -c '^action trace' gest/session.txt) lines; window $w; replayed byte for byte"

# 3. thorax digitize SCAN opens the viewer (it is killed once its window is drawn)
cat > d.sh <<'INNER'
"$THORAX" digitize ct.nii.gz -v > d.out 2> d.err &
P=$!
for i in $(seq 1 300); do grep -q "window 1 drawn" d.err 2>/dev/null && break; sleep 0.1; done
kill $P 2>/dev/null || true
wait $P 2>/dev/null || true
INNER
THORAX="$THORAX" xvfb-run -a -s "-screen 0 1600x1000x24" bash d.sh
grep -q "window 1 drawn" d.err || fail "thorax digitize SCAN did not open the viewer: $(cat d.err)"
echo "e2e_view_trace: ok"
