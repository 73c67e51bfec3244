#!/usr/bin/env bash
# The forward problem partitioned over MPI ranks at scale (issue 28, item 3): the high phantom's
# surfaces meshed at a finer grid (--grid 2.3 --layer-spacing 1.6: 11.9 M tetrahedra, 2.0 M nodes),
# then 4 frames of its beat solved with CG and BoomerAMG (-ksp_rtol 1e-12) on 1 rank and on 2 ranks:
# wall time, the phases forward -v reports, the peak memory of each process (the largest rank, and
# all ranks together), and the two answers compared. Direct solvers are left out at this size (the
# factor alone would be about 10 GB). Prints figures; never fails on time.
#   DATA=DIR   reuse DIR/m10 (the fine mesh) and DIR/beat4.raw (4 frames); else they are made in a
#              temporary directory (about 2 minutes and 2 GB; frames 40, 170, 190, 230 ms of the beat)
#   OPTS=...   other PETSc options (default: -ksp_type cg -pc_type hypre -ksp_rtol 1e-12)
set -euo pipefail
cd "$(dirname "$0")/.."
THORAX=${THORAX:-$PWD/build/bin/thorax}
[ -x "$THORAX" ] || { echo "build first (make)"; exit 1; }
command -v mpirun > /dev/null || { echo "mpirun missing (Debian package openmpi-bin)"; exit 1; }
MPI=(mpirun --oversubscribe)
[ "$(id -u)" = 0 ] && MPI+=(--allow-run-as-root)
OPTS=${OPTS:--ksp_type cg -pc_type hypre -ksp_rtol 1e-12}
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
PY=/usr/bin/python3
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), $(free -g | awk '/Mem/ {print $2}') GiB, load $(cut -d' ' -f1-3 /proc/loadavg)"
if [ -n "${DATA:-}" ]; then
    M=$DATA/m10 B=$DATA/beat4.raw
else
    M=$W/m10 B=$W/beat4.raw
    "$THORAX" phantom --resolution high --seed 1 -o "$W/c.txt" -q
    "$THORAX" surfaces "$W/c.txt" -o "$W/m" -q 2> /dev/null
    /usr/bin/time -f "mesh: %e s, %M KB" "$THORAX" mesh "$W/m" -o "$M" --no-heart --grid 2.3 --layer-spacing 1.6 -q
    # four frames with activity (the P wave, the QRS upstroke and peak, the T wave) out of a beat
    "$THORAX" beat "$M" -o "$W/beat.raw" --frames 300 -q
    $PY - "$W/beat.raw" "$B" <<'PYEOF'
import sys, numpy as np
b = open(sys.argv[1], 'rb').read()
r, f = (int(x) for x in np.frombuffer(b[8:24], dtype='<u8'))
t = np.frombuffer(b[200:200 + 8 * f], dtype='<f8')
v = np.frombuffer(b[200 + 8 * f:], dtype='<f8').reshape(f, r)
k = [40, 170, 190, 230]
h = bytearray(b[:200]); h[16:24] = np.array([len(k)], dtype='<u8').tobytes()
open(sys.argv[2], 'wb').write(bytes(h) + t[k].tobytes() + v[k].tobytes())
PYEOF
fi
$PY - "$M" <<'PYEOF'
import json, sys
v = json.load(open(sys.argv[1] + '/model.json'))['volume']
print('mesh: %d tetrahedra, %d nodes' % (v['n_tets'], v['n_nodes']))
PYEOF
# run N: forward on N ranks, its log and every process's peak memory
run() {
    local n=$1
    if [ "$n" = 1 ]; then
        /usr/bin/time -f "%e %M" -o "$W/time.$n" "$THORAX" forward "$M" --epicardial "$B" -o "$W/s$n" -v $OPTS > "$W/log.$n" 2>&1
    else
        # each rank's own peak: time(1) around every rank
        /usr/bin/time -f "%e" -o "$W/time.$n" "${MPI[@]}" -np "$n" sh -c \
            "exec /usr/bin/time -f '%M' -o $W/peak.$n.\$OMPI_COMM_WORLD_RANK $THORAX forward $M --epicardial $B -o $W/s$n -v $OPTS" \
            > "$W/log.$n" 2>&1
    fi
    local wall peak
    wall=$(awk '{print $1}' "$W/time.$n")
    if [ "$n" = 1 ]; then peak=$(awk '{print $2}' "$W/time.$n"); echo "1 rank: $wall s, peak $((peak / 1024)) MiB"
    else
        local all=0 top=0 p
        for f in "$W"/peak.$n.*; do p=$(tail -1 "$f"); all=$((all + p)); [ "$p" -gt "$top" ] && top=$p; done
        echo "$n ranks: $wall s, peak $((top / 1024)) MiB on the largest rank, $((all / 1024)) MiB on all"
    fi
    grep -E 'assembl|setup|solve|iteration|read|check' "$W/log.$n" | sed 's/^/    /' | head -12
}
run 1
run 2
$PY - "$W/s1/torso.raw" "$W/s2/torso.raw" <<'PYEOF'
import sys, numpy as np
def raw(p):
    b = open(p, 'rb').read(); r, f = (int(x) for x in np.frombuffer(b[8:24], '<u8'))
    return np.frombuffer(b[200 + 8 * f:], '<f8').reshape(f, r)
a, b = raw(sys.argv[1]), raw(sys.argv[2])
s = abs(a).max(axis=1)
k = s > 0   # (a frame of zeros has no relative difference)
print('1 rank against 2: %.2e of each frame\'s largest value (torso)' % (abs(a - b).max(axis=1)[k] / s[k]).max())
PYEOF
