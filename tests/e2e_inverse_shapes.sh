#!/usr/bin/env bash
# thorax inverse's λ rules on every shape of problem (issue 24, item 1), against numpy computing
# them its own way: the influence matrix H = A (A^T A + λ² L^T L)^-1 A^T from a QR factorization of
# [A; λ R] (R^T R = L^T L, the operator assembled again here from the surface's triangles), GCV as
# ||(I - H) b||² / trace(I - H)² on a grid of λ, residuals and the L-curve's curvature and CRESO's
# function by finite differences; nothing of thorax's standard form or SVD filter formulas.
#  - shapes: a closed 162-node surface (an icosphere) with smooth matrices of 100 (wide), 162
#    (square) and 240 (tall) rows, and the issue's 191 x 337 ECGI set-up: the Forward/Inverse
#    toolkit's tank (torso_closed, 284 nodes) and closed heart (337 nodes), the 191 jacket leads,
#    a BEM transfer matrix made here (thorax import, mesh, bem), a known smooth heart source,
#    1% noise (tests/data/fwdinv/SOURCE.md);
#  - Tikhonov 0, 1, 2 (orders 1 and 2: the constants are the operator's null space), TSVD, TV;
#    GCV per frame and per series on every shape; the discrepancy principle per frame; the L-curve
#    and CRESO per series (their λ a local maximum of numpy's curvature / CRESO function);
#  - the 191 x 337 case: CC and RE of the GCV solutions against the source (the old GCV picked
#    λ ~ 1e-15: CC ~ 0, RE ~ 1e7);
#  - a λ per frame falls back to the series' λ on the frames whose data is below the noise
#    (||b̄||² < 2 (m - p0) σ², the frames numpy finds), flagged in inverse.json and warned;
#    --no-fallback keeps their own λ;
#  - a λ at the end of the search range is flagged per frame and warned (discrepancy with a noise
#    level no λ reaches);
#  - Greensite with a noise level keeps the temporal components above σ (√m + √F);
#  - a heart model whose node count is not the matrix's columns is refused for every method, the
#    model named; a rank-1 matrix and a one-row matrix give finite results and exit 0.
# Env: THORAX (built CLI), SRC (source dir), WORK (scratch dir, created here).
set -euo pipefail
: "${THORAX:?}" "${SRC:?}" "${WORK:?}"
D=$(cd "$SRC/tests/data/fwdinv" && pwd)
PY="env OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 /usr/bin/python3"
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK"
fail() { echo "e2e_inverse_shapes: FAIL: $*" >&2; exit 1; }
. "$SRC/tests/expect_rc.sh"
inv() { # OUT ARGS...: thorax inverse, exit 0 expected, stderr kept in OUT.err
    local out=$1; shift
    "$THORAX" inverse "$@" -o "$out" -q 2> "$out.err" || { cat "$out.err" >&2; fail "thorax inverse $* -o $out"; }
}

# ---- the problems -------------------------------------------------------------------------------
$PY - "$D" <<'PY'
import sys, numpy as np, scipy.io as sio
D = sys.argv[1]
# an icosphere (162 nodes, 320 triangles, counterclockwise seen from outside), radius 1
t = (1 + 5 ** 0.5) / 2
P = [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t], [0, -1, -t], [0, 1, -t],
     [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]]
P = [np.array(p, float) / np.linalg.norm(p) for p in P]
T = [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4], [11, 10, 2], [10, 7, 6],
     [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10],
     [8, 6, 7], [9, 8, 1]]
for _ in range(2):
    mid = {}
    def m(a, b):
        k = (min(a, b), max(a, b))
        if k not in mid:
            q = P[a] + P[b]; P.append(q / np.linalg.norm(q)); mid[k] = len(P) - 1
        return mid[k]
    T = [x for a, b, c in T for x in ([a, m(a, b), m(c, a)], [b, m(b, c), m(a, b)], [c, m(c, a), m(b, c)],
                                      [m(a, b), m(b, c), m(c, a)])]
