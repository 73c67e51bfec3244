#!/usr/bin/env bash
# thorax forward on 1, 2 and 3 MPI ranks gives the same answers (issue 28, items 3 and 5; docs/design/
# parallel.md, "The forward problem partitioned"): under mpirun the nodes are cut into boxes among the
# ranks and each rank assembles only the rows it owns.
# On the medium phantom meshed without the heart (tests/medium_phantom.sh), each case is solved by one
# process (no launcher: what a user runs) and under `mpirun -np 2` and `-np 3`, and every series it
# writes must agree with the one-process answer to 1e-10 of each frame's largest |value| (a transfer
# matrix: of each column's, a heart node's), max norm:
#   transfer   --transfer-out (the torso's rows, a solve per heart node): the default solver, Cholesky
#              (thorax's own CHOLMOD path on one rank, MUMPS on several)
#   transfer   --transfer-out --rows 12lead.txt (9 adjoint solves): MUMPS named on the command line, and
#              CG + GAMG at -ksp_rtol 1e-13
#   epicardial --epicardial (12 frames) --volume: the default solver (Cholesky as above: MUMPS on 2 and 3
#              ranks against CHOLMOD on one)
#   epicardial --epicardial (4 of those frames) --volume: CG + GAMG at -ksp_rtol 1e-13
# (MUMPS named on one rank against several for the epicardial problem too was measured, 4e-15; left out
# to keep the test near 35 s on two cores.)
# Not here, because they do not agree to 1e-10 and are not meant to: the default for fewer than 12
# right-hand sides, CG + GAMG at thorax's -ksp_rtol 1e-10 (2 and 3 ranks differ from one by 7e-10 of a
# frame's largest value on 4 frames, 1.9e-9 of a column on the 12-lead transfer: another partition,
# another preconditioner, an answer within the tolerance, not the same one).
# A transfer matrix applied (--epicardial S --transfer T, no --volume: no solve) on 2 ranks gives the
# 12-frame solve: that path started no MPI, so every process took itself for rank 0 and wrote DIR, and all
# but one stopped with "DIR was changed by another command" (found while writing this test; fixed).
# Real properties asserted besides: each run's solution.json names its rank count and solver; the
# potentials are not trivially small; a transfer matrix's rows sum to 1 (a constant heart gives that
# constant on the torso); the iterative answers agree with the direct ones to 1e-10 on one rank.
# Skipped (exit 77) without mpirun. Writes only in a mktemp -d directory, removed at exit.
# Env: THORAX (built CLI); THORAX_PHANTOM_MODELS (optional: the fixture's models, tests/medium_phantom.sh).
set -euo pipefail
: "${THORAX:?}"
HERE=$(cd "$(dirname "$0")" && pwd)
. "$HERE/ranks_test.sh"
ranks_test e2e_forward_ranks
# the direct path keeps its ordering in a cache (docs/design/parallel.md): ctest names one, else ours
export THORAX_CACHE_DIR="${THORAX_CACHE_DIR:-$TMP/cache}"

# the medium phantom meshed without the heart (tests/medium_phantom.sh), its electrodes and a beat
. "$HERE/medium_phantom.sh"
medium_phantom || fail "the medium phantom"
"$THORAX" electrodes model -q
"$THORAX" beat model -o beat.raw --frames 240 -q
# frames on the P wave, the QRS and the T wave (none of them all zero: the comparison is per frame)
"$PY" - <<'EOF'
import numpy as np
b = open('beat.raw', 'rb').read()
r, f = (int(x) for x in np.frombuffer(b[8:24], dtype='<u8'))
t = np.frombuffer(b[200:200 + 8 * f], dtype='<f8')
v = np.frombuffer(b[200 + 8 * f:], dtype='<f8').reshape(f, r)
for name, k in (('e4.raw', [40, 170, 190, 230]), ('e12.raw', [30, 40, 50, 60, 70, 80, 170, 180, 190, 200, 210, 230])):
    assert all(abs(v[i]).max() > 0.05 for i in k), [abs(v[i]).max() for i in k]
    h = bytearray(b[:200]); h[16:24] = np.array([len(k)], dtype='<u8').tobytes()
    open(name, 'wb').write(bytes(h) + t[k].tobytes() + v[k].tobytes())
EOF

