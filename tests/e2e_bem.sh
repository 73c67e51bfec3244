#!/bin/bash
# End-to-end: `thorax bem` on OpenMEEG's Head1 (the .geom/.cond pair as it is): dipoles 1-5 at the
# electrodes (Head1.patches) against the analytic potentials, read back by scipy from the .mat
# series; the cortex-to-scalp transfer matrix (--heart cortex) read back and checked (a constant on
# the cortex gives that constant on the scalp); byte-identical reruns; bad input refused with exit
# 1 (open surface, dipole outside, malformed dipole line) or 2 (usage), nothing written; the
# Dalhousie torso (map3d's data) meshed: dipoles in its heart by BEM against the FEM, in mV.
# Env: THORAX (built CLI), SRC (source dir), WORK (scratch dir, created here).
set -eu
: "${THORAX:?}" "${SRC:?}" "${WORK:?}"
PY=/usr/bin/python3
D="$SRC/../shared/data/openmeeg-spheres"
if [ ! -d "$D" ]; then echo "e2e_bem: no $D; skipped"; exit 0; fi
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK"
fail() { echo "e2e_bem: FAIL: $*" >&2; exit 1; }
expect_rc() { # CODE ARGS...
    local want=$1; shift
    set +e
    "$THORAX" "$@" >out.log 2>err.log
    local rc=$?
    set -e
    [ "$rc" -eq "$want" ] || fail "thorax $* -> exit $rc, expected $want: $(cat err.log)"
}
H="$D/data/Head1"
expect_rc 0 bem "$H/Head1.geom" --dipoles "$H/Head1.dip" --electrodes "$H/Head1.patches" -o dip --format mat -q
for f in bem.json outer.mat nodes.mat electrodes.mat; do [ -f "dip/$f" ] || fail "dip/$f missing"; done
"$PY" - "$D" <<'EOF' || fail "Head1 against the analytic potentials"
import json, sys
import numpy as np, scipy.io
D = sys.argv[1]
j = json.load(open("dip/bem.json"))
assert j["format"] == "thorax-bem" and j["problem"] == "dipoles", j
assert j["method"].startswith("symmetric") and "isolated_problem" not in j, j
assert j["unknowns"] == 3 * 42 + 2 * 80, j
assert [s["name"] for s in j["surfaces"]] == ["cortex", "skull", "scalp"]
assert [s["sigma_in"] for s in j["surfaces"]] == [1, 0.0125, 1]
m = scipy.io.loadmat("dip/electrodes.mat")
v = [m[k] for k in m if not k.startswith("__") and getattr(m[k], "shape", (0,)) == (32, 6)]
assert len(v) == 1, {k: getattr(m[k], "shape", None) for k in m}
v = v[0]
a = np.loadtxt(D + "/tests/analytic/eeg_head1_analytic.txt")
# OpenMEEG's own threshold for Head1 is 0.13; its suite expects dipoles 4 and 5 to fail it (WILL_FAIL):
# bounded there by what the symmetric method reaches (docs/validation.md)
bound = [0.13, 0.13, 0.13, 0.20, 0.26]
for d in range(5):
    x = v[:, d] - v[:, d].mean(); y = a[:, d] - a[:, d].mean()
    rdm = np.linalg.norm(x / np.linalg.norm(x) - y / np.linalg.norm(y))
    print("Head1 dipole %d: RDM %.4f MAG %.4f" % (d + 1, rdm, np.linalg.norm(x) / np.linalg.norm(y)))
    assert rdm < bound[d], (d, rdm)
    assert abs(1 - np.linalg.norm(x) / np.linalg.norm(y)) < 0.13, d
