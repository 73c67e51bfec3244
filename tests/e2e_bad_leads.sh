#!/usr/bin/env bash
# Bad leads end to end on the real recordings (../shared/data/map3d; issue 24, item 4):
#  - `thorax series check` on the Utah tank's sock recording (cool1-atdr-run1.mat, channels 193..320
#    by sock128.channels, on the open sock, the closed one and a model's surface MODEL:NAME) flags
#    recording channels 288 and 308 and no other; its printed scores agree with the same scores
#    computed here in numpy from the .mat; the list it writes names 288 and 308; the tank's 192
#    leads (on tank_leads_192) and the Dalhousie torso and epicardium (p2_3200_77, 96 frames) flag
#    nothing; the six Dalhousie dipole maps are refused (too few frames to judge);
#  - `forward --bad-leads` (the list, or auto) fills the heart's bad nodes by Laplacian
#    interpolation: through an identity transfer matrix the heart potentials come out, the two bad
#    nodes equal to a numpy least-squares fill (min ||L u||, L the Huiskamp Laplacian of the sock)
#    and every other node equal to the recording;
#  - `leads --bad-leads` samples the same filled values at electrodes on those nodes;
#  - `render --bad-leads` draws the same picture as the filled series given as data, and not the
#    picture of the raw recording; `view --bad-leads` likewise under Xvfb (when there is one), and
#    a running viewer refuses to change --bad-leads;
#  - `inverse --bad-leads` leaves the rows out: the same heart as the rows removed by hand, for a
#    list and for auto (a flat lead);
#  - bad lists and misuse refused with file:line, nothing written.
# Env: THORAX (built CLI), SRC (source dir), WORK (scratch dir, created here).
set -euo pipefail
: "${THORAX:?}" "${SRC:?}" "${WORK:?}"
D="$SRC/../shared/data/map3d"
[ -d "$D" ] || { echo "e2e_bad_leads: no $D: skipped"; exit 0; }
D=$(cd "$D" && pwd)
PY=/usr/bin/python3
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK"
fail() { echo "e2e_bad_leads: FAIL: $*" >&2; exit 1; }
. "$SRC/tests/expect_rc.sh"
REC=$D/data/tank/cool1-atdr-run1.mat
G=$D/geom/tank
CH=$G/sock128.channels

# ---------------------------------------------------------------- series check
expect_rc 0 "$THORAX" series check "$REC" --channels "$CH" --surface "$G/25feb97_sock.pts" -o bad.txt
cp out.txt check_open.txt
grep -q "^bad  *2 of 128 (channels: 288 308)$" check_open.txt || { cat check_open.txt; fail "open sock: not 288 and 308 alone"; }
grep -q "'channel' = the recording's row, 1-based" check_open.txt || fail "the numbering is not said"
[ "$(grep -v '^#' bad.txt | awk '{print $1}' | tr '\n' ' ')" = "288 308 " ] || { cat bad.txt; fail "the list"; }
grep -q "^288  duplicate of channel 308" bad.txt || { cat bad.txt; fail "288's reason"; }
expect_rc 0 "$THORAX" series check "$REC" --channels "$CH" --surface "$G/25feb97_sock_closed.pts"
grep -q "^bad  *2 of 128 (channels: 288 308)$" out.txt || { cat out.txt; fail "closed sock"; }
"$THORAX" import -o tank "$G/tank_full_771.pts" --name tank --role outer "$G/25feb97_sock_closed.pts" --name sock --role heart -q
expect_rc 0 "$THORAX" series check "$REC" --channels "$CH" --surface tank:sock
grep -q "^bad  *2 of 128 (channels: 288 308)$" out.txt && grep -q "^surface  *sock$" out.txt || { cat out.txt; fail "MODEL:NAME"; }
# the scores, computed independently from the .mat and the .fac
$PY - "$D" check_open.txt <<'EOF' || fail "scores differ from numpy's"
import sys, numpy as np, scipy.io as sio
D, table = sys.argv[1], sys.argv[2]
v = sio.loadmat(f"{D}/data/tank/cool1-atdr-run1.mat")["onerun"][0, 0]["potvals"].astype(float)
ch = np.loadtxt(f"{D}/geom/tank/sock128.channels", skiprows=1, dtype=int)
X = v[ch[:, 1] - 1]; X = X - X.mean(1, keepdims=True); rms = np.sqrt((X ** 2).mean(1))
fac = np.loadtxt(f"{D}/geom/tank/25feb97_sock.fac", dtype=int) - 1
nb = [set() for _ in range(128)]
for a, b, c in fac:
    for p, q in ((a, b), (b, c), (c, a)): nb[p].add(q); nb[q].add(p)
