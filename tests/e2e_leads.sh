#!/usr/bin/env bash
# Any electrode set and recording channels, end to end on the real files (../shared/data/map3d):
#  - the Dalhousie torso (daltorso.pts/.fac through `thorax import`) with map3d's daltorso.leadlinks
#    (117 leads): `thorax leads MODEL --data dipole2_001.pot --array daltorso.leadlinks -o DIR` with
#    no 12-lead set; each row is the .pot value at its lead's node (read here from the files);
#    electrodes between nodes (triangle centroids, and points 3 mm off the surface) take the
#    triangle's interpolated value; a node list; `thorax electrodes --from` writes any set as a
#    thorax electrode file; -o creates DIR, refuses a user's file, replaces its own; errors exit 1
#    with file:line and write nothing;
#  - the Utah tank (tank_full_771 + the closed sock, meshed): the 512-channel recording with
#    sock128.channels through `series convert --channels` (rows 193..320 exactly, scipy reads the
#    .mat) and `forward --channels --rows tank_leads_192.pts` (the 192 tank leads are nodes of the
#    full tank: DIR/electrodes.raw, no torso-named rows), compared with the tank's measured
#    channels 1..192; the electrode-row transfer matrix (DIR/transfer_electrodes.raw) applied gives
#    the same signals; `leads --data REC --channels` with a channel map made here returns the
#    recorded channels at the tank leads exactly.
# Env: THORAX (built CLI), SRC (source dir), WORK (scratch dir, created here).
set -euo pipefail
: "${THORAX:?}" "${SRC:?}" "${WORK:?}"
D="$SRC/../shared/data/map3d"
[ -d "$D" ] || { echo "e2e_leads: no $D: skipped"; exit 0; }
D=$(cd "$D" && pwd)
PY=/usr/bin/python3
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK"
fail() { echo "e2e_leads: FAIL: $*" >&2; exit 1; }
expect_rc() { # CODE ARGS...
    local want=$1; shift
    set +e
    "$THORAX" "$@" > out.log 2> err.log
    local rc=$?
    set -e
    [ "$rc" -eq "$want" ] || fail "thorax $* -> exit $rc, expected $want: $(cat err.log)"
}

# ---------------------------------------------------------------- the Dalhousie torso
"$THORAX" import -o dal "$D/geom/torso/daltorso.pts" --name torso --role outer -q
POT="$D/data/torso/dipole2_001.pot"
LL="$D/geom/torso/daltorso.leadlinks"
[ ! -e dal/electrodes ] || fail "the imported model has electrodes"
"$THORAX" leads dal --data "$POT" --array "$LL" -o out1 > leads.log
grep -q "array: 117 electrodes (.*daltorso.leadlinks, map3d .leadlinks; 0 between nodes" leads.log || fail "leads: $(cat leads.log)"
[ -f out1/array.txt ] && [ ! -e out1/ecg12.txt ] || fail "out1: $(ls out1)"
"$THORAX" leads dal --data "$POT" --array "$LL" -o out1 -q --format mat      # its own folder: written again
# electrodes between nodes: triangle centroids, and points 3 mm outside the surface along the normal
$PY - "$D" <<'EOF'
import sys, numpy as np
D = sys.argv[1]
p = np.loadtxt(f"{D}/geom/torso/daltorso.pts"); f = np.loadtxt(f"{D}/geom/torso/daltorso.fac", dtype=int) - 1
c = p[f[::37]].mean(axis=1)
np.savetxt("centroids.pts", c, fmt="%.9f")
a, b, cc = p[f[5::41, 0]], p[f[5::41, 1]], p[f[5::41, 2]]
n = np.cross(b - a, cc - a); n /= np.linalg.norm(n, axis=1)[:, None]
vol = np.sum(np.einsum('ij,ij->i', p[f[:, 0]], np.cross(p[f[:, 1]], p[f[:, 2]]))) / 6
out = (0.2 * a + 0.3 * b + 0.5 * cc) + 3.0 * np.sign(vol) * n
np.savetxt("outside.pts", out, fmt="%.9f")
open("nodes.txt", "w").write("# a node list\n7\n300\n1\n")
EOF
"$THORAX" leads dal --data "$POT" --array centroids.pts -o out2 > leads2.log
grep -q "positions; 19 between nodes, moved onto the surface by up to [0-9.e-]* mm" leads2.log || fail "centroids: $(cat leads2.log)"
"$THORAX" leads dal --data "$POT" --array outside.pts -o out3 -q
"$THORAX" leads dal --data "$POT" --array nodes.txt -o out4 -q
$PY - "$D" <<'EOF'
import sys, numpy as np, scipy.io as sio
D = sys.argv[1]
pot = np.loadtxt(f"{D}/data/torso/dipole2_001.pot")
p = np.loadtxt(f"{D}/geom/torso/daltorso.pts"); f = np.loadtxt(f"{D}/geom/torso/daltorso.fac", dtype=int) - 1
def text(p):  # thorax's text series (docs/formats.md): a header, then a line per row, then 'end'
    L = open(p).read().split('\n'); assert L[0] == 'thorax-series 1', L[0]
    n = int(next(l for l in L if l.startswith('rows ')).split()[1])
    e = L.index('end')  # the n rows are the lines before 'end' (after 'time ...' or 't0'/'dt')
    return np.array([[float(x) for x in L[e - n + r].split()] for r in range(n)])
