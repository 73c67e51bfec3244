import sys, numpy as np
from scipy.optimize import minimize_scalar, brentq
A = np.loadtxt(sys.argv[1]); b = np.loadtxt(sys.argv[2]); x_true = np.loadtxt(sys.argv[3]); sigma = float(sys.argv[4])
m, n = A.shape
AtA = A.T @ A; Atb = A.T @ b; I = np.eye(n)
def x_of(l): return np.linalg.lstsq(np.vstack([A, l * I]), np.concatenate([b, np.zeros(n)]), rcond=None)[0]
def res(l): return np.linalg.norm(A @ x_of(l) - b)
def gcv(lg):
    l = np.exp(lg); H = A @ np.linalg.solve(AtA + l * l * I, A.T)
    return res(l) ** 2 / (m - np.trace(H)) ** 2
def logs(lg): l = np.exp(lg); x = x_of(l); return np.log(np.linalg.norm(A @ x - b)), np.log(np.linalg.norm(x))
def kappa(lg, h=1e-3):
    p = [logs(lg + k * h) for k in (-2, -1, 0, 1, 2)]
    xs = np.array([q[0] for q in p]); ys = np.array([q[1] for q in p])
    dx = (xs[3] - xs[1]) / (2 * h); dy = (ys[3] - ys[1]) / (2 * h)
    ddx = (xs[3] - 2 * xs[2] + xs[1]) / h ** 2; ddy = (ys[3] - 2 * ys[2] + ys[1]) / h ** 2
    return (dx * ddy - ddx * dy) / (dx * dx + dy * dy) ** 1.5
def creso(lg, h=1e-4):
    t = np.exp(2 * lg); e = lambda tt: np.linalg.norm(x_of(np.sqrt(tt))) ** 2
    return e(t) + 2 * t * (e(t * (1 + h)) - e(t * (1 - h))) / (2 * t * h)
s = np.linalg.svd(A, compute_uv=False)
lo, hi = np.log(max(s[-1], s[0] * 16 * np.finfo(float).eps)), np.log(s[0])
grid = np.linspace(lo, hi, 400)
def refine(fn, sign, pick):
    v = np.nan_to_num(np.array([sign * fn(g) for g in grid]), nan=-np.inf); i = pick(v)
    r = minimize_scalar(lambda g: -sign * fn(g), bounds=(grid[max(i - 1, 0)], grid[min(i + 1, len(grid) - 1)]), method='bounded', options={'xatol': 1e-9})
    return np.exp(r.x)
def first_max_from_top(v):
    for i in range(len(v) - 2, 0, -1):
        if v[i] > v[i + 1] and v[i] >= v[i - 1]: return i
    return int(np.argmax(v))
out = {}
out['lcurve'] = refine(kappa, 1, lambda v: int(np.argmax(v)))
out['gcv'] = refine(lambda g: gcv(g), -1, lambda v: int(np.argmax(v)))
out['creso'] = refine(creso, 1, first_max_from_top)
out['discrepancy'] = np.exp(brentq(lambda g: res(np.exp(g)) - np.sqrt(m) * sigma, lo, hi, xtol=1e-12))
for k in ('lcurve', 'creso', 'gcv', 'discrepancy'):
    x = x_of(out[k]); print(k, repr(out[k]), repr(np.linalg.norm(x - x_true) / np.linalg.norm(x_true)))
x = x_of(1e-3); print('fixed', repr(1e-3), repr(np.linalg.norm(x - x_true) / np.linalg.norm(x_true)))
U, s, Vt = np.linalg.svd(A, full_matrices=False); k = int(np.sum(s > 1e-3))
xt = Vt[:k].T @ ((U[:, :k].T @ b) / s[:k]); print('tsvd', k, repr(np.linalg.norm(xt - x_true) / np.linalg.norm(x_true)))
kmax = int(np.sum(s > s[0] * 16 * np.finfo(float).eps))
rk = [np.linalg.norm(A @ (Vt[:q].T @ ((U[:, :q].T @ b) / s[:q])) - b) for q in range(1, kmax + 1)]
g = [rk[q - 1] ** 2 / (m - q) ** 2 for q in range(1, kmax + 1)]
ok = [q for q in range(1, kmax + 1) if rk[q - 1] <= np.sqrt(m) * sigma]
print('tsvd_rules', int(np.argmin(g)) + 1, ok[0] if ok else kmax)
et = [np.linalg.norm(Vt[:q].T @ ((U[:, :q].T @ b) / s[:q]) - x_true) / np.linalg.norm(x_true) for q in range(1, kmax + 1)]
print('tsvd_best', int(np.argmin(et)) + 1, repr(min(et)))
