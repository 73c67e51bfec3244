#!/usr/bin/env bash
# Benchmark of the boundary elements (thorax bem; docs/decisions.md, "Boundary elements"):
#   OpenMEEG's Head1/Head2/Head3 (3 shells of 42/162/642 vertices), dipoles 1-5 at the
#   electrodes: assembly and solve time (bem.json), wall time and peak memory (/usr/bin/time -v),
#   RDM and MAG against the analytic potentials, beside OpenMEEG's published figures;
#   the medium phantom's heart -> torso transfer matrix by BEM and by FEM (thorax forward
#   --transfer-out), time, memory and the correlation of every column (median, 10th percentile,
#   minimum).
# Prints figures; never fails on time. PHANTOM=0 leaves the phantom out (it takes minutes).
set -euo pipefail
cd "$(dirname "$0")/.."
THORAX=${THORAX:-$PWD/build/bin/thorax}
PY=/usr/bin/python3
[ -x "$THORAX" ] || { echo "build first (make)"; exit 1; }
D=${OPENMEEG_SPHERES:-../shared/data/openmeeg-spheres}
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')"
peak() { awk -F': ' '/Maximum resident/ { printf "%.0f MB", $2 / 1024 } /User time/ { u = $2 } /System time/ { s = $2 }
                    /Elapsed/ { w = $2 } END { printf ", wall %s, CPU %.2f s", w, u + s }' "$1"; }
echo
echo "OpenMEEG spheres (conductivities 1 / 0.0125 / 1), dipoles 1-5:"
echo "  OpenMEEG (symmetric BEM, Head3 on this class of machine): 25 s to assemble and invert;"
echo "  RDM 0.002-0.019, |1-MAG| 0.006-0.021; test thresholds 0.13 / 0.10 / 0.03 (Head1/2/3)"
echo "  load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
# the symmetric method (the default) on Head1-3, then Head3 by collocation
for run in 1 2 3 3c; do
    h=${run%[cs]}
    H="$D/data/Head$h"
    extra=()
    case $run in
        *c) extra=(--method collocation) ;;
    esac
    /usr/bin/time -v "$THORAX" bem "$H/Head$h.geom" --dipoles "$H/Head$h.dip" --electrodes "$H/Head$h.patches" \
        -o "$W/h$run" --format text -q "${extra[@]}" 2> "$W/h$run.time"
    case $run in
        *c) printf 'Head%d, collocation: ' "$h" ;;
        *) printf 'Head%d: ' "$h" ;;
    esac
    $PY - "$W/h$run" "$D/tests/analytic/eeg_head${h}_analytic.txt" <<'EOF'
import json, sys
import numpy as np
d, ref = sys.argv[1], sys.argv[2]
j = json.load(open(d + "/bem.json"))
L = open(d + "/electrodes.txt").read().split("\n")
i = [k for k, l in enumerate(L) if l.startswith("dt")][0]
v = np.loadtxt([l for l in L[i + 1:] if l.strip() and l != "end"])
a = np.loadtxt(ref)
out = []
for k in range(5):
    x = v[:, k] - v[:, k].mean(); y = a[:, k] - a[:, k].mean()
    out.append((np.linalg.norm(x / np.linalg.norm(x) - y / np.linalg.norm(y)), np.linalg.norm(x) / np.linalg.norm(y)))
print("%d unknowns, assembly %.2f s, solve %.2f s (%.0f MB of matrices);" % (j["unknowns"], j["seconds_assembly"], j["seconds_solve"], j["matrix_bytes"] / 2**20))
print("        RDM " + " ".join("%.3f" % r for r, m in out) + ";  MAG " + " ".join("%.3f" % m for r, m in out))
EOF
    echo "        peak $(peak "$W/h$run.time")"
done
echo "  load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
[ "${PHANTOM:-1}" = 0 ] && exit 0
echo
echo "medium phantom (muscle made isotropic, 0.16 S/m: the BEM needs one conductivity a compartment):"
"$THORAX" phantom --resolution medium --seed 1 -o "$W/c.txt" -q
"$THORAX" surfaces "$W/c.txt" -o "$W/m" -q
"$THORAX" mesh "$W/m" --no-heart -q
"$THORAX" sigma "$W/m" muscle=0.16 -q
/usr/bin/time -v "$THORAX" forward "$W/m" --transfer-out -o "$W/fem" --format text -q 2> "$W/fem.time"
/usr/bin/time -v "$THORAX" bem "$W/m" --transfer -o "$W/bem" --format text -q 2> "$W/bem.time"
echo "  FEM transfer: peak $(peak "$W/fem.time")"
echo "  BEM transfer: peak $(peak "$W/bem.time")"
$PY - "$W" <<'EOF'
import json, sys
import numpy as np
w = sys.argv[1]
def read(p):
    L = open(p).read().split("\n")
    i = [k for k, l in enumerate(L) if l.startswith("dt")][0]
    return np.loadtxt([l for l in L[i + 1:] if l.strip() and l != "end"])
F, B = read(w + "/fem/transfer.txt"), read(w + "/bem/transfer.txt")
j = json.load(open(w + "/bem/bem.json"))
print("  BEM: %d unknowns, assembly %.1f s, solve %.1f s" % (j["unknowns"], j["seconds_assembly"], j["seconds_solve"]))
cc = np.array([np.corrcoef(F[:, k], B[:, k])[0, 1] for k in range(F.shape[1])])
re = np.linalg.norm(F - B) / np.linalg.norm(F)
print("  %d x %d; correlation of the columns: median %.4f, 10th percentile %.4f, min %.4f; relative difference %.3f"
      % (F.shape[0], F.shape[1], np.median(cc), np.percentile(cc, 10), cc.min(), re))
EOF