MUMPS=(-ksp_type preonly -pc_type cholesky -pc_factor_mat_solver_type mumps)
GAMG=(-ksp_type cg -pc_type gamg -ksp_rtol 1e-13)
# solve NAME ARGS...: the case on 1 rank (NAME_1), 2 (NAME_2) and 3 ranks (NAME_3)
solve() {
    local name=$1 n t0
    shift
    for n in 1 2 3; do
        t0=$(date +%s.%N)
        if [ $n -eq 1 ]; then
            "$THORAX" forward model "$@" -o ${name}_1 -q > ${name}_1.log 2>&1 || { cat ${name}_1.log; fail "$name on 1 rank"; }
        else
            "${MPIRUN[@]}" -np $n "$THORAX" forward model "$@" -o ${name}_$n -q > ${name}_$n.log 2>&1 ||
                { cat ${name}_$n.log; fail "$name on $n ranks"; }
        fi
        printf '%s on %d rank(s): %.1f s\n' "$name" $n "$(echo "$(date +%s.%N) - $t0" | bc)"
    done
}
solve tr_default --transfer-out
solve tr12_mumps --transfer-out --rows model/electrodes/12lead.txt "${MUMPS[@]}"
solve tr12_gamg --transfer-out --rows model/electrodes/12lead.txt "${GAMG[@]}"
solve ep12_default --epicardial e12.raw --volume
solve ep4_gamg --epicardial e4.raw --volume "${GAMG[@]}"
"${MPIRUN[@]}" -np 2 "$THORAX" forward model --epicardial e12.raw --transfer tr_default_1/transfer.raw -o applied_2 \
    > applied_2.log 2>&1 || { cat applied_2.log; fail "a transfer matrix applied on 2 ranks"; }

"$PY" - <<'EOF' || fail "the answers (above)"
import json, numpy as np
def raw(p):
    b = open(p, 'rb').read()
    assert b[:8] == b'THXSER01', p
    r, f = (int(x) for x in np.frombuffer(b[8:24], dtype='<u8'))
    assert len(b) == 200 + 8 * f * (r + 1), p
    return np.frombuffer(b[200 + 8 * f:], dtype='<f8').reshape(f, r)   # frames (columns) x rows
def rel(a, b):
    """max over frames of max|a - b| / max|a| in that frame"""
    assert a.shape == b.shape, (a.shape, b.shape)
    s = np.abs(a).max(axis=1)
    assert (s > 0).all(), 'a frame of zeros'
    return (np.abs(a - b).max(axis=1) / s).max()
TOL = 1e-10
# case: (files, solver as solution.json names it on 1 rank and on several)
cases = {
    'tr_default':   (['transfer.raw'], ('preonly', 'cholesky'), ('preonly', 'cholesky')),
    'tr12_mumps':   (['transfer_electrodes.raw'], ('preonly', 'cholesky'), ('preonly', 'cholesky')),
    'tr12_gamg':    (['transfer_electrodes.raw'], ('cg', 'gamg'), ('cg', 'gamg')),
    'ep12_default': (['torso.raw', 'volume.raw'], ('preonly', 'cholesky'), ('preonly', 'cholesky')),
    'ep4_gamg':     (['torso.raw', 'volume.raw'], ('cg', 'gamg'), ('cg', 'gamg')),
}
bad = []
for case, (files, one, many) in cases.items():
    for n in (1, 2, 3):
        s = json.load(open('%s_%d/solution.json' % (case, n)))['solver']
        assert s['ranks'] == n, (case, n, s['ranks'])
        assert (s['ksp'], s['pc']) == (one if n == 1 else many), (case, n, s['ksp'], s['pc'])
        # the default on one rank is thorax's own CHOLMOD path; MUMPS named runs through PETSc
        assert ('factor' in s) == (n == 1 and case.endswith('_default')), (case, n, sorted(s))
    for f in files:
        a = raw('%s_1/%s' % (case, f))
        d = [rel(a, raw('%s_%d/%s' % (case, n, f))) for n in (2, 3)]
        ok = max(d) <= TOL
        print('%-13s %-24s %3d %-7s x %5d rows, largest %.3g: 2 ranks %.2e, 3 ranks %.2e  %s' %
              (case, f, a.shape[0], 'columns' if f.startswith('transfer') else 'frames', a.shape[1],
               np.abs(a).max(), d[0], d[1], 'ok' if ok else 'DIFFERS'))
        if not ok:
            bad.append('%s/%s: %.2e' % (case, f, max(d)))
assert not bad, 'differ from one rank by more than %g: %s' % (TOL, ', '.join(bad))
# real potentials: the beat's frames reach a few tenths of a mV on the torso (1.7 mV at most on the heart)
for case in ('ep12_default', 'ep4_gamg'):
    t = raw(case + '_1/torso.raw')
    assert 0.05 < np.abs(t).max() < 2, (case, np.abs(t).max())
