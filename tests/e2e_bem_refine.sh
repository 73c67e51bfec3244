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
sys.path.insert(0, os.path.join(os.environ["SRC"], "tests"))
from ecgsim_columns import read_heart, endocardial, load_rows, column_re, median
P, F = read_heart(sys.argv[1], sys.argv[2])
levels = [int(x) for x in sys.argv[3:]]
endo = endocardial(P, F)
def load(p): return load_rows(p, len(P))
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
    return median([column_re(A, B, j) for j in nodes])
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
