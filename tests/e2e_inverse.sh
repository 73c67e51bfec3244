#!/usr/bin/env bash
# thorax inverse end to end on the real Utah tank (../shared/data/map3d): tank_full_771 as outer,
# the closed 128-node sock as heart, meshed; the transfer matrix sock -> the 192 tank leads; the
# measured tank leads (channels 1..192 of cool1-atdr-run1.mat) inverted and compared with the
# measured sock (channels 193..320 through sock128.channels):
#  - every method and a λ rule: DIR/heart.raw (128 x 608, read back by thorax series and by scipy
#    after conversion), DIR/lambda.txt (a line per frame), DIR/inverse.json, DIR/lcurve.png (read by
#    VTK's PNG reader: 800 x 600, the red mark present), DIR/lcurve.svg (parsed
#    by Python's XML parser: a polyline and the corner marked);
#  - CC over the 150 most active frames above a floor measured here (Tikhonov order 2, CRESO);
#  - the heart surface found through solution.json beside the matrix (tikhonov1/2, tv);
#  - a .mat matrix from elsewhere (FILE.mat:NAME) gives the same solution as thorax's own file;
#  - bad input refused with exit 1, the file, row and frame named, nothing written: data with the
#    wrong rows, NaN in the data, NaN in the matrix, an unknown λ rule (exit 2), discrepancy
#    without --noise, a user's directory as -o.
# Env: THORAX (built CLI), SRC (source dir), WORK (scratch dir, created here).
set -euo pipefail
: "${THORAX:?}" "${SRC:?}" "${WORK:?}"
D="$SRC/../shared/data/map3d"
[ -d "$D" ] || { echo "e2e_inverse: no $D: skipped"; exit 0; }
D=$(cd "$D" && pwd)
PY=/usr/bin/python3
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK"
fail() { echo "e2e_inverse: FAIL: $*" >&2; exit 1; }
. "$SRC/tests/expect_rc.sh"
T=$D/geom/tank
REC=$D/data/tank/cool1-atdr-run1.mat
"$THORAX" import -o tank "$T/tank_full_771.pts" --name tank --role outer "$T/25feb97_sock_closed.pts" --name sock --role heart -q
"$THORAX" mesh tank -q
"$THORAX" forward tank --transfer-out --rows "$T/tank_leads_192.pts" -o Tt -q
{ echo "192 leads"; for i in $(seq 1 192); do echo " $i $i"; done; } > tank192.channels
"$THORAX" series convert "$REC" --channels tank192.channels -o leads.raw -q
"$THORAX" series convert "$REC" --channels "$T/sock128.channels" -o sock.raw -q
M=Tt/transfer_electrodes.raw

for method in tikhonov0 tikhonov1 tikhonov2 tsvd greensite tv; do
    rule=lcurve
    [ $method = tv ] && rule=creso
    expect_rc 0 "$THORAX" inverse --transfer $M --data leads.raw --method $method --lambda $rule --truth sock.raw -o inv_$method
    for f in heart.raw lambda.txt inverse.json lcurve.svg lcurve.png; do [ -f inv_$method/$f ] || fail "$method: no $f"; done
    grep -q "^median CC" out.txt || fail "$method: no CC summary printed"
    "$THORAX" series info inv_$method/heart.raw > info.txt || fail "$method: heart.raw not read back"
    grep -Eq "^rows +128$" info.txt && grep -Eq "^frames +608$" info.txt || { cat info.txt; fail "$method: heart.raw is not 128 x 608"; }
    [ "$(grep -vc '^#' inv_$method/lambda.txt)" -eq 608 ] || fail "$method: lambda.txt has not 608 frame lines"
    $PY - inv_$method/lcurve.svg <<'PY' || fail "$method: lcurve.svg"
import sys, xml.etree.ElementTree as ET
r = ET.parse(sys.argv[1]).getroot(); ns = '{http://www.w3.org/2000/svg}'
pl = r.findall('.//' + ns + 'polyline'); assert pl and len(pl[0].get('points').split()) > 5
assert any(c.get('id') == 'corner' for c in r.iter(ns + 'circle'))
PY
    # lcurve.png read by VTK: 800 x 600, and the mark's red present where inverse.json's point maps
    $PY - inv_$method <<'PY' || fail "$method: lcurve.png"