# a transfer matrix: rows sum to 1 (a constant heart gives that constant everywhere)
for case, f in (('tr_default', 'transfer.raw'), ('tr12_mumps', 'transfer_electrodes.raw'),
                ('tr12_gamg', 'transfer_electrodes.raw')):
    for n in (1, 2, 3):
        T = raw('%s_%d/%s' % (case, n, f))
        assert abs(T.sum(axis=0) - 1).max() < 1e-8, (case, n, abs(T.sum(axis=0) - 1).max())
# the iterative answers at -ksp_rtol 1e-13 are the direct ones (one rank; e4.raw's frames are e12.raw's 2, 7, 9, 12)
x = [rel(raw('tr12_mumps_1/transfer_electrodes.raw'), raw('tr12_gamg_1/transfer_electrodes.raw'))]
for f in ('torso.raw', 'volume.raw'):
    x.append(rel(raw('ep12_default_1/' + f)[[1, 6, 8, 11]], raw('ep4_gamg_1/' + f)))
print('CG + GAMG (rtol 1e-13) against the direct solvers, one rank: transfer %.2e, torso %.2e, volume %.2e' % tuple(x))
assert max(x) <= TOL, x
# the full transfer matrix applied to the 12 frames is the 12-frame solve (both by the default solver)
T = raw('tr_default_1/transfer.raw').T                       # torso rows x heart nodes
E = raw('e12.raw').T                                          # heart nodes x frames
t = raw('ep12_default_1/torso.raw').T
assert np.abs(T @ E - t).max() <= TOL * np.abs(t).max(), np.abs(T @ E - t).max()
# the volume in parts (--volume under mpirun; docs/formats.md, "Partitioned volume potentials"): read by
# this program from the format's description, every active tetrahedron in exactly one part, each part's
# nodes' values those of volume.raw to the bit, the checksum right
import hashlib, struct
def part(p):
    b = open(p, 'rb').read()
    assert b[:8] == b'THXPART2' and hashlib.sha256(b[:-32]).digest() == b[-32:], p
    rank, ranks = struct.unpack_from('<II', b, 8)
    nn, nt, nf, ng, ngt = struct.unpack_from('<5Q', b, 16)
    o = 64 + 24 * (ranks - 1)
    node = np.frombuffer(b, '<i4', nn, o); o += 4 * nn
    o += 24 * nn
    tet = np.frombuffer(b, '<i4', 4 * nt, o).reshape(nt, 4); o += 16 * nt
    o += 4 * nt
    tid = np.frombuffer(b, '<i4', nt, o); o += 4 * nt
    own = np.frombuffer(b, '<i4', nt, o); o += 4 * nt
    val = np.frombuffer(b, '<f8', nf * nn, o).reshape(nf, nn); o += 8 * nf * nn
    assert o + 32 == len(b), p
    assert (np.diff(tid) > 0).all() and ((own >= 0) & (own < ranks)).all()
    return rank, ranks, node, tet[own == rank], val
vol_tets = None
for n in (2, 3):
    d = 'ep12_default_%d' % n
    assert json.load(open(d + '/solution.json'))['volume_parts']['ranks'] == n
    man = json.load(open(d + '/parts/parts.json'))
    assert man['format'] == 'thorax-parts' and len(man['files']) == n
    whole = raw(d + '/volume.raw')
    seen, same = set(), True
    for k, f in enumerate(man['files']):
        rank, ranks, node, tet, val = part(d + '/parts/' + f)
        assert (rank, ranks) == (k, n)
        same &= bool((val == whole[:, node]).all())
        g = [tuple(sorted(t)) for t in node[tet]]
        assert not seen.intersection(g), 'a tetrahedron in two parts'
        seen.update(g)
    assert same, 'a part holds other values than volume.raw'
    assert len(seen) == man['tetrahedra'], (len(seen), man['tetrahedra'])
    print('%d parts: %d tetrahedra, each in one part; every value that of volume.raw' % (n, len(seen)))
# and applied by thorax on 2 ranks (rank 0 writing alone)
a = rel(raw('ep12_default_1/torso.raw'), raw('applied_2/torso.raw'))
print('the transfer matrix applied on 2 ranks against the 12-frame solve: %.2e' % a)
assert a <= TOL, a
EOF
echo "e2e_forward_ranks: all checks passed"