def rows(p): return text(p)[:, 0]
ll = [l.split() for l in open(f"{D}/geom/torso/daltorso.leadlinks")][1:]
ll = [x for x in ll if x]
want = np.array([pot[int(n) - 1] for _, n in ll])
got = sio.loadmat('out1/array.mat')['potvals'][:, 0]
assert got.shape == (117,) and np.array_equal(got, want), (got[:5], want[:5])
# centroids: the mean of the triangle's three corners
c = rows('out2/array.txt'); fc = f[::37]
assert np.abs(c - pot[fc].mean(axis=1)).max() < 1e-9 * np.abs(pot).max(), np.abs(c - pot[fc].mean(axis=1)).max()
# 3 mm outside, projected back onto its triangle: the same weights
o = rows('out3/array.txt'); fo = f[5::41]
want_o = 0.2 * pot[fo[:, 0]] + 0.3 * pot[fo[:, 1]] + 0.5 * pot[fo[:, 2]]
err = np.abs(o - want_o).max() / np.abs(pot).max()
assert err < 1e-6, err
n4 = rows('out4/array.txt'); assert np.array_equal(n4, pot[[6, 299, 0]])
print("e2e_leads: daltorso: 117 leadlinks leads = the .pot at their nodes; %d centroids and %d points 3 mm off "
      "interpolated on their triangles (error %.1e of max |phi|)" % (len(c), len(o), err))
EOF

# thorax electrodes --from: the leadlinks as a thorax electrode file in MODEL/electrodes (its manifest
# names it), giving the same signals; a user's file of that name is left alone
"$THORAX" electrodes dal --from "$LL" -q
grep -q '"daltorso":	"daltorso.txt"' dal/electrodes/electrodes.json || fail "electrodes.json: $(cat dal/electrodes/electrodes.json)"
"$THORAX" electrodes dal --from centroids.pts -q
grep -q '"centroids":	"centroids.txt"' dal/electrodes/electrodes.json && grep -q "^P1 - " dal/electrodes/centroids.txt ||
    fail "centroids.txt"
"$THORAX" leads dal --data "$POT" --array dal/electrodes/daltorso.txt -o out5 --format mat -q
$PY -c "
import scipy.io as sio, numpy as np
assert np.array_equal(sio.loadmat('out5/array.mat')['potvals'], sio.loadmat('out1/array.mat')['potvals'])" ||
    fail "daltorso.txt and daltorso.leadlinks give different signals"
mkdir theirs && echo "their notes" > theirs/daltorso.txt
expect_rc 1 electrodes dal --from "$LL" -o theirs
[ "$(cat theirs/daltorso.txt)" = "their notes" ] && [ "$(ls theirs)" = "daltorso.txt" ] || fail "electrodes -o over a user's file"