rows = {int(l.split()[0]): l.split() for l in open(table) if l.strip()[:1].isdigit() and len(l.split()) > 10}
bad = {95, 115}  # nodes of channels 288 and 308 (0-based)
worst = 0
for i in range(128):
    r = rows[ch[i, 1]]
    assert abs(float(r[2]) - rms[i]) <= 1e-4 * rms[i], (i, r[2], rms[i])
    good = [k for k in sorted(nb[i]) if k not in bad]
    m = X[good].mean(0); m -= m.mean()
    unlike = np.sqrt(((X[i] - m) ** 2).mean()) / rms[i]
    ratio = rms[i] / np.median(rms[good])
    assert abs(float(r[7]) - unlike) < 2e-3 and abs(float(r[8]) - ratio) < 2e-3, (ch[i, 1], r, unlike, ratio)
    if i not in bad: worst = max(worst, unlike)
d = np.sqrt(((X[95] - X[115]) ** 2).mean()) / max(rms[95], rms[115])
assert abs(float(rows[288][5]) - d) < 1e-4, (rows[288], d)
# 288 and 308 stand apart: unlike 4.1 and 7.8 against at most 1.4 for the others (threshold 2.5)
assert worst < 1.5 and float(rows[288][7]) > 4 and float(rows[308][7]) > 7, worst
print("e2e_bad_leads: scores = numpy's; unlike 288 %s, 308 %s, others <= %.3f; d(288, 308) = %.4f" % (rows[288][7], rows[308][7], worst, d))
EOF
# the tank's 192 leads and the Dalhousie torso and epicardium: nothing flagged
{ echo "192 leads"; for i in $(seq 1 192); do echo " $i $i"; done; } > tank192.channels
expect_rc 0 "$THORAX" series check "$REC" --channels tank192.channels --surface "$G/tank_leads_192.pts"
grep -q "^bad  *0 of 192$" out.txt || { grep -v " ok$" out.txt; fail "tank leads flagged"; }
expect_rc 0 "$THORAX" series check "$D/data/torso/p2_3200_77_torso.tsdf" --surface "$D/geom/torso/daltorso.pts"
grep -q "^bad  *0 of 352$" out.txt || { grep -v " ok$" out.txt; fail "Dalhousie torso flagged"; }
expect_rc 0 "$THORAX" series check "$D/data/torso/p2_3200_77_epi.tsdf" --surface "$D/geom/torso/dalepi.pts"
grep -q "^bad  *0 of 98$" out.txt || { grep -v " ok$" out.txt; fail "Dalhousie epicardium flagged"; }
expect_rc 0 "$THORAX" series check "$REC"
grep -q "^bad  *0 of 512$" out.txt || { grep -v " ok$" out.txt; fail "no surface: flagged"; }
expect_rc 1 "$THORAX" series check "$D/data/torso/dipole2.tsdf" --surface "$D/geom/torso/daltorso.pts" -o never.txt
grep -q "6 frames; .* at least 20 frames" err.txt || { cat err.txt; fail "six frames: message"; }
[ ! -e never.txt ] || fail "a refused check wrote its list"

# ---------------------------------------------------------------- forward: filled on the heart
$PY -c "import numpy as np, scipy.io as sio; sio.savemat('I.mat', {'T': np.eye(128)})"
"$THORAX" forward tank --epicardial "$REC" --channels "$CH" --bad-leads bad.txt --transfer I.mat --format mat -o f1 -q
"$THORAX" forward tank --epicardial "$REC" --channels "$CH" --bad-leads auto --transfer I.mat --format mat -o f2 -q
"$THORAX" forward tank --epicardial "$REC" --channels "$CH" --transfer I.mat --format mat -o f0 -q
$PY - "$D" <<'EOF' || fail "forward's fill"
import sys, numpy as np, scipy.io as sio
D = sys.argv[1]
v = sio.loadmat(f"{D}/data/tank/cool1-atdr-run1.mat")["onerun"][0, 0]["potvals"].astype(float)
ch = np.loadtxt(f"{D}/geom/tank/sock128.channels", skiprows=1, dtype=int)
U = v[ch[:, 1] - 1]
def get(d):
    m = sio.loadmat(d + "/electrodes.mat"); k = [k for k in m if not k.startswith("__")]
    a = m["potvals"] if "potvals" in m else m[k[0]]
    return a if a.shape == (128, 608) else a[0, 0]["potvals"]
f0, f1, f2 = get("f0"), get("f1"), get("f2")
assert np.array_equal(f0, U), "no --bad-leads: the recording"
assert np.array_equal(f1, f2), "list and auto differ"
# the model's sock: same nodes as the file (import keeps them); the Huiskamp Laplacian
X = np.loadtxt("tank/sock.pts"); F = np.loadtxt("tank/sock.fac", dtype=int) - 1
n = len(X); nb = [set() for _ in range(n)]
for a, b, c in F:
    for p, q in ((a, b), (b, c), (c, a)): nb[p].add(q); nb[q].add(p)