# every node's potentials: the scalp block equals outer.mat
n = scipy.io.loadmat("dip/nodes.mat"); o = scipy.io.loadmat("dip/outer.mat")
n = [n[k] for k in n if not k.startswith("__") and getattr(n[k], "ndim", 0) == 2 and n[k].shape[1] == 6][0]
o = [o[k] for k in o if not k.startswith("__") and getattr(o[k], "ndim", 0) == 2 and o[k].shape[1] == 6][0]
assert n.shape == (126, 6) and o.shape == (42, 6)
assert np.array_equal(n[84:], o)
EOF
# the same again: byte-identical
expect_rc 0 bem "$H/Head1.geom" --dipoles "$H/Head1.dip" --electrodes "$H/Head1.patches" -o dip2 --format mat -q
cmp -s dip/electrodes.mat dip2/electrodes.mat || fail "a rerun differs"
# linear collocation (--method collocation): the isolated problem approach on the cortex
expect_rc 0 bem "$H/Head1.geom" --dipoles "$H/Head1.dip" --electrodes "$H/Head1.patches" -o dipc --method collocation --format text -q
"$PY" - <<'EOF' || fail "--method collocation"
import json
j = json.load(open("dipc/bem.json"))
assert j["method"].startswith("linear collocation") and j["isolated_problem"] == "cortex" and j["unknowns"] == 126, j
EOF
# transfer matrix cortex -> scalp (the cortex as the given-potential surface)
expect_rc 0 bem "$H/Head1.geom" --transfer --heart cortex -o tr --format text -q
expect_rc 0 series info tr/transfer.txt
grep -Eq "^rows +42" out.log && grep -Eq "^frames +42" out.log || fail "series info: $(cat out.log)"
"$PY" - <<'EOF' || fail "transfer matrix"
import numpy as np
L = open("tr/transfer.txt").read().split("\n")
i = [k for k, l in enumerate(L) if l.startswith("dt")][0]
assert any(l.startswith("label transfer matrix scalp <- cortex (bem)") for l in L[:i]), L[:i]
T = np.loadtxt([l for l in L[i + 1:] if l.strip() and l != "end"])
assert T.shape == (42, 42), T.shape
assert abs(T.sum(axis=1) - 1).max() < 1e-8, abs(T.sum(axis=1) - 1).max()
EOF
# electrode rows: the patches projected on the scalp; each row the interpolation of node rows
expect_rc 0 bem "$H/Head1.geom" --transfer --heart cortex --electrodes "$H/Head1.patches" -o tre --format text -q
"$PY" - "$H/Head1.patches" <<'EOF2' || fail "electrode-row transfer matrix"
import numpy as np
L = open("tre/transfer_electrodes.txt").read().split("\n")
i = [k for k, l in enumerate(L) if l.startswith("dt")][0]
assert any(l.startswith("label transfer matrix electrodes on scalp <- cortex (bem)") for l in L[:i]), L[:i]
E = np.loadtxt([l for l in L[i + 1:] if l.strip() and l != "end"])
assert E.shape == (32, 42), E.shape
assert abs(E.sum(axis=1) - 1).max() < 1e-8
EOF2
# the distributed path: PETSc's MATSCALAPACK on 1 rank and under mpirun -np 2, the same matrix
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
expect_rc 0 bem "$H/Head1.geom" --transfer --heart cortex -o tr1 --format text --scalapack -q
set +e
mpirun -np 2 "$THORAX" bem "$H/Head1.geom" --transfer --heart cortex -o tr2 --format text -q > out.log 2> err.log
rc=$?
set -e
[ "$rc" -eq 0 ] || fail "mpirun -np 2 thorax bem: exit $rc: $(cat err.log)"
"$PY" - <<'EOF2' || fail "ScaLAPACK transfer matrices"
import json
import numpy as np
def read(p):
    L = open(p).read().split("\n")
    i = [k for k, l in enumerate(L) if l.startswith("dt")][0]
    return np.loadtxt([l for l in L[i + 1:] if l.strip() and l != "end"])
a, b, c = read("tr/transfer.txt"), read("tr1/transfer.txt"), read("tr2/transfer.txt")
s = abs(a).max()
print("LAPACK vs ScaLAPACK 1 rank: %.2g; 1 vs 2 ranks: %.2g" % (abs(a - b).max() / s, abs(b - c).max() / s))
assert abs(a - b).max() < 1e-12 * s and abs(b - c).max() < 1e-12 * s
j = json.load(open("tr2/bem.json"))
assert j["ranks"] == 2 and j["dense_solver"].startswith("ScaLAPACK"), j
EOF2
# the symmetric dipoles distributed: each rank assembles its rows of the symmetric system from the
# pair integrals alone; ScaLAPACK on 1 rank and on 2 against the serial LAPACK path (dip/, .mat)
expect_rc 0 bem "$H/Head1.geom" --dipoles "$H/Head1.dip" --electrodes "$H/Head1.patches" -o sd1 --format mat --scalapack -q
set +e
mpirun -np 2 "$THORAX" bem "$H/Head1.geom" --dipoles "$H/Head1.dip" --electrodes "$H/Head1.patches" -o sd2 --format mat -q \
    > out.log 2> err.log
rc=$?
set -e
[ "$rc" -eq 0 ] || fail "mpirun -np 2 thorax bem --dipoles: exit $rc: $(cat err.log)"
"$PY" - <<'EOF2' || fail "ScaLAPACK symmetric dipoles"
import json
import numpy as np, scipy.io
def read(p):
    m = scipy.io.loadmat(p)
    return [m[k] for k in m if not k.startswith("__") and getattr(m[k], "ndim", 0) == 2 and m[k].shape[1] == 6][0]