# -o: created; a user's file of the same name is never replaced; an error writes nothing
mkdir mine && echo "my notes" > mine/array.txt
expect_rc 1 leads dal --data "$POT" --array "$LL" -o mine
grep -q "mine/array.txt" err.log || fail "user's file: $(cat err.log)"
[ "$(cat mine/array.txt)" = "my notes" ] && [ "$(ls mine)" = "array.txt" ] || fail "a user's file was touched"
expect_rc 1 leads dal --data "$POT" --array "$LL" -o no/such/dir
[ ! -e no ] || fail "a failed run created no/"
printf '2 leads\n1 5\n2 400\n' > bad.leadlinks
expect_rc 1 leads dal --data "$POT" --array bad.leadlinks -o bad1
grep -q 'bad.leadlinks:3: lead 2 ("2"): node 400 is not on surface "torso" (nodes 1..352)' err.log || fail "$(cat err.log)"
[ ! -e bad1 ] || fail "a failed run left bad1"
echo "0 0 1000" > far.pts
expect_rc 1 leads dal --data "$POT" --array far.pts -o bad2
grep -q 'electrode 1 ("P1"): position .* mm from surface "torso" (at most 10 mm)' err.log || fail "$(cat err.log)"
expect_rc 1 leads dal --data "$POT" -o bad3
grep -q "no electrodes: .*give --twelve FILE or --array FILE" err.log || fail "$(cat err.log)"
expect_rc 2 leads dal --data "$POT" --array "$LL"
expect_rc 2 leads dal --channels "$D/geom/tank/sock128.channels" --array "$LL"
[ ! -e bad2 ] && [ ! -e bad3 ] || fail "a failed run wrote output"

# ---------------------------------------------------------------- the Utah tank
REC="$D/data/tank/cool1-atdr-run1.mat"
CH="$D/geom/tank/sock128.channels"
TL="$D/geom/tank/tank_leads_192.pts"
"$THORAX" series convert "$REC" --channels "$CH" -o sock.mat -q
"$THORAX" series info "$REC" --channels "$CH" | grep -q "^rows *128$" || fail "series info --channels"
"$THORAX" import -o tank "$D/geom/tank/tank_full_771.pts" --name tank --role outer \
    "$D/geom/tank/25feb97_sock_closed.pts" --name sock --role heart -q
"$THORAX" mesh tank -q
"$THORAX" forward tank --epicardial "$REC" --channels "$CH" --rows "$TL" -o tsol -q
[ -f tsol/electrodes.raw ] && [ -f tsol/torso.raw ] || fail "tsol: $(ls tsol)"
grep -q '"channels":' tsol/solution.json && grep -q '"electrodes":	"electrodes.raw"' tsol/solution.json || fail "solution.json"
"$THORAX" forward tank --transfer-out --rows "$TL" -o ttr -q
[ -f ttr/transfer_electrodes.raw ] && [ ! -e ttr/transfer.raw ] || fail "ttr: $(ls ttr)"
"$THORAX" forward tank --epicardial "$REC" --channels "$CH" --transfer ttr/transfer_electrodes.raw -o tsol2 -q
[ -f tsol2/electrodes.raw ] && [ ! -e tsol2/torso.raw ] || fail "an electrode-row matrix wrote $(ls tsol2)"
# the node-row matrix applied with --rows: torso.raw (nodes) and electrodes.raw sampled from it
"$THORAX" forward tank --transfer-out -o tfull -q
"$THORAX" forward tank --epicardial "$REC" --channels "$CH" --transfer tfull/transfer.raw --rows "$TL" -o tsol3 -q
[ -f tsol3/electrodes.raw ] && [ -f tsol3/torso.raw ] || fail "node-row matrix with --rows: $(ls tsol3)"
# leads on a solution with no 12-lead set: the array alone, sampled as forward --rows sampled it
"$THORAX" leads tsol --array "$TL" --format raw -q
[ ! -e tsol/ecg12.raw ] && grep -q '"array_raw":	"array.raw"' tsol/solution.json || fail "leads tsol --array"
cmp -s tsol/array.raw tsol/electrodes.raw || $PY -c "
import numpy as np
def raw(p):
    b = open(p, 'rb').read(); r, f = np.frombuffer(b[8:24], dtype='<u8'); return np.frombuffer(b[200:], dtype='<f8')[f:]