L = np.zeros((n, n))
for i in range(n):
    J = sorted(nb[i]); h = np.linalg.norm(X[J] - X[i], axis=1); s = 4 / (h.mean() * len(J))
    L[i, J] = s / h; L[i, i] = -(s / h).sum()
B = np.array([95, 115]); Gd = np.setdiff1d(np.arange(n), B)
want = np.linalg.lstsq(L[:, B], -L[:, Gd] @ U[Gd], rcond=None)[0]
keep = np.setdiff1d(np.arange(n), B)
assert np.array_equal(f1[keep], U[keep]), "kept nodes changed"
err = np.abs(f1[B] - want).max() / np.abs(U).max()
assert err < 1e-10, err
# the filled nodes now look like their neighbours: their rms among the neighbours'
r = lambda a: np.sqrt(((a - a.mean(-1, keepdims=True)) ** 2).mean(-1))
for b in B:
    nbr = [k for k in sorted(nb[b]) if k not in B]
    print("e2e_bad_leads: node %d: rms %.0f -> %.0f uV (neighbours %.0f..%.0f)" % (b + 1, r(U[b]), r(f1[b]), min(r(U[nbr])), max(r(U[nbr]))))
np.save("filled.npy", f1)
sio.savemat("filled.mat", {"potvals": f1})
EOF
expect_rc 2 "$THORAX" forward tank --transfer-out --bad-leads bad.txt -o f3
[ ! -e f3 ] || fail "a usage error wrote f3"

# ---------------------------------------------------------------- leads: sampled from the filled sock
$PY - <<'EOF'
import numpy as np
X = np.loadtxt("tank/sock.pts")
np.savetxt("at.pts", X[[95, 115, 0, 50]], fmt="%.10g")
EOF
"$THORAX" leads tank --data "$REC" --channels "$CH" --surface sock --array at.pts --bad-leads bad.txt --format mat -o l1 -q
$PY - <<'EOF' || fail "leads' fill"
import numpy as np, scipy.io as sio
f = np.load("filled.npy"); m = sio.loadmat("l1/array.mat"); k = [k for k in m if not k.startswith("__")][0]
a = m["potvals"] if "potvals" in m else m[k]
a = a if a.shape == (4, 608) else a[0, 0]["potvals"]
assert np.abs(a - f[[95, 115, 0, 50]]).max() <= 1e-9 * np.abs(f).max(), np.abs(a - f[[95, 115, 0, 50]]).max()
EOF
expect_rc 2 "$THORAX" leads tank --bad-leads bad.txt

# ---------------------------------------------------------------- render: the filled picture
# (on the closed sock, the surface forward filled on: the open one has other rings at the base)
R=(--frame 185 --scope frame --size 160x160 -q)
"$THORAX" render "$G/25feb97_sock_closed.pts" --data "$REC" --channels "$CH" --bad-leads bad.txt "${R[@]}" -o r1.png
"$THORAX" render "$G/25feb97_sock_closed.pts" --data filled.mat "${R[@]}" -o r2.png
"$THORAX" render "$G/25feb97_sock_closed.pts" --data "$REC" --channels "$CH" "${R[@]}" -o r0.png
"$THORAX" render "$G/25feb97_sock_closed.pts" --data "$REC" --channels "$CH" --bad-leads auto "${R[@]}" -o r3.png
$PY - <<'EOF' || fail "render --bad-leads"
import vtk
from vtk.util.numpy_support import vtk_to_numpy
import numpy as np
def img(p):
    r = vtk.vtkPNGReader(); r.SetFileName(p); r.Update(); return vtk_to_numpy(r.GetOutput().GetPointData().GetScalars())
a, b, c, d = img("r1.png"), img("r2.png"), img("r0.png"), img("r3.png")
assert np.array_equal(a, b), "the filled recording is not drawn as the filled series"
assert np.array_equal(a, d), "auto differs from the list"
assert (a != c).any(axis=-1).sum() > 50, "filling changed nothing drawn"
EOF