a, b, c = read("dip/nodes.mat"), read("sd1/nodes.mat"), read("sd2/nodes.mat")
s = abs(a).max()
print("symmetric dipoles: LAPACK vs ScaLAPACK 1 rank: %.2g; 1 vs 2 ranks: %.2g" % (abs(a - b).max() / s, abs(b - c).max() / s))
assert a.shape == (126, 6) and abs(a - b).max() < 1e-12 * s and abs(b - c).max() < 1e-12 * s
j = json.load(open("sd2/bem.json"))
assert j["ranks"] == 2 and j["dense_solver"].startswith("ScaLAPACK") and j["method"].startswith("symmetric"), j
EOF2
expect_rc 2 bem "$H/Head1.geom" --dipoles "$H/Head1.dip" --method collocation --scalapack -o bad
grep -q "collocation runs on one process" err.log || fail "collocation under --scalapack: $(cat err.log)"
# bad input
expect_rc 2 bem "$H/Head1.geom" --dipoles "$H/Head1.dip" --transfer -o bad
expect_rc 2 bem "$H/Head1.geom" -o bad
printf '0 0 1.5 0 0 1\n' > outside.dip
expect_rc 1 bem "$H/Head1.geom" --dipoles outside.dip -o bad
grep -q "dipole 1" err.log && grep -q "outside" err.log || fail "outside dipole: $(cat err.log)"
printf '0 0 0.5 0 0 1\n0 0 0.4 0 1\n' > short.dip
expect_rc 1 bem "$H/Head1.geom" --dipoles short.dip -o bad
grep -q "short.dip:2" err.log || fail "short dipole line: $(cat err.log)"
mkdir -p open
cp "$H/Head1.geom" "$H/Head1.cond" "$H/cortex.1.tri" "$H/skull.1.tri" open/
# the scalp with its last triangle left out (the count line says 79)
awk 'NR == 1 { print; next } /^- 80 80 80/ { print "- 79 79 79"; n = 1; next } n && ++k == 80 { next } { print }' \
    "$H/scalp.1.tri" > open/scalp.1.tri
expect_rc 1 bem open/Head1.geom --dipoles "$H/Head1.dip" -o bad
grep -q "not closed" err.log || fail "open surface: $(cat err.log)"
[ ! -e bad ] || fail "a refused run wrote bad/"
! find . -name '*.tmp*' | grep -q . || fail "temporary files left"
mkdir -p mine && echo keep > mine/notes.txt
expect_rc 1 bem "$H/Head1.geom" --dipoles "$H/Head1.dip" -o mine
[ "$(cat mine/notes.txt)" = keep ] || fail "a user's directory was touched"

# A real torso: the Dalhousie torso and epicardium (map3d's daltorsoepi.geom, 352 and 98 nodes),
# meshed (heart 0.4 S/m inside the torso's 0.239): four dipoles in the heart by the symmetric BEM
# against the finite elements (thorax forward --dipoles) at the torso's nodes, both in mV
M3="$SRC/../shared/data/map3d"
if [ -d "$M3/geom/torso" ]; then
    "$THORAX" import -q -o dal --up -y --front -z "$M3/geom/torso/daltorsoepi.geom@1" --name torso --role outer \
        "$M3/geom/torso/daltorsoepi.geom@2" --name epi --role heart || fail "import daltorsoepi.geom"
    "$THORAX" mesh dal -q || fail "mesh dal"
    "$PY" - <<'EOF' || fail "dipoles for the Dalhousie heart"
import numpy as np
e = np.loadtxt("dal/epi.pts"); c = e.mean(0); x = e.max(0) - e.min(0)
P = [c, c + 0.15 * x * [1, 0, 0], c + 0.15 * x * [0, 1, 0.5], c - 0.2 * x * [0, 0, 1]]
Q = [[0, 0, 1], [1, 0, 0], [0, 1, 0], [0.5, 0.5, 0.7]]
open("dal.dip", "w").write("".join("%.6f %.6f %.6f %g %g %g\n" % (*p, *q) for p, q in zip(P, Q)))
EOF
    expect_rc 0 forward dal --dipoles dal.dip -o dalfem --format text -q
    expect_rc 0 bem dal --dipoles dal.dip -o dalbem --format text -q
    "$PY" - <<'EOF' || fail "BEM against FEM on the Dalhousie torso"
import json
import numpy as np
def read(p):
    L = open(p).read().split("\n")
    i = [k for k, l in enumerate(L) if l.startswith("dt")][0]
    return np.loadtxt([l for l in L[i + 1:] if l.strip() and l != "end"])
j = json.load(open("dalbem/bem.json"))
assert j["unit"] == "mV" and j["moment_unit"] == "mA*m" and j["method"].startswith("symmetric"), j
F, B = read("dalfem/torso.txt"), read("dalbem/outer.txt")
assert F.shape == B.shape == (352, 4), (F.shape, B.shape)
for d in range(4):
    x = F[:, d] - F[:, d].mean(); y = B[:, d] - B[:, d].mean()
    rdm = np.linalg.norm(x / np.linalg.norm(x) - y / np.linalg.norm(y)); mag = np.linalg.norm(y) / np.linalg.norm(x)
    print("Dalhousie torso, dipole %d: BEM against FEM RDM %.4f MAG %.4f" % (d + 1, rdm, mag))
    assert rdm < 0.04 and abs(1 - mag) < 0.03, (d, rdm, mag)
EOF
fi
echo "e2e_bem: ok"