assert np.array_equal(raw('tsol/array.raw'), raw('tsol/electrodes.raw'))" || fail "leads --array differs from forward --rows"
expect_rc 1 leads tsol2
grep -q "holds the potentials at its electrodes" err.log || fail "$(cat err.log)"
# the tank leads' channels (1..192) as a map of the full tank's nodes, made from the positions
$PY - "$D" <<'EOF'
import sys, numpy as np
D = sys.argv[1]
full = np.loadtxt(f"{D}/geom/tank/tank_full_771.pts"); leads = np.loadtxt(f"{D}/geom/tank/tank_leads_192.pts")
d = np.linalg.norm(leads[:, None] - full[None], axis=2); node = d.argmin(axis=1); assert d.min(axis=1).max() < 1e-9
ch = np.zeros(len(full), int); ch[node] = np.arange(1, 193)
open("tank.channels", "w").write("%d leads\n" % len(full) + "".join("%d %d\n" % (i + 1, c) for i, c in enumerate(ch)))
EOF
"$THORAX" leads tank --data "$REC" --channels tank.channels --array "$TL" -o tleads > tleads.log
grep -q "array: 192 electrodes (.*positions; 0 between nodes" tleads.log || fail "$(cat tleads.log)"
$PY - "$REC" <<'EOF'
import sys, numpy as np, scipy.io as sio
pv = sio.loadmat(sys.argv[1])['onerun']['potvals'][0, 0].astype(float)
def raw(p):
    b = open(p, 'rb').read(); assert b[:8] == b'THXSER01'
    r, f = np.frombuffer(b[8:24], dtype='<u8'); d = np.frombuffer(b[200:], dtype='<f8')
    return d[f:].reshape(f, r).T
s = sio.loadmat('sock.mat')['potvals']
assert s.shape == (128, 608) and np.array_equal(s, pv[192:320])
E, E2, E3 = raw('tsol/electrodes.raw'), raw('tsol2/electrodes.raw'), raw('tsol3/electrodes.raw')
assert E.shape == (192, 608)
assert np.abs(E - E2).max() < 1e-7 * np.abs(E).max(), np.abs(E - E2).max()
assert np.abs(E - E3).max() < 1e-7 * np.abs(E).max(), np.abs(E - E3).max()
def text(p):
    L = open(p).read().split('\n'); assert L[0] == 'thorax-series 1', L[0]
    n = int(next(l for l in L if l.startswith('rows ')).split()[1])
    e = L.index('end')  # the n rows are the lines before 'end' (after 'time ...' or 't0'/'dt')
    return np.array([[float(x) for x in L[e - n + r].split()] for r in range(n)])
T = text('tleads/array.txt')
assert T.shape == (192, 608) and np.array_equal(T, pv[:192]), T.shape
# the computed tank potentials against the measured ones (common reference removed per frame),
# at the 50 frames of largest measured RMS
a, b = E - E.mean(0), pv[:192] - pv[:192].mean(0)
fr = np.argsort(np.sqrt((b ** 2).mean(0)))[-50:]
cc = np.median([np.corrcoef(a[:, k], b[:, k])[0, 1] for k in fr])
print("e2e_leads: tank: sock128.channels -> 128 x 608; forward at the 192 tank leads vs measured: median "
      "correlation %.3f at the 50 largest frames; transfer_electrodes applied = solved (%.1e)" %
      (cc, np.abs(E - E2).max() / np.abs(E).max()))
assert cc > 0.85, cc
EOF
! find "$WORK" -name '*.tmp*' | grep -q . || fail "temporary files left"
echo "e2e_leads: all checks passed"
