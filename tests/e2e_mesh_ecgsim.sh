#!/usr/bin/env bash
# ECGSim's torso and ventricles (tests/data/ecgsim, issue 24). The model is valid (`thorax check`
# passes) and `thorax mesh` must mesh it with default options, with --no-heart, with --repair 0 and
# with --quality 0 --repair 0 (0.794 deg before the repair's wide slide; --quality 0 alone, 2.09 deg,
# is left out for time: 40 s), each volume passing `thorax check` at its default threshold. Before the repair inserted nodes the
# heart meshed failed ("smallest dihedral angle 0.889 deg < 1 deg" at the right-ventricular rim).
# Then, with the heart left out (its surface potentials given), every column of the FEM transfer
# matrix (`thorax forward --transfer-out`) is compared with BEM's (`thorax bem --transfer --refine 2`:
# the heart subdivided twice, within 0.04 of three times; the unrefined BEM's endocardial columns are
# 0.74 off, docs/design/mesh.md, "Folds"): no column may be all zero (node 217, at the bottom of a
# narrow pocket of the right-ventricular cavity, had one: no free node reached it), and the median
# relative error (each column less its mean) must be below 0.1 for the epicardial and the
# endocardial nodes alike (the endocardial median was 0.32 against this reference before the mesh
# was graded towards the heart's folds, where the endocardia meet the epicardium at angles down to
# 7.5 deg). Epicardial and endocardial nodes are told apart independently of thorax: a ray from the
# node along its outward normal meets the heart surface again for an endocardial node (the cavity's
# far wall) and escapes for an epicardial one.
# Under THORAX_QUICK (the sanitized build) only the default mesh runs (no --no-heart, --repair 0 or
# FEM/BEM comparison).
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
"$THORAX" check ecg -q && ok "the model is valid" || bad "thorax check of the model"
variants=("" "--no-heart" "--repair 0" "--quality 0 --repair 0")
[ -n "${THORAX_QUICK:-}" ] && variants=("")
for o in "${variants[@]}"; do
    tag=v$(echo "$o" | tr -d ' -')
    if "$THORAX" mesh ecg -o $tag $o -q --stats > $tag.stats 2> $tag.err && "$THORAX" check $tag > $tag.chk 2>&1; then
        ok "mesh ${o:-(default options)}: passes thorax check, smallest dihedral $(awk '$1 == "volume" && $2 ~ /^[0-9]+$/ {print $8}' $tag.chk) deg"
        grep -q 'provenance.*"mesh"' $tag/model.json && bad "mesh $o: a lowered-bar warning in model.json"
    else bad "mesh ${o:-(default options)}: $(cat $tag.err; grep -v '^ ' $tag.chk 2>/dev/null | tail -2)"; fi
done
[ -n "${THORAX_QUICK:-}" ] && { [ $fails -eq 0 ] || exit 1; echo "all passed (quick: no FEM/BEM comparison)"; exit 0; }
# the heart's folds found and graded around (44 edges below 120 deg), and --folds refused when malformed
grep -q '^folds: 44 edges of the heart' vnoheart.stats && ok "--no-heart: $(grep '^folds' vnoheart.stats)" ||
    bad "--no-heart: no folds line: $(grep -i fold vnoheart.stats)"
for f in 180 -1 120/0 abc 120/x; do
    if "$THORAX" mesh ecg -o badfolds --no-heart --folds "$f" -q 2> badfolds.err; then bad "--folds $f accepted"
    elif [ -e badfolds ]; then bad "--folds $f: output written"
    else grep -q -- "--folds takes DEG" badfolds.err && ok "--folds $f refused" || bad "--folds $f: $(cat badfolds.err)"; fi
done

"$THORAX" forward vnoheart --transfer-out -o fem --format text -q || bad "forward --transfer-out"
"$THORAX" bem vnoheart --transfer --refine 2 -o bem --format text -q || bad "bem --transfer --refine 2"
$PY - ecg/heart.pts ecg/heart.fac fem/transfer.txt bem/transfer.txt <<'PYEOF' || bad "FEM against BEM columns"
import sys, math
P = [list(map(float, l.split())) for l in open(sys.argv[1]) if l.strip()]
F = [[int(x) - 1 for x in l.split()] for l in open(sys.argv[2]) if l.strip()]
def sub(a, b): return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
def cross(a, b): return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
def dot(a, b): return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
assert min(min(t) for t in F) >= 0 and max(max(t) for t in F) < len(P)
N = [[0.0] * 3 for _ in P]
for t in F:
    n = cross(sub(P[t[1]], P[t[0]]), sub(P[t[2]], P[t[0]]))
    for v in t: N[v] = [N[v][k] + n[k] for k in range(3)]
def hits(o, d, skip):
    c = 0
    for t in F:
        if skip in t: continue
        a = P[t[0]]; e1, e2 = sub(P[t[1]], a), sub(P[t[2]], a); h = cross(d, e2); det = dot(e1, h)
        if abs(det) < 1e-12: continue
        s = sub(o, a); u = dot(s, h) / det
        if u < 0 or u > 1: continue
        q = cross(s, e1); w = dot(d, q) / det
        if w < 0 or u + w > 1: continue
        c += dot(e2, q) / det > 1e-9
    return c
endo = set()
for v, n in enumerate(N):
    l = math.sqrt(dot(n, n)); n = [x / l for x in n]
    a = [1, 0, 0] if abs(n[0]) < 0.9 else [0, 1, 0]
    u = cross(n, a); lu = math.sqrt(dot(u, u)); u = [x / lu for x in u]; w = cross(n, u)
    dirs = (n, [n[k] * math.cos(0.17) + u[k] * math.sin(0.17) for k in range(3)], [n[k] * math.cos(0.17) + w[k] * math.sin(0.17) for k in range(3)])
    if sum(hits(P[v], d, v) > 0 for d in dirs) >= 2: endo.add(v)
def load(p):
    R = []
    for l in open(p):
        f = l.split()
        try: R.append([float(x) for x in f])
        except ValueError: continue
    return [r for r in R if len(r) == len(P)]
A, B = load(sys.argv[3]), load(sys.argv[4])
assert len(A) == len(B) == 300 and len(A[0]) == len(P), (len(A), len(B))
zero, re = [], []
for j in range(len(P)):
    f = [r[j] for r in A]; b = [r[j] for r in B]
    mf, mb = sum(f) / len(f), sum(b) / len(b)
    f = [x - mf for x in f]; b = [x - mb for x in b]
    if max(abs(x) for x in f) == 0: zero.append(j + 1)
    re.append(math.sqrt(sum((x - y) ** 2 for x, y in zip(f, b))) / math.sqrt(sum(y * y for y in b)))
med = lambda xs: sorted(xs)[len(xs) // 2]
ren = [re[j] for j in range(len(P)) if j in endo]; rep = [re[j] for j in range(len(P)) if j not in endo]
print("heart nodes %d: endocardial %d, epicardial %d; all-zero FEM columns %s; median RE endocardial %.3f, epicardial %.3f"
      % (len(P), len(ren), len(rep), zero or "none", med(ren), med(rep)))
ok = not zero and med(rep) < 0.1 and 60 < len(ren) < 130 and med(ren) < 0.1
sys.exit(0 if ok else 1)
PYEOF
[ $fails -eq 0 ] || { echo "$fails failed"; exit 1; }
echo "all passed"
