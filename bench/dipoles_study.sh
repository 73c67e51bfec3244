#!/usr/bin/env bash
# The dipole study (docs/validation.md, "Dipole sources"): OpenMEEG's three spheres (radii 0.87,
# 0.92, 1; conductivities 1, 0.0125, 1) scaled by 100 to mm (87, 92, 100 mm: thorax's mesher and
# its defaults are made for models in mm), meshed by thorax mesh at increasing resolution, the
# dipoles of HeadN.dip (positions x 100 mm, moments as written, read as mA·m) solved by thorax
# forward --dipoles, the potentials at Head3's 128 electrodes (x 100 mm, projected onto the scalp
# by --rows) compared with OpenMEEG's analytic values x 100 (potential ~ q / (sigma R^2): R = 0.1 m
# makes mV = 100 x the dimensionless value). RDM and |1 - MAG| as OpenMEEG computes them (each
# column's mean removed; tests/dipole_compare.py). Figures only, no pass/fail.
#   meshes: OpenMEEG's own Head1-3 surfaces (42, 162, 642 nodes a sphere) with thorax mesh's default
#   grid; then icospheres of levels LEVELS (default 3 4 5: 642, 2,562, 10,242 nodes) with the grid
#   60 / 2^level mm (as thorax verify's spheres).
# METHOD=venant (default) or partial: thorax forward --dipole-method.
set -euo pipefail
SRC=$(cd "$(dirname "$0")/.." && pwd)
T=${THORAX:-$SRC/build/bin/thorax}
PY=/usr/bin/python3
DATA=${THORAX_DATA:-$SRC/../shared/data}/openmeeg-spheres
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
cd "$W"
METHOD=${METHOD:-venant}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
awk '{printf "%.10g %.10g %.10g %s %s %s\n", $1*100, $2*100, $3*100, $4, $5, $6}' "$DATA/data/Head3/Head3.dip" > d.dip
awk '{printf "%.10g %.10g %.10g\n", $(NF-2)*100, $(NF-1)*100, $NF*100}' "$DATA/data/Head3/Head3.patches" > el.txt
REF=$DATA/tests/analytic/eeg_head3_analytic.txt

run() { # NAME MODEL [mesh options]
    local name=$1 model=$2; shift 2
    local t0=$(date +%s.%N)
    "$T" mesh "$model" -o "v_$name" -q --region mean_thorax=scalp:1 --region skull:0.0125 --region brain:1 "$@"
    local t1=$(date +%s.%N)
    "$T" forward "v_$name" --dipoles d.dip --dipole-method "$METHOD" --rows el.txt -o "s_$name" --format text -q
    local t2=$(date +%s.%N)
    $PY "$SRC/tests/dipole_compare.py" "s_$name/electrodes.txt" "$REF" 100 1-5 > "cmp_$name.txt"
    $PY - "$name" "v_$name" "cmp_$name.txt" "$(echo "$t1 - $t0" | bc)" "$(echo "$t2 - $t1" | bc)" <<'PYEOF'
import sys, numpy as np
name, vdir, cmp, tm, ts = sys.argv[1:6]
P = np.loadtxt(vdir + "/volume.pts"); Tt = np.loadtxt(vdir + "/volume.tet", dtype=int)
# mean edge of the tetrahedra (mm)
x = P[Tt[:, :4] - 1]
e = [np.linalg.norm(x[:, a] - x[:, b], axis=1) for a, b in ((0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3))]
h = np.mean(e)
C = np.loadtxt(cmp)
fmt = lambda x: "%.3f" % x if x >= 0.01 else "%.2g" % x  # two significant digits below 0.01
print("| %s | %d | %d | %.2f | %s | %s | %.1f / %.1f |" % (name, len(P), len(Tt), h,
      " ".join(fmt(r) for r in C[:, 1]), " ".join(fmt(m) for m in C[:, 2]), float(tm), float(ts)))
sys.stdout.flush()
PYEOF
}

echo "method: $METHOD"
echo "| mesh | nodes | tetrahedra | h (mm) | RDM, dipoles 1-5 | \|1 − MAG\|, dipoles 1-5 | s mesh / forward |"
echo "|---|---|---|---|---|---|---|"
for n in ${HEADS:-1 2 3}; do
    for s in scalp skull cortex; do
        $PY - "$DATA/data/Head$n/$s.$n.tri" "${s}_$n" <<'PYEOF'
import sys
L = open(sys.argv[1]).read().split("\n")
nv = int(L[0].split()[1]); nt = int(L[1 + nv].split()[1])
open(sys.argv[2] + ".pts", "w").write("".join(" ".join(l.split()[:3]) + "\n" for l in L[1:1 + nv]))
open(sys.argv[2] + ".fac", "w").write("".join(l.strip() + "\n" for l in L[2 + nv:2 + nv + nt]))
PYEOF
    done
    "$T" import -o "head$n" -q --scale 100 "scalp_$n.pts" --name scalp --role outer "skull_$n.pts" --name skull --role other \
        "cortex_$n.pts" --name brain --role other
    run "Head$n" "head$n"
done
for k in ${LEVELS:-3 4 5}; do
    $PY "$SRC/bench/icosphere_shells.py" "$k" 100 scalp 92 skull 87 cortex
    "$T" import -o "ico$k" -q scalp.pts --name scalp --role outer skull.pts --name skull --role other cortex.pts --name brain --role other
    run "ico$k" "ico$k" --grid "$(echo "60 / 2^$k" | bc -l)"
done
