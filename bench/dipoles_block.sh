#!/usr/bin/env bash
# Blocked dipole solves (issue 15): thorax forward --dipoles on the medium phantom (heart meshed,
# every region conducting) with a moment time series of 300 frames, solved frame by frame
# (-thorax_block_size 1: the same Cholesky factorization, one triangular solve pair per
# right-hand side, the old path) and blocked (the default: dense blocks of right-hand sides, one
# MatMatSolve each), in the same run, with the largest difference between the two answers
# relative to the largest potential. Two layouts:
#   120 dipoles x 300 frames: 300 <= 3 n, a right-hand side per frame (300 solves);
#    20 dipoles x 300 frames: 300 > 3 n, a right-hand side per dipole and axis (60 solves),
#                             combined per frame.
# The dipoles: seeded random positions within 15 mm of the heart surface's centroid, moments a
# rotating, swelling vector per dipole (no physiology intended). Prints figures; never fails on time.
set -euo pipefail
cd "$(dirname "$0")/.."
THORAX=${THORAX:-$PWD/build/bin/thorax}
PY=${PY:-/usr/bin/python3}
[ -x "$THORAX" ] || { echo "build first"; exit 1; }
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')"
"$THORAX" phantom --resolution medium --seed 1 -o "$W/c.txt" -q
"$THORAX" surfaces "$W/c.txt" -o "$W/m" -q
"$THORAX" mesh "$W/m" -q
nt=$($PY -c "import json; v=json.load(open('$W/m/model.json'))['volume']; print(v['n_tets'], 'tetrahedra,', v['n_nodes'], 'nodes')")
echo "medium phantom, heart meshed: $nt"
for nd in 120 20; do
    $PY - "$W/m" "$nd" 300 > "$W/d$nd.txt" <<'PY'
import sys, json, numpy as np
m, n, F = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
j = json.load(open(m + '/model.json'))
heart = [s for s in j['surfaces'] if s.get('role') == 'heart'][0]
c = np.loadtxt(m + '/' + heart['name'] + '.pts').mean(0)
rng = np.random.default_rng(15)
u = rng.normal(size=(n, 3)); u /= np.linalg.norm(u, axis=1)[:, None]
P = c + u * 15 * rng.random(n)[:, None] ** (1 / 3)
print('thorax-dipoles 1'); print('dipoles', n)
for p in P: print('%.6f %.6f %.6f' % tuple(p))
print('frames', F, 'ms')
ph = rng.random(n) * 6.283
for f in range(F):
    a = 2 * np.pi * f / F
    s = np.sin(np.pi * f / F) ** 2
    q = np.stack([np.cos(a + ph), np.sin(a + ph), 0.3 * np.cos(2 * a + ph)], 1) * s * 1e-3
    print(f * 2, ' '.join('%.9g' % x for x in q.ravel()))
print('end')
PY
    for mode in frames blocked; do
        extra=()
        [ $mode = frames ] && extra=(-thorax_block_size 1)
        rm -rf "$W/s_$mode"
        /usr/bin/time -f "%e %M" -o "$W/t" "$THORAX" forward "$W/m" --dipoles "$W/d$nd.txt" -o "$W/s_$mode" -q "${extra[@]}"
        read -r wall rss < "$W/t"
        $PY - "$W/s_$mode/solution.json" "$nd dipoles x 300 frames, $mode" "$wall" "$rss" <<'PY'
import json, sys
j = json.load(open(sys.argv[1])); s = j['solver']
print("%-36s wall %6.2f s, peak %4d MB | %s+%s, block %d, assembly %.2f s, setup (factorization) %.2f s, solves %.3f s" %
      (sys.argv[2], float(sys.argv[3]), int(sys.argv[4]) // 1024, s['ksp'], s['pc'], s['block'], s['seconds_assembly'],
       s['seconds_setup'], s['seconds_solve']))
PY
    done
    $PY - "$W/s_frames/torso.raw" "$W/s_blocked/torso.raw" <<'PY'
import sys, struct, numpy as np
def rd(p):
    b = open(p, 'rb').read(); r, f = struct.unpack('<QQ', b[8:24])
    return np.frombuffer(b[200 + 8 * f: 200 + 8 * f + 8 * r * f], '<f8').reshape(f, r)
a, b = rd(sys.argv[1]), rd(sys.argv[2])
print("  torso %d nodes x %d frames: largest difference %.2e of the largest potential (%.3g mV); "
      "||frames - blocked|| / ||frames|| %.2e (all values)" %
      (a.shape[1], a.shape[0], np.abs(a - b).max() / np.abs(a).max(), np.abs(a).max(),
       np.linalg.norm(a - b) / np.linalg.norm(a)))
PY
done