# ---------------------------------------------------------------- inverse: rows left out
$PY - <<'EOF'
import numpy as np, scipy.io as sio
rng = np.random.default_rng(24)
A = rng.standard_normal((30, 12)); x = rng.standard_normal((12, 40)); B = A @ x + 0.01 * rng.standard_normal((30, 40))
B[4] = 7.0  # lead 5: flat (a lost electrode at a constant offset)
sio.savemat("A.mat", {"T": A}); sio.savemat("B.mat", {"B": B})
keep = [i for i in range(30) if i not in (2, 4, 16)]
sio.savemat("A2.mat", {"T": A[keep]}); sio.savemat("B2.mat", {"B": B[keep]})
keep = [i for i in range(30) if i != 4]
sio.savemat("A3.mat", {"T": A[keep]}); sio.savemat("B3.mat", {"B": B[keep]})
open("inv_bad.txt", "w").write("# three leads\n3 loose\n5\n17  # noisy\n")
EOF
IV=(--method tikhonov0 --lambda 0.01 --format mat -q)
"$THORAX" inverse --transfer A.mat --data B.mat --bad-leads inv_bad.txt "${IV[@]}" -o i1
"$THORAX" inverse --transfer A2.mat --data B2.mat "${IV[@]}" -o i2
"$THORAX" inverse --transfer A.mat --data B.mat --bad-leads auto "${IV[@]}" -o i3 2> i3.log
"$THORAX" inverse --transfer A3.mat --data B3.mat "${IV[@]}" -o i4
"$THORAX" inverse --transfer A.mat --data B.mat "${IV[@]}" -o i0
$PY - <<'EOF' || fail "inverse --bad-leads"
import numpy as np, scipy.io as sio
def h(d):
    m = sio.loadmat(d + "/heart.mat"); k = [k for k in m if not k.startswith("__")][0]
    a = m["potvals"] if "potvals" in m else m[k]
    return a if a.dtype != object and a.dtype.names is None else a[0, 0]["potvals"]
assert np.array_equal(h("i1"), h("i2")), "list: not the rows removed by hand"
assert np.array_equal(h("i3"), h("i4")), "auto: not the flat row removed"
assert not np.allclose(h("i0"), h("i4")), "leaving the flat lead out changed nothing"
EOF

# ---------------------------------------------------------------- bad lists and misuse
printf '288\nabc\n' > bad_word.txt
expect_rc 1 "$THORAX" forward tank --epicardial "$REC" --channels "$CH" --bad-leads bad_word.txt --transfer I.mat -o f4
grep -q "bad_word.txt:2: 'abc' is not a channel number" err.txt || { cat err.txt; fail "bad word: message"; }
[ ! -e f4 ] || fail "a refused list wrote f4"
printf '288\n288\n' > bad_twice.txt
expect_rc 1 "$THORAX" render "$G/25feb97_sock.pts" --data "$REC" --channels "$CH" --bad-leads bad_twice.txt -o r4.png
grep -q "bad_twice.txt:2: channel 288 listed twice (first on line 1)" err.txt || { cat err.txt; fail "twice: message"; }
[ ! -e r4.png ] || fail "a refused list wrote r4.png"
expect_rc 1 "$THORAX" inverse --transfer A.mat --data B.mat --bad-leads no_such_list.txt "${IV[@]}" -o i5
[ ! -e i5 ] || fail "a missing list wrote i5"
expect_rc 2 "$THORAX" series info "$REC" --surface "$G/25feb97_sock.pts"

# ---------------------------------------------------------------- view under Xvfb (when there is one)
if command -v xvfb-run > /dev/null; then
    for k in 1 2; do
        { echo "$G/25feb97_sock_closed.pts"
          if [ $k = 1 ]; then printf -- '--data\n%s\n--channels\n%s\n--bad-leads\nbad.txt\n' "$REC" "$CH"
          else printf -- '--data\nfilled.mat\n'; fi
          printf -- '--frame 185\n--scope frame\n--size 160x160\naction screenshot %s/v%s.png\nquit\n' "$PWD" $k; } > v$k.txt
    done
    printf -- '%s\n--data\n%s\n--channels\n%s\n--size 120x120\naction frame-next\n--bad-leads auto\nquit\n' \
        "$G/25feb97_sock.pts" "$REC" "$CH" > v3.txt
    cat > inside.sh <<'INNER'
set -u
"$THORAX" view --script v1.txt > v1.out 2> v1.err || { cat v1.err; echo "view 1 failed"; }
"$THORAX" view --script v2.txt > v2.out 2> v2.err || { cat v2.err; echo "view 2 failed"; }
if "$THORAX" view --script v3.txt > v3.out 2> v3.err; then echo "view 3 accepted"; fi
INNER
    THORAX="$THORAX" xvfb-run -a -s "-screen 0 640x480x24" bash inside.sh 2>&1 | grep -v "dbus\|session bus\|^$" || true
    grep -q "cannot change" v3.err || { cat v3.err; fail "a running viewer changed --bad-leads"; }
    $PY - <<'EOF' || fail "view --bad-leads"
import vtk, numpy as np
from vtk.util.numpy_support import vtk_to_numpy
def img(p):
    r = vtk.vtkPNGReader(); r.SetFileName(p); r.Update(); return vtk_to_numpy(r.GetOutput().GetPointData().GetScalars())
assert np.array_equal(img("v1.png"), img("v2.png")), "the viewer's filled recording differs from the filled series"
EOF
fi
echo "e2e_bad_leads: all passed"
