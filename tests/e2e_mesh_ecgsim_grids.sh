#!/usr/bin/env bash
# ECGSim's torso with its heart (tests/data/ecgsim, issue 24) meshed at every grid from 4 to 12 mm
# with default options: each volume must pass `thorax check` (smallest dihedral angle at least 1 deg,
# no lowered-bar warning), and its smallest dihedral angle, computed here independently from
# volume.pts and volume.tet with numpy, must agree with the check's and be at least 1 deg. Before the
# conformity put points at small corners on sharp folds (src/mesh/conform.c, protect_folds), grids 6,
# 7, 8, 10 and 11 failed (0.79-0.89 deg at heart node 195, where triangle 214's 2.05 deg corner lies on
# a 16 deg fold of the right-ventricular rim). Two meshes run at a time. Under THORAX_QUICK (the
# sanitized build) only grids 6 and 11 run.
set -uo pipefail
: "${THORAX:?}" "${SRC:?}" "${WORK:?}"
PY=/usr/bin/python3
D=$SRC/tests/data/ecgsim
rm -rf "$WORK" && mkdir -p "$WORK" && cd "$WORK"
fails=0
ok() { echo "ok: $1"; }
bad() { echo "FAIL: $1" >&2; fails=$((fails + 1)); }

"$THORAX" import -o ecg -q --scale 1000 "$D/thorax.tri" --name torso --role outer "$D/heart.tri" --name heart --role heart ||
    { bad "import"; exit 1; }
grids=(4 5 6 7 8 9 10 11 12)
[ -n "${THORAX_QUICK:-}" ] && grids=(6 11)

# the smallest dihedral angle, independently: each tetrahedron's six dihedral angles from its face
# normals; it must be at least 1 deg and agree with the check's figure (argv[3])
cat > dihedral.py <<'PYEOF'
import sys, numpy as np
P = np.fromstring(open(sys.argv[1]).read(), sep=" ").reshape(-1, 3)
T = np.fromstring(open(sys.argv[2]).read(), sep=" ").reshape(-1, 5)[:, :4].astype(np.int64) - 1
assert T.min() >= 0 and T.max() < len(P)
A = P[T]
faces = [(1, 2, 3), (0, 3, 2), (0, 1, 3), (0, 2, 1)]
N = []
for f, (a, b, c) in enumerate(faces):
    n = np.cross(A[:, b] - A[:, a], A[:, c] - A[:, a])
    n /= np.linalg.norm(n, axis=1)[:, None]
    n *= -np.sign(np.einsum("ij,ij->i", n, A[:, f] - A[:, a]))[:, None]  # outward
    N.append(n)
m = np.full(len(T), 180.0)
for i in range(4):
    for j in range(i + 1, 4):
        m = np.minimum(m, 180 - np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", N[i], N[j]), -1, 1))))
got, told = m.min(), float(sys.argv[3])
print("%.3f" % got)
sys.exit(0 if got >= 1.0 and abs(got - told) <= 0.01 + 0.01 * told else 1)
PYEOF

one() { # grid: mesh, check, the angle again; the outcome in g$1.res
    local g=$1 told mine
    if ! "$THORAX" mesh ecg -o g$g --grid $g -q 2> g$g.err; then echo "FAIL mesh fails: $(head -1 g$g.err)" > g$g.res; return; fi
    if ! "$THORAX" check g$g > g$g.chk 2>&1; then echo "FAIL check fails: $(grep -v '^ ' g$g.chk | tail -1)" > g$g.res; return; fi
    grep -q 'provenance.*"mesh"' g$g/model.json && { echo "FAIL a lowered-bar warning in model.json" > g$g.res; return; }
    told=$(awk '$1 == "volume" && $2 ~ /^[0-9]+$/ {print $8}' g$g.chk)
    if mine=$($PY dihedral.py g$g/volume.pts g$g/volume.tet "$told"); then
        echo "ok passes thorax check, smallest dihedral $told deg (numpy: $mine deg)" > g$g.res
    else
        echo "FAIL the check says $told deg, numpy ${mine:-failed}" > g$g.res
    fi
    rm -rf g$g # the largest meshes are 100 MB
}
i=0
for g in "${grids[@]}"; do
    one $g &
    i=$((i + 1))
    [ $((i % 2)) = 0 ] && wait
done
wait

for g in "${grids[@]}"; do
    read -r what rest < g$g.res
    if [ "$what" = ok ]; then ok "grid $g mm: $rest"; else bad "grid $g mm: $rest"; fi
done
[ $fails -eq 0 ] || exit 1
echo "all passed"
