#!/usr/bin/env bash
# `thorax bem --transfer --refine N` on ECGSim's torso and ventricles (tests/data/ecgsim, issue 24,
# item 2): the heart is one closed surface whose endocardia are cavities joined to the epicardium
# at thin rims, and its transfer columns at the cavities' nodes are far from converged on the
# heart's own triangles. With the heart subdivided N = 0, 1, 2 times (the columns mapped back onto
# the heart's nodes): the output has the unrefined shape (300 torso rows x 257 heart columns) and
# bem.json records heart_refine and heart_nodes_solved; --refine 0 is byte-identical to no
# --refine; the endocardial columns' median relative change (each column less its mean) from
# N = 1 to 2 is below that from 0 to 1 (convergence), and so for the epicardial ones; the ScaLAPACK
# path (--scalapack, one rank) gives --refine 1's matrix to rounding. Endocardial nodes are told
# apart independently of thorax, by the ray test of tests/e2e_mesh_ecgsim.sh (a ray from the node
# along its outward normal meets the heart again for an endocardial node). Refused with exit 2 (a
# usage error) and nothing written: --refine -1, --refine 99 (the limit and the memory named),
# --refine without --transfer, a --refine whose dense system exceeds THORAX_MAX_MEMORY.
# Under THORAX_QUICK (the sanitized build) N = 2 and the ScaLAPACK run are left out (N = 0 and 1
# compared, refusals checked).
set -uo pipefail
: "${THORAX:?}" "${SRC:?}" "${WORK:?}"
PY=/usr/bin/python3
D=$SRC/tests/data/ecgsim
rm -rf "$WORK" && mkdir -p "$WORK" && cd "$WORK"
fails=0
ok() { echo "ok: $1"; }
bad() { echo "FAIL: $1" >&2; fails=$((fails + 1)); }
refused() { # WHAT GREP ARGS...: exit 2, the message, no output directory
    local what=$1 msg=$2; shift 2
    "$THORAX" "$@" > out.txt 2> err.txt
    local rc=$?
    if [ $rc -eq 2 ] && grep -q -- "$msg" err.txt && [ ! -e bad ]; then ok "$what refused: $(head -1 err.txt)"
    else bad "$what: exit $rc (expected 2), message $(cat err.txt), output $(ls -d bad 2>/dev/null)"; fi
}

"$THORAX" import -o ecg -q --scale 1000 "$D/thorax.tri" --name torso --role outer "$D/heart.tri" --name heart --role heart ||
    { bad "import"; exit 1; }
"$THORAX" mesh ecg -o v --no-heart -q || { bad "mesh --no-heart"; exit 1; }

levels=(0 1 2)
[ -n "${THORAX_QUICK:-}" ] && levels=(0 1)
for n in "${levels[@]}"; do
    "$THORAX" bem v --transfer --refine $n -o r$n --format text -q || bad "bem --transfer --refine $n"
done
"$THORAX" bem v --transfer -o plain --format text -q || bad "bem --transfer"
cmp -s plain/transfer.txt r0/transfer.txt && ok "--refine 0 is the unrefined transfer, byte for byte" ||
    bad "--refine 0 differs from no --refine"
if [ -z "${THORAX_QUICK:-}" ]; then
    "$THORAX" bem v --transfer --refine 1 --scalapack -o s1 --format text -q || bad "bem --refine 1 --scalapack"
fi

$PY - ecg/heart.pts ecg/heart.fac "${levels[@]}" <<'PYEOF' || bad "the refined transfer matrices"
import sys, math, json, os
P = [list(map(float, l.split())) for l in open(sys.argv[1]) if l.strip()]
F = [[int(x) - 1 for x in l.split()] for l in open(sys.argv[2]) if l.strip()]
levels = [int(x) for x in sys.argv[3:]]
# the ray test of tests/e2e_mesh_ecgsim.sh (copied: endocardial = a ray along the outward normal
# meets the heart again for at least two of three directions)
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
good = True
def check(c, what):
    global good
    print(("ok: " if c else "FAIL: ") + what)
    good = good and c
T = {}
for n in levels:
    T[n] = load("r%d/transfer.txt" % n)
    check(len(T[n]) == 300 and all(len(r) == len(P) for r in T[n]), "--refine %d: 300 x %d, the unrefined shape" % (n, len(P)))
    j = json.load(open("r%d/bem.json" % n))
    nf = len(P)
    for _ in range(n): nf += 3 * (nf * 2 - 4) // 2  # a closed genus-0 surface: t = 2 n - 4, e = 3 t / 2
    check(j.get("heart_refine") == n and j.get("heart_nodes_solved") == nf and j.get("unknowns") == 300 + nf,
          "--refine %d: bem.json heart_refine %s, heart_nodes_solved %s (expected %d), unknowns %s"
          % (n, j.get("heart_refine"), j.get("heart_nodes_solved"), nf, j.get("unknowns")))
def med_change(A, B, nodes):
    """median over the columns of |A_j - B_j| / |B_j|, each column less its mean (B the finer)"""
    re = []
    for j in nodes:
        a = [r[j] for r in A]; b = [r[j] for r in B]
        ma, mb = sum(a) / len(a), sum(b) / len(b)
        a = [x - ma for x in a]; b = [x - mb for x in b]
        re.append(math.sqrt(sum((x - y) ** 2 for x, y in zip(a, b))) / math.sqrt(sum(y * y for y in b)))
    return sorted(re)[len(re) // 2]
en = sorted(endo); ep = [v for v in range(len(P)) if v not in endo]
check(60 < len(en) < 130, "%d endocardial nodes, %d epicardial" % (len(en), len(ep)))
ch = {}
for n in levels[1:]:
    ch[n] = (med_change(T[n - 1], T[n], en), med_change(T[n - 1], T[n], ep))
    print("--refine %d against %d: median relative change, endocardial columns %.3f, epicardial %.3f" % (n, n - 1, ch[n][0], ch[n][1]))
check(ch[1][0] > 0.2, "the unrefined endocardial columns are far from converged (%.3f from --refine 1)" % ch[1][0])
if 2 in ch:
    check(ch[2][0] < ch[1][0] / 2 and ch[2][1] < ch[1][1] / 2,
          "converging: --refine 2 moves the endocardial columns by %.3f < %.3f / 2, the epicardial by %.3f < %.3f / 2"
          % (ch[2][0], ch[1][0], ch[2][1], ch[1][1]))
if os.path.exists("s1/transfer.txt"):
    S = load("s1/transfer.txt")
    d = max(abs(x - y) for r, s in zip(T[1], S) for x, y in zip(r, s)); m = max(abs(x) for r in T[1] for x in r)
    check(len(S) == 300 and d < 1e-9 * m, "--refine 1 --scalapack: the serial matrix within %.1e (relative)" % (d / m))
sys.exit(0 if good else 1)
PYEOF

refused "--refine -1" "--refine must be" bem v --transfer --refine -1 -o bad
refused "--refine 99" "at most 4" bem v --transfer --refine 99 -o bad
grep -q "GB" err.txt || bad "--refine 99: the memory not named: $(cat err.txt)"
refused "--refine without --transfer" "goes with --transfer" bem v --dipoles /dev/null --refine 1 -o bad
THORAX_MAX_MEMORY=1e8 refused "--refine 2 over THORAX_MAX_MEMORY=1e8" "the limit" bem v --transfer --refine 2 -o bad

[ $fails -eq 0 ] || { echo "$fails failed"; exit 1; }
echo "all passed"
