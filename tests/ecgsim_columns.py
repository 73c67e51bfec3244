"""ECGSim's heart and transfer columns, shared by e2e_mesh_ecgsim and e2e_bem_refine.

Endocardial and epicardial nodes are told apart independently of thorax: a ray from the node
along its outward normal (and two rays 0.17 rad off it) meets the heart surface again for an
endocardial node (the cavity's far wall) and escapes for an epicardial one; two hits of three
make a node endocardial."""
import math


def read_heart(pts, fac):
    """The heart's nodes and its triangles (0-based) from a thorax model's NAME.pts / NAME.fac."""
    P = [list(map(float, l.split())) for l in open(pts) if l.strip()]
    F = [[int(x) - 1 for x in l.split()] for l in open(fac) if l.strip()]
    assert min(min(t) for t in F) >= 0 and max(max(t) for t in F) < len(P)
    return P, F


def _sub(a, b): return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
def _cross(a, b): return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
def _dot(a, b): return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def endocardial(P, F):
    """The set of endocardial node indices (0-based), by the ray test above."""
    N = [[0.0] * 3 for _ in P]
    for t in F:
        n = _cross(_sub(P[t[1]], P[t[0]]), _sub(P[t[2]], P[t[0]]))
        for v in t: N[v] = [N[v][k] + n[k] for k in range(3)]

    def hits(o, d, skip):
        c = 0
        for t in F:
            if skip in t: continue
            a = P[t[0]]; e1, e2 = _sub(P[t[1]], a), _sub(P[t[2]], a); h = _cross(d, e2); det = _dot(e1, h)
            if abs(det) < 1e-12: continue
            s = _sub(o, a); u = _dot(s, h) / det
            if u < 0 or u > 1: continue
            q = _cross(s, e1); w = _dot(d, q) / det
            if w < 0 or u + w > 1: continue
            c += _dot(e2, q) / det > 1e-9
        return c
    endo = set()
    for v, n in enumerate(N):
        l = math.sqrt(_dot(n, n)); n = [x / l for x in n]
        a = [1, 0, 0] if abs(n[0]) < 0.9 else [0, 1, 0]
        u = _cross(n, a); lu = math.sqrt(_dot(u, u)); u = [x / lu for x in u]; w = _cross(n, u)
        dirs = (n, [n[k] * math.cos(0.17) + u[k] * math.sin(0.17) for k in range(3)],
                [n[k] * math.cos(0.17) + w[k] * math.sin(0.17) for k in range(3)])
        if sum(hits(P[v], d, v) > 0 for d in dirs) >= 2: endo.add(v)
    return endo


def load_rows(path, n):
    """The rows of n numbers of a text matrix (thorax --format text), header lines skipped."""
    R = []
    for l in open(path):
        try: R.append([float(x) for x in l.split()])
        except ValueError: continue
    return [r for r in R if len(r) == n]


def column_re(A, B, j):
    """|A_j - B_j| / |B_j| for column j, each column less its mean (B the reference)."""
    a = [r[j] for r in A]; b = [r[j] for r in B]
    ma, mb = sum(a) / len(a), sum(b) / len(b)
    a = [x - ma for x in a]; b = [x - mb for x in b]
    return math.sqrt(sum((x - y) ** 2 for x, y in zip(a, b))) / math.sqrt(sum(y * y for y in b))


def median(xs):
    return sorted(xs)[len(xs) // 2]