P = np.array(P) * 30.0  # mm
T = np.array(T)
np.savetxt('ico.pts', P, fmt='%.9f'); np.savetxt('ico.fac', T + 1, fmt='%d')
n = len(P)
rng = np.random.default_rng(24)
u = P / 30.0
x_true = np.stack([u[:, 2] + 0.5 * u[:, 0] * u[:, 1] + 0.3, np.cos(2 * u[:, 0]) - 0.4 * u[:, 1],
                   0.7 * u[:, 1] * u[:, 2] - u[:, 0] + 0.1], 1)
for name, rows in (('wide', 100), ('square', n), ('tall', 240)):
    # leads on a sphere of radius 2.2 (Fibonacci points); A_ij = a smooth, decaying kernel
    k = np.arange(rows) + 0.5
    z = 1 - 2 * k / rows; r = np.sqrt(1 - z * z); ph = np.pi * (1 + 5 ** 0.5) * k
    L = 66.0 * np.stack([r * np.cos(ph), r * np.sin(ph), z], 1)
    A = 30.0 / np.linalg.norm(L[:, None, :] - P[None, :, :], axis=2) ** 2 / n
    B0 = A @ x_true
    B = B0 + 0.01 * np.sqrt((B0 ** 2).mean()) * rng.standard_normal(B0.shape)
    sio.savemat('A_%s.mat' % name, {'potvals': A}); sio.savemat('B_%s.mat' % name, {'potvals': B})
# the ECGI set-up's leads: the jacket nodes of the tank
tp = np.loadtxt(D + '/torso_closed.pts'); j = np.loadtxt(D + '/jacket.nodes', dtype=int) - 1
np.savetxt('jacket.pts', tp[j], fmt='%.6f')
# a rank-1 matrix and a one-row matrix (TSVD, Tikhonov: finite results)
sio.savemat('ones.mat', {'potvals': np.ones((20, 30))}); sio.savemat('ones_b.mat', {'potvals': rng.standard_normal((20, 4))})
sio.savemat('row.mat', {'potvals': np.ones((1, 30))}); sio.savemat('row_b.mat', {'potvals': rng.standard_normal((1, 4))})
PY
"$THORAX" import -o ico ico.pts --name heart --role heart -q
"$THORAX" import -o mfs "$D/torso_closed.pts" --name torso --role outer "$D/heart_closed.pts" --name heart --role heart -q
# PETSc's and MPI's caches live to the end of a run (as in e2e_bem and e2e_inverse): no leak check
# for mesh and bem (the sanitized build's ASAN_OPTIONS kept otherwise); inverse keeps it
NOLEAK="${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0"
ASAN_OPTIONS="$NOLEAK" "$THORAX" mesh mfs -q
ASAN_OPTIONS="$NOLEAK" "$THORAX" bem mfs --transfer --electrodes jacket.pts -o bem -q
"$THORAX" series info bem/transfer_electrodes.raw > info.txt
grep -Eq "^rows +191$" info.txt && grep -Eq "^frames +337$" info.txt || { cat info.txt; fail "the transfer matrix is not 191 x 337"; }
"$THORAX" series convert bem/transfer_electrodes.raw -o A_ecgi.mat -q
# the ECGI data: 40 frames, a rotating dipole-like layer and a bump (frames 1..30), then 10 frames of
# a heart signal far below the noise at the leads; σ = 1% of the data's RMS
SIGMA=$($PY - "$D" <<'PY'
import sys, numpy as np, scipy.io as sio
A = sio.loadmat('A_ecgi.mat')['potvals']
h = np.loadtxt(sys.argv[1] + '/heart_closed.pts'); c = h.mean(0); p = (h - c) / np.abs(h - c).max()
F = 40; rng = np.random.default_rng(1); X = np.zeros((337, F))
for f in range(F):
    a = np.sin(np.pi * (f + 1) / 31) if f < 30 else 0.004
    th = 2 * np.pi * f / 30; d = np.array([np.cos(th), np.sin(th), 0.5])
    X[:, f] = a * (10 * p @ d + 5 * np.exp(-((p - [0.3, -0.2, 0.1]) ** 2).sum(1) / 0.3))
B0 = A @ X; sigma = 0.01 * np.sqrt((B0 ** 2).mean())
sio.savemat('B_ecgi.mat', {'potvals': B0 + sigma * rng.standard_normal(B0.shape)}); sio.savemat('X_ecgi.mat', {'potvals': X})
print(repr(sigma))
PY
)