import sys, json, math, vtk
from vtk.util.numpy_support import vtk_to_numpy
d = sys.argv[1]; rd = vtk.vtkPNGReader(); rd.SetFileName(d + '/lcurve.png'); rd.Update()
im = rd.GetOutput(); w, h, _ = im.GetDimensions(); assert (w, h) == (800, 600), (w, h)
a = vtk_to_numpy(im.GetPointData().GetScalars()).reshape(h, w, -1)[::-1]  # VTK's rows go up
red = (a[:, :, 0] == 0xd6) & (a[:, :, 1] == 0x27) & (a[:, :, 2] == 0x28)
assert red.sum() > 40, red.sum()  # the mark and the legend's disc
j = json.load(open(d + '/inverse.json')); m = j['lcurve_mark']
assert m['residual'] > 0 and m['solution_norm'] > 0 and m['lambda'] == m['lambda'], m
PY
done
# accuracy on the measured sock: CC over the 150 frames of largest sock RMS (activity)
"$THORAX" inverse --transfer $M --data leads.raw --method tikhonov2 --lambda creso -o inv_acc -q
"$THORAX" series convert inv_acc/heart.raw -o x.mat -q
"$THORAX" series convert sock.raw -o s.mat -q
$PY - x.mat s.mat <<'PY' || fail "tank accuracy"
import sys, numpy as np, scipy.io as sio
x = sio.loadmat(sys.argv[1])['potvals']; s = sio.loadmat(sys.argv[2])['potvals']
assert x.shape == (128, 608), x.shape
idx = np.argsort(np.sqrt((s ** 2).mean(0)))[-150:]
cc = np.median([np.corrcoef(x[:, f], s[:, f])[0, 1] for f in idx])
print("tank, tikhonov2 + CRESO: median CC over the 150 most active frames %.3f" % cc)
assert cc > 0.5, cc
PY
# a .mat from elsewhere: the same matrix as variable T among others gives the same solution
"$THORAX" series convert $M -o Tm.mat -q
$PY -c "import scipy.io as s; a=s.loadmat('Tm.mat')['potvals']; s.savemat('other.mat', {'junk': a[:5], 'T': a})"
"$THORAX" inverse --transfer other.mat:T --data leads.raw --method tikhonov0 --lambda gcv -o inv_mat -q
"$THORAX" inverse --transfer $M --data leads.raw --method tikhonov0 --lambda gcv -o inv_raw -q
cmp -s inv_mat/heart.raw inv_raw/heart.raw || fail ".mat:T and the raw matrix give different solutions"
# tikhonov1 on a .mat needs --heart (no solution.json beside it), and works with it
expect_rc 1 "$THORAX" inverse --transfer other.mat:T --data leads.raw --method tikhonov1 -o inv_h
grep -q "heart surface" err.txt || fail "tikhonov1 without a heart: $(cat err.txt)"
expect_rc 0 "$THORAX" inverse --transfer other.mat:T --data leads.raw --method tikhonov1 --heart tank -o inv_h

# bad input
expect_rc 1 "$THORAX" inverse --transfer $M --data sock.raw -o bad1
grep -q "has 192 rows" err.txt && grep -q "sock.raw has 128 rows" err.txt || fail "row mismatch message: $(cat err.txt)"
[ ! -e bad1 ] || fail "bad1 written"
"$THORAX" series convert leads.raw -o l.mat -q
$PY -c "
import scipy.io as s; a=s.loadmat('l.mat')['potvals']; a[16,99]=float('nan'); s.savemat('nan.mat', {'potvals': a})
t=s.loadmat('Tm.mat')['potvals']; t[4,6]=float('nan'); s.savemat('Tnan.mat', {'potvals': t})"
expect_rc 1 "$THORAX" inverse --transfer $M --data nan.mat -o bad2
grep -q "nan.mat: row 17, frame 100: NaN" err.txt || fail "NaN in data: $(cat err.txt)"
expect_rc 1 "$THORAX" inverse --transfer Tnan.mat --data leads.raw -o bad3
grep -q "Tnan.mat: row 5, column 7 (heart node): NaN" err.txt || fail "NaN in matrix: $(cat err.txt)"
expect_rc 2 "$THORAX" inverse --transfer $M --data leads.raw --lambda lcurv -o bad4
expect_rc 2 "$THORAX" inverse --transfer $M --data leads.raw --lambda discrepancy -o bad5
expect_rc 1 "$THORAX" inverse --transfer $M --data leads.raw --method tsvd --lambda creso -o bad6
[ ! -e bad2 ] && [ ! -e bad3 ] && [ ! -e bad4 ] && [ ! -e bad5 ] && [ ! -e bad6 ] || fail "output left by a refused run"
mkdir mine && echo keep > mine/notes.txt
expect_rc 1 "$THORAX" inverse --transfer $M --data leads.raw -o mine
[ "$(cat mine/notes.txt)" = keep ] && [ ! -e mine/heart.raw ] || fail "a user's directory was touched"
# thorax's own result directory is replaced
expect_rc 0 "$THORAX" inverse --transfer $M --data leads.raw --lambda 100 -o inv_raw
grep -q '"lambda_rule":	"fixed"' inv_raw/inverse.json || fail "fixed λ not recorded"
echo "e2e_inverse: all passed"