# ---- the runs -----------------------------------------------------------------------------------
for shape in wide square tall ecgi; do
    H=ico; [ $shape = ecgi ] && H=mfs
    for method in tikhonov0 tikhonov1 tikhonov2 tsvd; do
        for per in frame series; do
            inv g_${shape}_${method}_$per --transfer A_$shape.mat --data B_$shape.mat --heart $H --method $method \
                --lambda gcv --lambda-per $per --no-fallback
        done
    done
    [ $shape = ecgi ] && continue
    for method in tikhonov0 tikhonov2; do
        for rule in lcurve creso; do
            inv r_${shape}_${method}_$rule --transfer A_$shape.mat --data B_$shape.mat --heart $H --method $method \
                --lambda $rule --lambda-per series
        done
    done
done
# the discrepancy principle per frame, σ a little above the noise added (1.2% of the data's RMS)
for shape in wide square tall; do
    S=$($PY -c "
import scipy.io as s, numpy as np; A=s.loadmat('A_$shape.mat')['potvals']; B=s.loadmat('B_$shape.mat')['potvals']
print(repr(0.012 * np.sqrt((B ** 2).mean())))")
    for method in tikhonov0 tikhonov1 tikhonov2; do
        inv d_${shape}_$method --transfer A_$shape.mat --data B_$shape.mat --heart ico --method $method --lambda discrepancy \
            --noise "$S" --no-fallback
        echo "$S" > d_${shape}_$method.sigma
    done
done
# TV on the ECGI set-up: its λ is order 1's GCV λ (the old GCV stopped it: "not positive definite")
inv tv_ecgi --transfer A_ecgi.mat --data B_ecgi.mat --heart mfs --method tv --lambda gcv --truth X_ecgi.mat
# accuracy of the GCV solutions on the ECGI set-up
for method in tikhonov0 tikhonov1 tikhonov2; do
    inv a_$method --transfer A_ecgi.mat --data B_ecgi.mat --heart mfs --method $method --lambda gcv --lambda-per series \
        --truth X_ecgi.mat
done
# the fallback: the L-curve per frame with the noise given, with and without the fallback
inv fb_on --transfer A_ecgi.mat --data B_ecgi.mat --heart mfs --method tikhonov1 --lambda lcurve --noise "$SIGMA"
inv fb_off --transfer A_ecgi.mat --data B_ecgi.mat --heart mfs --method tikhonov1 --lambda lcurve --noise "$SIGMA" --no-fallback
inv fb_est --transfer A_ecgi.mat --data B_ecgi.mat --heart mfs --method tikhonov0 --lambda lcurve
"$THORAX" inverse --transfer A_ecgi.mat --data B_ecgi.mat --heart mfs --method tikhonov1 --lambda lcurve --noise "$SIGMA" \
    -o fb_warn > /dev/null 2> fb_warn.err
grep -q "warning: data below the noise level.*the series' λ used on 10 of 40 frames (31, 32" fb_warn.err ||
    { cat fb_warn.err; fail "no warning for the frames below the noise"; }
# Greensite with the noise level
inv gs --transfer A_ecgi.mat --data B_ecgi.mat --method greensite --lambda gcv --noise "$SIGMA"
# its per-frame λ: a number on every line (NaN before), the components' median as inverse.json's lambda_used
$PY - gs <<'PY' || fail "greensite's lambda.txt"
import sys, json, math
j = json.load(open(sys.argv[1] + '/inverse.json'))
L = [float(l.split()[2]) for l in open(sys.argv[1] + '/lambda.txt') if not l.startswith('#')]
c = sorted(j['component_lambda']); k = len(c); med = c[k // 2] if k % 2 else 0.5 * (c[k // 2 - 1] + c[k // 2])
assert len(L) == j['frames'] and all(math.isfinite(x) and x > 0 for x in L), L[:3]
assert all(abs(x - j['lambda_used']) <= 1e-8 * j['lambda_used'] for x in L) and abs(med - j['lambda_used']) <= 1e-12 * med, (L[0], j['lambda_used'], med)
PY
# a λ no rule reaches: the discrepancy's target above every residual
"$THORAX" inverse --transfer A_square.mat --data B_square.mat --lambda discrepancy --noise 1e6 --no-fallback -o hi > /dev/null 2> hi.err ||
    fail "discrepancy out of reach: $(cat hi.err)"
grep -q "warning: λ (discrepancy) at the large end of its search range.*on 3 of 3 frames" hi.err ||
    { cat hi.err; fail "no warning for λ at the end of the range"; }

# ---- numpy's check -------------------------------------------------------------------------------
$PY - "$D" "$SIGMA" <<'PY' || fail "numpy's check"
import sys, json, glob, numpy as np, scipy.io as sio
D, SIGMA = sys.argv[1], float(sys.argv[2])
bad = []
def check(ok, what):
    if not ok: bad.append(what); print('FAIL:', what)

def surface(pts, fac):
    return np.loadtxt(pts), np.loadtxt(fac, dtype=int) - 1
surf = {'ico': surface('ico.pts', 'ico.fac'), 'mfs': surface(D + '/heart_closed.pts', D + '/heart_closed.fac')}

def operator(P, T, order):
    """x^T K x = ∫ |∇x|² of the piecewise-linear x (K from each triangle's hat-function gradients);
    order 2: K D^-1 K, D the lumped mass (a third of each triangle's area to its corners)"""
    n = len(P); K = np.zeros((n, n)); mass = np.zeros(n)
    for t in T:
        a, b, c = P[t]
        nv = np.cross(b - a, c - a); area = 0.5 * np.linalg.norm(nv)
        E = np.array([c - b, a - c, b - a])                     # the edge opposite each corner
        G = np.cross(nv, E) / (nv @ nv)                         # ∇ of each corner's hat function
        K[np.ix_(t, t)] += area * G @ G.T
        mass[t] += area / 3
    assert np.abs(K.sum(1)).max() < 1e-9 * np.abs(K).max()     # constants: no gradient
    return K if order == 1 else K @ (K / mass[:, None])

cacheR = {}
def Rof(h, order, n):
    if order == 0: return np.eye(n)
    if (h, order) not in cacheR:
        w, V = np.linalg.eigh(operator(*surf[h], order))
        cacheR[(h, order)] = np.sqrt(np.clip(w, 0, None))[:, None] * V.T   # R^T R = the operator
    return cacheR[(h, order)]

def fit(A, R, B, lam):
    """the Tikhonov solutions of every column of B at λ, from the QR of [A; λ R]: A x = Q1 Q1^T b,
    trace(I - H) = m - ||Q1||²"""
    m = A.shape[0]
    Q, Rq = np.linalg.qr(np.vstack([A, lam * R]))
    Q1 = Q[:m]; C = Q1.T @ B
    X = np.linalg.solve(Rq, C)
    return B - Q1 @ C, m - (Q1 * Q1).sum(), X

def load(d):
    return json.load(open(d + '/inverse.json'))

order_of = {'tikhonov0': 0, 'tikhonov1': 1, 'tikhonov2': 2, 'tv': 1}
mats = {}
def mat(shape):
    if shape not in mats:
        mats[shape] = (sio.loadmat('A_%s.mat' % shape)['potvals'], sio.loadmat('B_%s.mat' % shape)['potvals'])
    return mats[shape]

# GCV: thorax's λ against numpy's G(λ) = ||(I - H) b||² / trace(I - H)²
for d in sorted(glob.glob('g_*_*_*')):
    if d.endswith('.err'): continue
    _, shape, method, per = d.split('_')
    A, B = mat(shape); m, n = A.shape; F = B.shape[1]
    j = load(d); lam = [f['lambda'] for f in j['per_frame']]
    h = 'mfs' if shape == 'ecgi' else 'ico'
    if method == 'tsvd':
        U, s, Vt = np.linalg.svd(A, full_matrices=False)
        kmax = int((s > s[0] * max(m, n) * np.finfo(float).eps).sum())
        cols = range(F) if per == 'frame' else [None]
        for f in cols:
            b = B if f is None else B[:, [f]]
            g = []
            for k in range(1, min(kmax, m - 1) + 1):
                r = b - U[:, :k] @ (U[:, :k].T @ b)
                g.append((r ** 2).sum() / (m - k) ** 2)
            kk = int(np.argmin(g)) + 1
            got = j['per_frame'][0 if f is None else f]['kept']
            check(got == kk, '%s frame %s: tsvd GCV keeps %d, numpy %d' % (d, f, got, kk))
        continue
    R = Rof(h, order_of[method], n)
    sA = np.linalg.norm(A, 2) / np.linalg.norm(R, 2)
    grid = sA * np.logspace(-10, 2, 40)
    G = []
    for l in grid:
        Rs, tr, _ = fit(A, R, B, l)
        rho2 = (Rs ** 2).sum(0)
        G.append(np.append(rho2, rho2.sum()) / tr ** 2 if tr > 1e-3 else np.full(F + 1, np.inf))
    G = np.array(G)
    # every frame of the small problems; 10 of the ECGI set-up's 40 (their QRs are the cost here)
    frames = range(F) if F <= 8 else list(range(0, F, 4)) + [F - 1]
    for f in (frames if per == 'frame' else [F]):
        lt = lam[f] if f < F else lam[0]
        Rs, tr, _ = fit(A, R, B, lt)
        rho2 = (Rs ** 2).sum(0)
        gt = (rho2[f] if f < F else rho2.sum()) / tr ** 2
        i = int(np.argmin(G[:, f]))
        # thorax's λ as good as numpy's best grid point (GCV may have two nearly equal minima), where
        # numpy's trace has its digits (the old λ ~ 1e-15 of m < n had trace(I - H) ~ 0)
        ok = tr > 1e-3 and gt <= G[i, f] * (1 + 1e-6)
        check(ok, '%s frame %d: thorax λ %.4g (G %.6g), numpy grid minimum λ %.4g (G %.6g)' % (d, f + 1, lt, gt, grid[i], G[i, f]))
    if shape == 'ecgi' and per == 'series':
        print('%s: GCV λ %.4g (numpy grid minimum %.4g)' % (d, lam[0], grid[int(np.argmin(G[:, F]))]))

# the discrepancy principle: numpy's residual at thorax's λ is √m σ in every frame
for d in sorted(glob.glob('d_*_*')):
    if d.endswith('.err') or d.endswith('.sigma'): continue
    _, shape, method = d.split('_')
    A, B = mat(shape); m, n = A.shape; sigma = float(open(d + '.sigma').read())
    j = load(d)
    R = Rof('ico', order_of[method], n)
    for f, e in enumerate(j['per_frame']):
        Rs, _, _ = fit(A, R, B[:, [f]], e['lambda'])
        rn = np.linalg.norm(Rs)
        check(abs(rn / (np.sqrt(m) * sigma) - 1) < 1e-6 and e['flags'] == [],
              '%s frame %d: residual %.9g at λ %.6g, target %.9g, flags %s' % (d, f + 1, rn, e['lambda'], np.sqrt(m) * sigma, e['flags']))

# the L-curve and CRESO per series: thorax's λ a local maximum of numpy's curvature / CRESO function
def norms(A, R, B, lam):
    Rs, _, X = fit(A, R, B, lam)
    return (Rs ** 2).sum(), ((R @ X) ** 2).sum()
def kappa(A, R, B, lg, h=2e-3):
    p = [norms(A, R, B, np.exp(lg + k * h)) for k in (-1, 0, 1)]
    x = np.log([q[0] for q in p]) / 2; y = np.log([q[1] for q in p]) / 2
    dx, dy = (x[2] - x[0]) / (2 * h), (y[2] - y[0]) / (2 * h)
    ddx, ddy = (x[2] - 2 * x[1] + x[0]) / h ** 2, (y[2] - 2 * y[1] + y[0]) / h ** 2
    return (dx * ddy - ddx * dy) / (dx * dx + dy * dy) ** 1.5
def creso(A, R, B, lg, h=1e-3):
    t = np.exp(2 * lg); e = lambda tt: norms(A, R, B, np.sqrt(tt))[1]
    return e(t) + 2 * t * (e(t * (1 + h)) - e(t * (1 - h))) / (2 * t * h)
for d in sorted(glob.glob('r_*_*_*')):
    if d.endswith('.err'): continue
    _, shape, method, rule = d.split('_')
    A, B = mat(shape); m, n = A.shape
    R = Rof('ico', order_of[method], n)
    lg = np.log(load(d)['per_frame'][0]['lambda'])
    fn = kappa if rule == 'lcurve' else creso
    v = [fn(A, R, B, lg + k * 0.05) for k in (-1, 0, 1)]
    check(v[1] >= v[0] and v[1] >= v[2] and (rule == 'creso' or v[1] > 0),
          '%s: λ %.4g is not a local maximum of numpy\'s %s: %s' % (d, np.exp(lg), rule, v))

# TV's λ is tikhonov1's GCV λ per frame, and it finished
tv = load('tv_ecgi'); t1 = load('g_ecgi_tikhonov1_frame')
check(all(abs(a['lambda'] / b['lambda'] - 1) < 1e-9 for a, b in zip(tv['per_frame'], t1['per_frame']) if 'below_noise' not in a['flags']),
      'TV\'s λ is not order 1\'s GCV λ')
print('ecgi tv: median CC %.4f, median RE %.4f' % (tv['truth']['cc_median'], tv['truth']['re_median']))
# accuracy: the GCV solutions on the 191 x 337 set-up find the source
for method, cc_min, re_max in (('tikhonov0', 0.9, 0.5), ('tikhonov1', 0.98, 0.15), ('tikhonov2', 0.98, 0.15)):
    t = load('a_' + method)['truth']
    print('ecgi %s, GCV per series: λ %.4g, median CC %.4f, median RE %.4f' % (method, load('a_' + method)['lambda_used'], t['cc_median'], t['re_median']))
    check(t['cc_median'] > cc_min and t['re_median'] < re_max, 'ecgi %s: CC %.4f, RE %.4f' % (method, t['cc_median'], t['re_median']))

# the fallback: the frames below the noise are those numpy finds; their λ is the series'
A, B = mat('ecgi'); m, n = A.shape
a1 = A @ np.ones(n); Bb = B - np.outer(a1, a1 @ B) / (a1 @ a1)       # b minus the null space's image
below = set(np.nonzero((Bb ** 2).sum(0) < 2 * (m - 1) * SIGMA ** 2)[0])
check(below == set(range(30, 40)), 'numpy\'s frames below the noise: %s' % sorted(below))
on, off = load('fb_on'), load('fb_off')
check(on['fallback']['on'] and on['fallback']['noise_from'] == 'noise' and abs(on['fallback']['noise_sigma'] / SIGMA - 1) < 1e-12, 'fallback noise')
for f in range(B.shape[1]):
    eo, ef = on['per_frame'][f], off['per_frame'][f]
    fl = 'below_noise' in eo['flags']
    check(fl == (f in below) and fl == ('below_noise' in ef['flags']), 'frame %d: below_noise flag %s' % (f + 1, fl))
    if fl:
        check(eo['lambda'] == on['fallback']['series_lambda'], 'frame %d: λ %.4g is not the series\' %.4g' % (f + 1, eo['lambda'], on['fallback']['series_lambda']))
    else:
        check(eo['lambda'] == ef['lambda'], 'frame %d: the fallback changed a frame above the noise' % (f + 1))
check(on['fallback']['frames'] == len(below) and off['fallback']['frames'] == 0, 'fallback counts')
check(any(on['per_frame'][f]['lambda'] != off['per_frame'][f]['lambda'] for f in below), '--no-fallback changed nothing')
# σ estimated by the series' GCV fit when not given: within 10% of the noise added
est = load('fb_est')['fallback']
check(est['noise_from'] == 'gcv' and abs(est['noise_sigma'] / SIGMA - 1) < 0.1, 'GCV noise estimate %.4g, true %.4g' % (est['noise_sigma'], SIGMA))

# Greensite keeps the temporal components above σ (√m + √F) (not σ √(m + F), which keeps more here)
s = np.linalg.svd(B, compute_uv=False); F = B.shape[1]
want = int((s > SIGMA * (np.sqrt(m) + np.sqrt(F))).sum()); other = int((s > SIGMA * np.sqrt(m + F)).sum())
got = len(load('gs')['component_lambda'])
check(want != other, 'the two cut-offs keep the same number here (%d)' % want)
check(got == want, 'greensite keeps %d components, σ(√m+√F) gives %d' % (got, want))

# a λ at the end of the range: flagged on every frame
hi = load('hi')
check(all('range_high' in e['flags'] for e in hi['per_frame']) and hi['lambda_flag_frames']['range_high'] == 3, 'range_high flags: %s' % [e['flags'] for e in hi['per_frame']])
if bad: sys.exit(1)
print('numpy agrees on %d GCV runs' % len([d for d in glob.glob('g_*') if not d.endswith('.err')]))
PY

# ---- sizes that disagree, rank-deficient matrices --------------------------------------------
for method in tikhonov0 tikhonov1 tsvd greensite tv; do
    expect_rc 1 "$THORAX" inverse --transfer A_ecgi.mat --data B_ecgi.mat --heart ico --method $method -o bad_$method
    grep -q "A_ecgi.mat has 337 columns (heart nodes) but the heart surface \"heart\" of ico has 162 nodes" err.txt ||
        fail "$method with a heart of another size: $(cat err.txt)"
    [ ! -e bad_$method ] || fail "bad_$method written"
done
expect_rc 1 "$THORAX" inverse --transfer A_ecgi.mat --data B_square.mat -o bad_rows
grep -q "A_ecgi.mat has 191 rows.*B_square.mat has 162 rows" err.txt || fail "rows: $(cat err.txt)"
for m in tsvd tikhonov0; do
    for r in lcurve gcv; do
        for p in ones row; do
            expect_rc 0 "$THORAX" inverse --transfer $p.mat --data ${p}_b.mat --method $m --lambda $r -o rk_${m}_${r}_$p
            ! grep -qi "nan" rk_${m}_${r}_$p/lambda.txt rk_${m}_${r}_$p/inverse.json || fail "NaN written: $m $r $p"
            if grep -q "\.tmp" err.txt; then fail "a message names a temporary file: $(cat err.txt)"; fi
        done
    done
done
echo "e2e_inverse_shapes: all passed"
