/*
 * 3D Delaunay tetrahedralization (see thorax/mesh/delaunay.h; paper 3.3).
 *
 * Method.
 *  1. Order: BRIO (Amenta, Choi, Rote 2003). The points are shuffled with a
 *     fixed seed and cut into rounds [n/4, n), [n/16, n/4), ... inserted from
 *     the smallest; inside each round they follow a 3D Hilbert curve on a
 *     grid over the bounding box (Skilling's transpose form), the direction
 *     alternating from round to round so that a round starts where the
 *     previous one ended. The random rounds keep the expected cost
 *     O(n log n) whatever the input (grids included); the curve keeps the
 *     walks short and the memory access local.
 *  2. Location: a remembering stochastic visibility walk (Devillers, Pion,
 *     Teillaud 2002) from the last tetrahedron created: leave the current
 *     tetrahedron through a face that has the point strictly on its other
 *     side, trying the faces from a pseudo-random one and never the face just
 *     entered. It ends in a solid tetrahedron that contains the point (closed)
 *     or in a ghost whose hull face the point lies strictly beyond. The
 *     randomness makes it terminate with probability 1 in any triangulation;
 *     a step limit falls back to a scan of all tetrahedra (never seen).
 *  3. Insertion: Bowyer–Watson. The cavity (tetrahedra in conflict with the
 *     point) is grown by a depth-first search over face neighbours from the
 *     located tetrahedron, deleted, and replaced by one tetrahedron per
 *     boundary face joined to the point. Deleted slots are reused, leftovers
 *     go to a free list: no per-tetrahedron allocation.
 *
 * Conflict rules (p the new point):
 *  - solid tetrahedron t: p strictly inside the circumsphere of t under the
 *    symbolic perturbation below;
 *  - ghost t (a hull face and the vertex at infinity, INF): p strictly beyond
 *    the hull face; if p is in the plane of the hull face, t conflicts iff
 *    the solid tetrahedron across that face does (i.e. p inside the
 *    circumcircle of the face, perturbed the same way). This is the limit of
 *    the solid rule as the fourth vertex goes to infinity, so the two rules
 *    agree and the cavity stays a connected region star-shaped from p.
 *
 * Degeneracies: symbolic perturbation of the lifting. Point i is lifted to
 * the paraboloid height |x_i|^2 + eps^(n - i): the point with the largest
 * index is perturbed most. The perturbed points are in general position with
 * respect to spheres (no five cospherical), and their Delaunay
 * tetrahedralization (a regular triangulation of the original points) is
 * unique, is a Delaunay tetrahedralization of the original points, and has no
 * flat tetrahedra. When insphere(a,b,c,d,e) == 0 exactly, its perturbed sign is
 * the sign of the coefficient of the largest eps term: walking the five
 * points by decreasing index, the coefficient of e is -orient3d(a,b,c,d) < 0
 * (e lifted up: outside), that of a tetrahedron vertex v is
 * +orient3d(tetrahedron with v replaced by e); the first non-zero one decides.
 * The tetrahedron itself is not flat, so the walk ends at e at the latest.
 * Orientation is never perturbed: coplanar points (grid planes) need none,
 * since a tetrahedron built on a cavity face always has p strictly on the
 * cavity side of that face.
 *
 * Storage: tet_t holds v[4] (vertex indices, INF = -1 for the vertex at
 * infinity, v[0] = DEAD for a free slot) and n[4], the neighbour across the
 * face opposite v[i], coded (tetrahedron << 2) | (index of the shared face in
 * the neighbour), so that back-links are set in O(1). 32 bytes per
 * tetrahedron, 64-byte aligned; the cavity search marks tetrahedra with the
 * sign bits of n[0] and n[1] (cleared before the insertion returns).
 * Invariants: every live tetrahedron (solid or ghost) is positively oriented
 * (thx_orient3d(v0,v1,v2,v3) > 0; for a ghost, with INF replaced by any point
 * strictly beyond its hull face); n is symmetric: if t.n[i] = (o << 2) | j
 * then o.n[j] = (t << 2) | i and the two faces have the same vertices;
 * every live tetrahedron has four neighbours (the ghosts close the space).
 */
#include "thorax/mesh/delaunay.h"
#include "thorax/geom/predicates.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define INF (-1)
#define DEAD (-2)
#define MAX_POINTS ((size_t)1 << 26)
#define MAX_TETS ((size_t)1 << 29)
/* Neighbour codes are below 2^31; during an insertion the sign bit of n[0]
 * marks a tetrahedron of the cavity, that of n[1] one tested and not in it. */
#define CODE INT32_MAX
#define CAVITY INT32_MIN
#define TESTED INT32_MIN

typedef struct {
    int32_t v[4];
    int32_t n[4];
} tet_t;

/* A face of the cavity boundary: vertices f[3], counterclockwise seen from
 * outside the cavity, and the neighbour code of the tetrahedron beyond it. */
typedef struct {
    int32_t f[3];
    int32_t out;
    uint8_t l[4]; /* local numbers of f[] for linking (see LT), l[3] unused */
} bface;

/* Linking table side: a cavity boundary with at most LT - 2 distinct finite
 * vertices (nearly all of them) links its new tetrahedra through an
 * LT x LT table indexed by local vertex numbers (0: none, 1: INF); larger
 * ones through the edge hash table. */
#define LT 64

/* Open-addressing table entry: directed edge (a, b) of a new tetrahedron's
 * face through p, and the code (tetrahedron << 2 | face). Entries whose stamp
 * differs from the current one are empty (no clearing between insertions). */
typedef struct {
    uint64_t key;
    int32_t code;
    uint32_t stamp;
} hent;

typedef struct {
    thx_ctx *ctx;
    double *p;       /* coordinates in insertion order: vertex k is input point orig[k] (owned) */
    int32_t *orig;   /* insertion rank -> input index (owned) */
    int32_t np;      /* vertices (ranks) in use */
    size_t pcap;     /* capacity of p (points) and orig */
    /* incremental use (thx_dt): input index -> rank, rank -> a live tetrahedron holding it */
    int32_t *rank, *vt;
    int32_t *sstack;  /* star search stack */
    size_t sstack_cap;
    /* optional veto (thx_dt_insert_checked): a face inside the cavity it refuses stops the insertion */
    int (*reject)(void *user, int32_t a, int32_t b, int32_t c, int interior);
    void *reject_user;
    int rejected;
    int32_t rejected_face[3];
    size_t last_nb;   /* boundary faces of the last cavity (m->bnd), joined to point last_p */
    int32_t last_p;
    tet_t *t;
    size_t nt, tcap;
    uint32_t *mark; /* thx_dt_star's visit stamps (tcap; allocated by its first call) */
    uint32_t stamp;
    int32_t *freel;
    size_t nfree, free_cap;
    int32_t last;   /* walk start: a tetrahedron created by the last insertion */
    uint64_t rnd;
    int32_t *stack, *cav;
    size_t stack_cap, cav_cap;
    bface *bnd;
    size_t bnd_cap;
    hent *h;
    size_t hcap;
    uint32_t hstamp;
    uint8_t *vloc;   /* rank -> local number in the current cavity boundary, 0 outside it (pcap) */
    int32_t lv[LT];  /* local number -> rank (2..) */
    int32_t *newt;   /* the new tetrahedra of an insertion, one per boundary face */
    size_t newt_cap;
    int32_t *ltab;   /* LT x LT: directed edge (local a, local b) -> code of the new face holding it */
    /* figures */
    size_t walk_steps, cavity_tets, n_degenerate;
} dt_t;

/* Local vertex indices of the face opposite vertex i, ordered so that
 * (f0, f1, f2, v_i) is an even permutation of (v0, v1, v2, v3): the face is
 * counterclockwise seen from outside, and replacing v_i by a point on the same
 * side keeps the orientation. Same table as thx_delaunay_face. */
static const int FACE[4][3] = {{1, 3, 2}, {0, 2, 3}, {0, 3, 1}, {0, 1, 2}};

static inline const double *P(const dt_t *m, int32_t i) { return m->p + 3 * (size_t)i; }

/* Ghost test: INF = -1 is the only negative vertex in a live tetrahedron, so
 * the OR of the four indices is negative iff one of them is INF. */
static inline int is_ghost(const tet_t *t) { return (t->v[0] | t->v[1] | t->v[2] | t->v[3]) < 0; }

static inline int inf_slot(const tet_t *t)
{
    return t->v[0] == INF ? 0 : t->v[1] == INF ? 1 : t->v[2] == INF ? 2 : 3;
}

/* ---- predicates: the floating-point filters of predicates.c, inline --------
 * Same expressions and error bounds (9u and 17u times the permanent,
 * u = 2^-53); the exact predicates are called only when the filter cannot
 * decide. Called tens of millions of times: a function call each would cost
 * a sizeable share of the run time. */

/* Second stage, for points on grids (the meshing case, where the first stage
 * fails on every cospherical or coplanar set): if all coordinates are
 * multiples of 1/16 (mm) and all coordinate differences are at most 4096 in
 * magnitude, the differences are exact and, scaled by 16, integers of at most
 * 2^16. Every intermediate value of the floating-point evaluation is then an
 * integer (times a power of 2) bounded by 2^51 (orient3d: products of three
 * differences, three terms) or by the permanent (insphere, checked against
 * 2^52 after scaling), hence exactly representable: the float value IS the
 * exact determinant, zero included. */
static inline int on_grid(const double *a)
{
    for (int k = 0; k < 3; k++) {
        double s = a[k] * 16.0;
        if (!(fabs(s) < 2147483647.0) || s != (double)(int32_t)s) return 0;
    }
    return 1;
}

/* All coordinate differences of the k points q[] to the last one at most 4096. */
static int near_all(const double *const *q, int k)
{
    for (int i = 0; i + 1 < k; i++)
        for (int c = 0; c < 3; c++)
            if (!(fabs(q[i][c] - q[k - 1][c]) <= 4096.0)) return 0;
    return 1;
}

/* The filter failed: the second stage, then the exact predicate (not inlined:
 * rare except on grids, and kept out of the hot loop's code). The permanent
 * (sum of the absolute values of the terms) is computed here, only when needed. */
static __attribute__((noinline)) double orient_slow(const double *a, const double *b, const double *c,
                                                    const double *d, double det)
{
    double adx = a[0] - d[0], ady = a[1] - d[1], adz = a[2] - d[2];
    double bdx = b[0] - d[0], bdy = b[1] - d[1], bdz = b[2] - d[2];
    double cdx = c[0] - d[0], cdy = c[1] - d[1], cdz = c[2] - d[2];
    double perm = (fabs(bdx * cdy) + fabs(cdx * bdy)) * fabs(adz) + (fabs(cdx * ady) + fabs(adx * cdy)) * fabs(bdz) +
                  (fabs(adx * bdy) + fabs(bdx * ady)) * fabs(cdz);
    if (perm == 0) return 0.0; /* every product has an exactly zero factor: exact */
    double bound = (9.0 / 9007199254740992.0) * perm;
    if (det > bound || -det > bound) return det; /* Shewchuk's filter decides where the semi-static one did not */
    const double *q[4] = {a, b, c, d};
    if (on_grid(a) && on_grid(b) && on_grid(c) && on_grid(d) && near_all(q, 4)) return det;
    return thx_orient3d(a, b, c, d);
}

static __attribute__((noinline)) double insphere_slow(const double *a, const double *b, const double *c,
                                                      const double *d, const double *e, double det)
{
    double aex = a[0] - e[0], aey = a[1] - e[1], aez = a[2] - e[2];
    double bex = b[0] - e[0], bey = b[1] - e[1], bez = b[2] - e[2];
    double cex = c[0] - e[0], cey = c[1] - e[1], cez = c[2] - e[2];
    double dex = d[0] - e[0], dey = d[1] - e[1], dez = d[2] - e[2];
    double aezp = fabs(aez), bezp = fabs(bez), cezp = fabs(cez), dezp = fabs(dez);
    double abp = fabs(aex * bey) + fabs(bex * aey), bcp = fabs(bex * cey) + fabs(cex * bey);
    double cdp = fabs(cex * dey) + fabs(dex * cey), dap = fabs(dex * aey) + fabs(aex * dey);
    double acp = fabs(aex * cey) + fabs(cex * aey), bdp = fabs(bex * dey) + fabs(dex * bey);
    double alift = aex * aex + aey * aey + aez * aez;
    double blift = bex * bex + bey * bey + bez * bez;
    double clift = cex * cex + cey * cey + cez * cez;
    double dlift = dex * dex + dey * dey + dez * dez;
    double perm = (cdp * bezp + bdp * cezp + bcp * dezp) * alift + (dap * cezp + acp * dezp + cdp * aezp) * blift +
                  (abp * dezp + bdp * aezp + dap * bezp) * clift + (bcp * aezp + acp * bezp + abp * cezp) * dlift;
    double bound = (17.0 / 9007199254740992.0) * perm;
    if (det > bound || -det > bound) return det; /* Shewchuk's filter decides where the semi-static one did not */
    const double *q[5] = {a, b, c, d, e};
    /* permanent scaled by 16^5 below 2^52 */
    if (perm * 1048576.0 < 4503599627370496.0 && on_grid(a) && on_grid(b) && on_grid(c) && on_grid(d) &&
        on_grid(e) && near_all(q, 5))
        return det;
    return thx_insphere(a, b, c, d, e);
}

static inline double dmax(double x, double y) { return x > y ? x : y; }

/* First stage: semi-static filters. Shewchuk's bound (9u times the permanent
 * for orient3d, 17u for insphere, u = 2^-53, the permanent evaluated in
 * floating point) is bounded above by the same expression with every
 * |difference| replaced by the largest one of its coordinate, X, Y, Z
 * (rounding is monotonic): orient3d's permanent has 6 terms |x y z| <= XYZ,
 * insphere's 24 terms |x y z| lift <= XYZ (X^2 + Y^2 + Z^2). So
 *   |det| > 6.1e-15 XYZ               (> 54u XYZ, with rounding slack)
 *   |det| > 4.6e-14 XYZ (X^2+Y^2+Z^2)  (> 408u ..., with rounding slack)
 * decide the sign wherever Shewchuk's filter would have, give or take the
 * slack; elsewhere the slow path applies his filter itself, then the exact
 * stages. Fewer operations than the permanent (no products of absolute values). */
static inline __attribute__((always_inline)) double orient(const double *a, const double *b, const double *c, const double *d)
{
    double adx = a[0] - d[0], ady = a[1] - d[1], adz = a[2] - d[2];
    double bdx = b[0] - d[0], bdy = b[1] - d[1], bdz = b[2] - d[2];
    double cdx = c[0] - d[0], cdy = c[1] - d[1], cdz = c[2] - d[2];
    double det = adz * (bdx * cdy - cdx * bdy) + bdz * (cdx * ady - adx * cdy) + cdz * (adx * bdy - bdx * ady);
    double mx = dmax(dmax(fabs(adx), fabs(bdx)), fabs(cdx));
    double my = dmax(dmax(fabs(ady), fabs(bdy)), fabs(cdy));
    double mz = dmax(dmax(fabs(adz), fabs(bdz)), fabs(cdz));
    double bound = 6.1e-15 * (mx * my * mz);
    if (det > bound || -det > bound) return det;
    return orient_slow(a, b, c, d, det);
}

/* orient(a, b, c, d) given the differences A = a - d, B = b - d, C = c - d
 * (the same expression: the same value). */
static inline __attribute__((always_inline)) double orient_diff(const double *A, const double *B, const double *C,
                                                                const double *a, const double *b, const double *c,
                                                                const double *d)
{
    double det = A[2] * (B[0] * C[1] - C[0] * B[1]) + B[2] * (C[0] * A[1] - A[0] * C[1]) +
                 C[2] * (A[0] * B[1] - B[0] * A[1]);
    double mx = dmax(dmax(fabs(A[0]), fabs(B[0])), fabs(C[0]));
    double my = dmax(dmax(fabs(A[1]), fabs(B[1])), fabs(C[1]));
    double mz = dmax(dmax(fabs(A[2]), fabs(B[2])), fabs(C[2]));
    double bound = 6.1e-15 * (mx * my * mz);
    if (det > bound || -det > bound) return det;
    return orient_slow(a, b, c, d, det);
}

static inline __attribute__((always_inline)) double insphere(const double *a, const double *b, const double *c, const double *d, const double *e)
{
    double aex = a[0] - e[0], aey = a[1] - e[1], aez = a[2] - e[2];
    double bex = b[0] - e[0], bey = b[1] - e[1], bez = b[2] - e[2];
    double cex = c[0] - e[0], cey = c[1] - e[1], cez = c[2] - e[2];
    double dex = d[0] - e[0], dey = d[1] - e[1], dez = d[2] - e[2];
    double ab = aex * bey - bex * aey, bc = bex * cey - cex * bey, cd = cex * dey - dex * cey;
    double da = dex * aey - aex * dey, ac = aex * cey - cex * aey, bd = bex * dey - dex * bey;
    double abc = aez * bc - bez * ac + cez * ab;
    double bcd = bez * cd - cez * bd + dez * bc;
    double cda = cez * da + dez * ac + aez * cd;
    double dab = dez * ab + aez * bd + bez * da;
    double alift = aex * aex + aey * aey + aez * aez;
    double blift = bex * bex + bey * bey + bez * bez;
    double clift = cex * cex + cey * cey + cez * cez;
    double dlift = dex * dex + dey * dey + dez * dez;
    double det = (dlift * abc - clift * dab) + (blift * cda - alift * bcd);
    double mx = dmax(dmax(fabs(aex), fabs(bex)), dmax(fabs(cex), fabs(dex)));
    double my = dmax(dmax(fabs(aey), fabs(bey)), dmax(fabs(cey), fabs(dey)));
    double mz = dmax(dmax(fabs(aez), fabs(bez)), dmax(fabs(cez), fabs(dez)));
    double bound = 4.6e-14 * (mx * my * mz) * (mx * mx + my * my + mz * mz);
    if (det > bound || -det > bound) return det;
    return insphere_slow(a, b, c, d, e, det);
}

/* orient3d of tetrahedron t with vertex slot i replaced by point pi
 * (all four vertices finite after the replacement). */
static inline double orient_replaced(const dt_t *m, const tet_t *t, int i, int32_t pi)
{
    const double *q[4];
    for (int k = 0; k < 4; k++) q[k] = k == i ? P(m, pi) : P(m, t->v[k]);
    return orient(q[0], q[1], q[2], q[3]);
}

/* Perturbed sign of insphere(t, pi) given that the exact value is 0:
 * 1 if pi is in conflict (inside), 0 if not. See the header comment. */
static int perturbed_inside(dt_t *m, const tet_t *t, int32_t pi)
{
    const int32_t *org = m->orig; /* the perturbation ranks points by input index */
    int32_t id[5] = {org[t->v[0]], org[t->v[1]], org[t->v[2]], org[t->v[3]], org[pi]};
    int pos[5] = {0, 1, 2, 3, 4};
    /* sort the five positions by decreasing point index (indices are distinct) */
    for (int a = 1; a < 5; a++) {
        int x = pos[a], b = a;
        while (b > 0 && id[pos[b - 1]] < id[x]) { pos[b] = pos[b - 1]; b--; }
        pos[b] = x;
    }
    m->n_degenerate++;
    for (int k = 0; k < 5; k++) {
        int j = pos[k];
        if (j == 4) return 0; /* the new point lifted most: outside */
        double o = orient_replaced(m, t, j, pi);
        if (o > 0) return 1;
        if (o < 0) return 0;
    }
    return 0; /* not reached: the tetrahedron itself is not flat */
}

static inline int solid_conflict(dt_t *m, const tet_t *t, int32_t pi)
{
    double s = insphere(P(m, t->v[0]), P(m, t->v[1]), P(m, t->v[2]), P(m, t->v[3]), P(m, pi));
    if (s > 0) return 1;
    if (s < 0) return 0;
    return perturbed_inside(m, t, pi);
}

static int in_conflict(dt_t *m, int32_t ti, int32_t pi)
{
    const tet_t *t = &m->t[ti];
    if (!is_ghost(t)) return solid_conflict(m, t, pi);
    int k = inf_slot(t);
    double o = orient_replaced(m, t, k, pi);
    if (o > 0) return 1;
    if (o < 0) return 0;
    /* p in the plane of the hull face: decided by the solid tetrahedron across it */
    return solid_conflict(m, &m->t[t->n[k] >> 2], pi);
}

/* ---- storage ---------------------------------------------------------------- */

/* Tetrahedron storage aligned to a cache line, so that no 32-byte
 * tetrahedron straddles two lines (malloc's 16-byte alignment would split
 * every other one). Grown by copying: realloc would not keep the alignment. */
static tet_t *tets_alloc(thx_ctx *ctx, size_t cap, const tet_t *old, size_t n_old)
{
    size_t bytes = (cap * sizeof(tet_t) + 63) & ~(size_t)63;
    tet_t *t = aligned_alloc(64, bytes);
    if (!t) {
        thx_error(ctx, THX_ENOMEM, "out of memory (%zu bytes)", bytes);
        return NULL;
    }
    if (n_old) memcpy(t, old, n_old * sizeof *t);
    return t;
}

static thx_status tet_new(dt_t *m, int32_t *out)
{
    if (m->nfree > 0) {
        *out = m->freel[--m->nfree];
        return THX_OK;
    }
    if (m->nt >= MAX_TETS)
        return thx_error(m->ctx, THX_EINPUT, "delaunay3d: more than %zu tetrahedra needed", MAX_TETS);
    if (m->nt == m->tcap) {
        size_t cap = m->tcap + m->tcap / 2 + 64;
        tet_t *t = tets_alloc(m->ctx, cap, m->t, m->nt);
        if (!t) return THX_ENOMEM;
        free(m->t);
        m->t = t;
        if (m->mark) {
            uint32_t *mk = thx_realloc(m->ctx, m->mark, cap * sizeof *mk);
            if (!mk) return THX_ENOMEM;
            memset(mk + m->tcap, 0, (cap - m->tcap) * sizeof *mk);
            m->mark = mk;
        }
        m->tcap = cap;
    }
    if (m->mark) m->mark[m->nt] = 0;
    *out = (int32_t)m->nt++;
    return THX_OK;
}

static inline thx_status push_i32(dt_t *m, int32_t **arr, size_t *cap, size_t n, int32_t v)
{
    if (n >= *cap) THX_CHECK(thx_grow(m->ctx, (void **)arr, cap, n + 1, sizeof **arr));
    (*arr)[n] = v;
    return THX_OK;
}

/* ---- location ----------------------------------------------------------------- */

/* Exhaustive search (safety net for the walk): a solid tetrahedron containing
 * pi or a ghost pi lies strictly beyond. */
static int32_t locate_scan(const dt_t *m, int32_t pi)
{
    for (size_t ti = 0; ti < m->nt; ti++) {
        const tet_t *t = &m->t[ti];
        if (t->v[0] == DEAD) continue;
        if (is_ghost(t)) {
            if (orient_replaced(m, t, inf_slot(t), pi) > 0) return (int32_t)ti;
            continue;
        }
        int in = 1;
        for (int i = 0; i < 4 && in; i++) in = orient_replaced(m, t, i, pi) >= 0;
        if (in) return (int32_t)ti;
    }
    return -1;
}

/* Walk to a tetrahedron in conflict with pi (see the header comment, 2). */
static int32_t locate(dt_t *m, int32_t pi)
{
    int32_t ti = m->last;
    if (is_ghost(&m->t[ti])) ti = m->t[ti].n[inf_slot(&m->t[ti])] >> 2;
    const double *p = P(m, pi);
    int from = -1;
    size_t steps = 0, limit = 4 * m->nt + 1000;
    for (;;) {
        const tet_t *t = &m->t[ti];
        if (is_ghost(t)) break;
        m->rnd = m->rnd * 6364136223846793005ull + 1442695040888963407ull;
        int r = (int)(m->rnd >> 62), moved = 0;
        /* the four vertices relative to p, shared by the faces tried */
        double d[4][3];
        for (int k = 0; k < 4; k++) {
            const double *q = P(m, t->v[k]);
            for (int c = 0; c < 3; c++) d[k][c] = q[c] - p[c];
        }
        for (int s = 0; s < 4; s++) {
            int i = (r + s) & 3;
            if (i == from) continue;
            const int *f = FACE[i]; /* orient(f0, f1, f2, p): the sign of orient_replaced(t, i, p) */
            if (orient_diff(d[f[0]], d[f[1]], d[f[2]], P(m, t->v[f[0]]), P(m, t->v[f[1]]), P(m, t->v[f[2]]), p) < 0) {
                int32_t c = t->n[i];
                ti = c >> 2;
                from = c & 3;
                moved = 1;
                break;
            }
        }
        if (!moved) break;
        if (++steps > limit) {
            ti = locate_scan(m, pi);
            break;
        }
    }
    m->walk_steps += steps;
    return ti;
}

/* ---- insertion ------------------------------------------------------------------ */

static inline uint32_t hash_edge(uint64_t key)
{
    key *= 0x9E3779B97F4A7C15ull;
    return (uint32_t)(key >> 32);
}

static thx_status link_small(dt_t *m, int32_t pi, size_t nc, size_t nb);
static thx_status link_hashed(dt_t *m, int32_t pi, size_t nc, size_t nb);
static thx_status finish_insert(dt_t *m, int32_t pi, size_t nc, size_t nb, int32_t ti);

/* Bowyer–Watson insertion of point pi. */
static thx_status insert_point(dt_t *m, int32_t pi)
{
    int32_t t0 = locate(m, pi);
    if (t0 < 0) return thx_error(m->ctx, THX_EINTERNAL, "delaunay3d: point %d could not be located", (int)pi);
    if (!is_ghost(&m->t[t0])) {
        const double *q = P(m, pi);
        for (int k = 0; k < 4; k++) {
            int32_t v = m->t[t0].v[k];
            const double *w = P(m, v);
            if (w[0] == q[0] && w[1] == q[1] && w[2] == q[2]) {
                int32_t a = m->orig[v], b = m->orig[pi];
                return thx_error(m->ctx, THX_EGEOM, "delaunay3d: points %d and %d coincide (%.17g, %.17g, %.17g)",
                                 (int)(a < b ? a : b), (int)(a < b ? b : a), q[0], q[1], q[2]);
            }
        }
    }
    /* Cavity search. Marks live in the tetrahedra themselves (no separate
     * array to miss in the cache): the sign bit of n[0] = in the cavity,
     * of n[1] = tested, not in it (see CAVITY, TESTED). Every marked
     * tetrahedron is on the cavity list or beyond a boundary face, so the
     * marks are cleared (or overwritten) before the insertion returns. */
    size_t ns = 0, nc = 0, nb = 0;
    thx_status st = THX_OK;
    if ((st = push_i32(m, &m->stack, &m->stack_cap, ns++, t0)) != THX_OK) return st;
    if ((st = push_i32(m, &m->cav, &m->cav_cap, nc++, t0)) != THX_OK) return st;
    m->t[t0].n[0] |= CAVITY;
    /* Invariant: every tetrahedron on the stack is in the cavity; a tetrahedron
     * is tested at most once per insertion (its mark remembers the answer). */
    while (ns > 0) {
        int32_t c = m->stack[--ns];
        for (int i = 0; i < 4; i++) {
            int32_t code = m->t[c].n[i] & CODE, o = code >> 2;
            tet_t *to = &m->t[o];
            if (to->n[0] & CAVITY) continue;
            if (!(to->n[1] & TESTED)) {
                if (in_conflict(m, o, pi)) {
                    if ((st = push_i32(m, &m->stack, &m->stack_cap, ns, o)) != THX_OK ||
                        (st = push_i32(m, &m->cav, &m->cav_cap, nc, o)) != THX_OK)
                        goto fail;
                    ns++;
                    nc++;
                    to->n[0] |= CAVITY;
                    /* its neighbours are tested soon (depth first): start fetching them */
                    for (int j = 0; j < 4; j++) __builtin_prefetch(&m->t[(to->n[j] & CODE) >> 2]);
                    continue;
                }
            }
            if (nb >= m->bnd_cap &&
                (st = thx_grow(m->ctx, (void **)&m->bnd, &m->bnd_cap, nb + 1, sizeof *m->bnd)) != THX_OK)
                goto fail;
            const tet_t *tc = &m->t[c];
            bface *b = &m->bnd[nb++];
            b->f[0] = tc->v[FACE[i][0]];
            b->f[1] = tc->v[FACE[i][1]];
            b->f[2] = tc->v[FACE[i][2]];
            b->out = code;
            to->n[1] |= TESTED;
        }
    }
    if (m->reject) {
        /* faces shared by two cavity tetrahedra would disappear: ask before anything changes */
        for (size_t k = 0; k < nc; k++) {
            int32_t c = m->cav[k];
            const tet_t *tc = &m->t[c];
            for (int i = 0; i < 4; i++) {
                int32_t o = (tc->n[i] & CODE) >> 2;
                if (o <= c || !(m->t[o].n[0] & CAVITY)) continue;
                int32_t a = tc->v[FACE[i][0]], b = tc->v[FACE[i][1]], d = tc->v[FACE[i][2]];
                if (a < 0 || b < 0 || d < 0) continue;
                if (m->reject(m->reject_user, m->orig[a], m->orig[b], m->orig[d], 1)) {
                    m->rejected = 1;
                    m->rejected_face[0] = m->orig[a];
                    m->rejected_face[1] = m->orig[b];
                    m->rejected_face[2] = m->orig[d];
                    goto fail;
                }
            }
        }
        for (size_t k = 0; k < nb; k++) {
            const bface *bf = &m->bnd[k];
            if (bf->f[0] < 0 || bf->f[1] < 0 || bf->f[2] < 0) continue;
            if (m->reject(m->reject_user, m->orig[bf->f[0]], m->orig[bf->f[1]], m->orig[bf->f[2]], 0)) {
                m->rejected = 1;
                for (int j = 0; j < 3; j++) m->rejected_face[j] = m->orig[bf->f[j]];
                goto fail;
            }
        }
    }
    m->cavity_tets += nc;

    /* Local numbers of the boundary vertices (see LT): 1 for INF, 2.. for the others in order of appearance; more than LT - 2 of them
     * (large cavities: degenerate input, refinement) take the hash table. */
    int small = 1;
    uint32_t nl = 2;
    for (size_t k = 0; k < nb && small; k++) {
        bface *bf = &m->bnd[k];
        for (int j = 0; j < 3; j++) {
            int32_t v = bf->f[j];
            uint32_t l = 1;
            if (v >= 0) {
                l = m->vloc[v];
                if (!l) {
                    if (nl == LT) { small = 0; break; }
                    l = nl;
                    m->vloc[v] = (uint8_t)nl;
                    m->lv[nl++] = v;
                }
            }
            bf->l[j] = (uint8_t)l;
        }
    }
    for (uint32_t l = 2; l < nl; l++) m->vloc[m->lv[l]] = 0;
    if (small) return link_small(m, pi, nc, nb);
    return link_hashed(m, pi, nc, nb);
fail: /* nothing changed but the marks */
    for (size_t k = 0; k < nc; k++) m->t[m->cav[k]].n[0] &= CODE;
    for (size_t k = 0; k < nb; k++) m->t[m->bnd[k].out >> 2].n[1] &= CODE;
    return st;
}

/* The new tetrahedron (f0, f1, f2, p) on boundary face k, in a cavity slot
 * (k < nc) or a new one; joined to the tetrahedron beyond the face. Positive
 * because p is on the cavity side of the face. */
static inline thx_status new_tet(dt_t *m, int32_t pi, size_t nc, size_t k, int32_t *out)
{
    int32_t ti;
    if (k < nc) ti = m->cav[k];
    else THX_CHECK(tet_new(m, &ti));
    const bface *b = &m->bnd[k];
    tet_t *t = &m->t[ti];
    t->v[0] = b->f[0];
    t->v[1] = b->f[1];
    t->v[2] = b->f[2];
    t->v[3] = pi;
    t->n[3] = b->out;
    if (m->vt) {
        for (int j = 0; j < 3; j++)
            if (b->f[j] >= 0) m->vt[b->f[j]] = ti;
        m->vt[pi] = ti;
    }
    tet_t *o = &m->t[b->out >> 2];
    o->n[b->out & 3] = (ti << 2) | 3;
    o->n[1] &= CODE; /* its TESTED mark */
    *out = ti;
    return THX_OK;
}

/* Face j < 3 of the new tetrahedron on boundary face f holds p and the
 * boundary edge (f[j+1], f[j+2]) (indices mod 3). The boundary faces are
 * consistently oriented (a closed surface), so the neighbour through that
 * face holds the same edge reversed: with the table, the first pass records
 * every directed edge, the second reads every reversed one (all present). */
static thx_status link_small(dt_t *m, int32_t pi, size_t nc, size_t nb)
{
    if (nb > m->newt_cap) THX_CHECK(thx_grow(m->ctx, (void **)&m->newt, &m->newt_cap, nb, sizeof *m->newt));
    int32_t *tab = m->ltab, *nt = m->newt;
    int32_t ti = -1;
    for (size_t k = 0; k < nb; k++) {
        THX_CHECK(new_tet(m, pi, nc, k, &ti));
        nt[k] = ti;
        const uint8_t *l = m->bnd[k].l;
        tab[l[1] * LT + l[2]] = (ti << 2) | 0;
        tab[l[2] * LT + l[0]] = (ti << 2) | 1;
        tab[l[0] * LT + l[1]] = (ti << 2) | 2;
    }
    for (size_t k = 0; k < nb; k++) {
        tet_t *t = &m->t[nt[k]];
        const uint8_t *l = m->bnd[k].l;
        t->n[0] = tab[l[2] * LT + l[1]];
        t->n[1] = tab[l[0] * LT + l[2]];
        t->n[2] = tab[l[1] * LT + l[0]];
    }
    return finish_insert(m, pi, nc, nb, ti);
}

static thx_status link_hashed(dt_t *m, int32_t pi, size_t nc, size_t nb)
{
    /* Edge table for linking the new tetrahedra to each other. */
    if (m->hcap < 4 * nb) {
        size_t cap = 64;
        while (cap < 4 * nb) cap *= 2;
        hent *h = thx_calloc(m->ctx, cap, sizeof *h);
        if (!h) return THX_ENOMEM;
        free(m->h);
        m->h = h;
        m->hcap = cap;
        m->hstamp = 0;
    }
    if (++m->hstamp == 0) {
        memset(m->h, 0, m->hcap * sizeof *m->h);
        m->hstamp = 1;
    }
    const uint32_t hs = m->hstamp;
    const size_t hmask = m->hcap - 1;
    int32_t ti = -1;
    for (size_t k = 0; k < nb; k++) {
        THX_CHECK(new_tet(m, pi, nc, k, &ti));
        const bface b = m->bnd[k];
        tet_t *t = &m->t[ti];
        for (int j = 0; j < 3; j++) {
            uint32_t a = (uint32_t)b.f[j == 2 ? 0 : j + 1], c = (uint32_t)b.f[j == 0 ? 2 : j - 1];
            uint64_t rev = ((uint64_t)c << 32) | a;
            size_t s = hash_edge(rev) & hmask;
            while (m->h[s].stamp == hs && m->h[s].key != rev) s = (s + 1) & hmask;
            if (m->h[s].stamp == hs) { /* found: link both */
                int32_t oc = m->h[s].code;
                t->n[j] = oc;
                m->t[oc >> 2].n[oc & 3] = (ti << 2) | j;
            } else {
                uint64_t key = ((uint64_t)a << 32) | c;
                s = hash_edge(key) & hmask;
                while (m->h[s].stamp == hs) s = (s + 1) & hmask;
                m->h[s].key = key;
                m->h[s].code = (ti << 2) | j;
                m->h[s].stamp = hs;
            }
        }
    }
    return finish_insert(m, pi, nc, nb, ti);
}

/* Leftover cavity slots to the free list; the walk restarts from ti. */
static thx_status finish_insert(dt_t *m, int32_t pi, size_t nc, size_t nb, int32_t ti)
{
    /* (a cavity can hold more tetrahedra than its boundary has faces) */
    for (size_t k = nb; k < nc; k++) {
        int32_t d = m->cav[k];
        m->t[d].v[0] = DEAD;
        m->t[d].n[0] &= CODE; /* its CAVITY mark */
        THX_CHECK(push_i32(m, &m->freel, &m->free_cap, m->nfree, d));
        m->nfree++;
    }
    m->last = ti;
    m->last_nb = nb;
    m->last_p = pi;
    return THX_OK;
}

/* ---- order: BRIO rounds, Hilbert curve inside each -------------------------- */

/* Hilbert index of (x, y, z) on a 2^bits grid (Skilling 2004: axes to the
 * "transposed" index, then the bits interleaved). 3 * bits <= 32. */
static uint32_t hilbert3(uint32_t x, uint32_t y, uint32_t z, int bits)
{
    uint32_t X[3] = {x, y, z};
    uint32_t M = 1u << (bits - 1);
    for (uint32_t Q = M; Q > 1; Q >>= 1) { /* undo the excess work of the Gray code */
        uint32_t Pm = Q - 1;
        for (int i = 0; i < 3; i++) {
            if (X[i] & Q) X[0] ^= Pm; /* invert */
            else {                    /* exchange */
                uint32_t t = (X[0] ^ X[i]) & Pm;
                X[0] ^= t;
                X[i] ^= t;
            }
        }
    }
    X[1] ^= X[0]; /* Gray encode */
    X[2] ^= X[1];
    uint32_t t = 0;
    for (uint32_t Q = M; Q > 1; Q >>= 1)
        if (X[2] & Q) t ^= Q - 1;
    for (int i = 0; i < 3; i++) X[i] ^= t;
    uint32_t d = 0;
    for (int b = bits - 1; b >= 0; b--)
        for (int i = 0; i < 3; i++) d = (d << 1) | ((X[i] >> b) & 1u);
    return d;
}

/* Stable LSD radix sort of a[0..n) by the key_bits bits above bit 32
 * (11-bit digits); tmp holds n elements. */
static void radix_sort_hi(uint64_t *a, uint64_t *tmp, size_t n, int key_bits)
{
    size_t count[2048];
    for (int shift = 0; shift < key_bits; shift += 11) {
        memset(count, 0, sizeof count);
        for (size_t i = 0; i < n; i++) count[(a[i] >> (32 + shift)) & 2047]++;
        size_t sum = 0;
        for (int d = 0; d < 2048; d++) { size_t c = count[d]; count[d] = sum; sum += c; }
        for (size_t i = 0; i < n; i++) tmp[count[(a[i] >> (32 + shift)) & 2047]++] = a[i];
        memcpy(a, tmp, n * sizeof *a);
    }
}

static inline uint64_t splitmix(uint64_t *s)
{
    uint64_t z = (*s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

/* Fills ord[0..n) with the insertion order. */
static thx_status brio_order(thx_ctx *ctx, const double *xyz, size_t n, int32_t *ord)
{
    uint64_t *a = thx_malloc(ctx, 2 * n * sizeof *a);
    if (!a) return THX_ENOMEM;
    uint64_t seed = 0x5DEECE66Dull;
    for (size_t i = 0; i < n; i++) ord[i] = (int32_t)i;
    for (size_t i = n - 1; i > 0; i--) { /* Fisher–Yates, fixed seed */
        size_t j = (size_t)(splitmix(&seed) % (i + 1));
        int32_t t = ord[i]; ord[i] = ord[j]; ord[j] = t;
    }
    double lo[3], hi[3];
    for (int c = 0; c < 3; c++) lo[c] = hi[c] = xyz[c];
    for (size_t i = 1; i < n; i++)
        for (int c = 0; c < 3; c++) {
            lo[c] = fmin(lo[c], xyz[3 * i + c]);
            hi[c] = fmax(hi[c], xyz[3 * i + c]);
        }
    double span = fmax(hi[0] - lo[0], fmax(hi[1] - lo[1], hi[2] - lo[2]));
    /* rounds [b_k, e_k): [n/4, n), [n/16, n/4), ..., [0, small) */
    size_t rb[32], re[32];
    int rbits[32], nr = 0;
    for (size_t e = n; e > 0; nr++) {
        size_t b = e / 4 < 64 ? 0 : e / 4;
        int bits = 2;
        while (bits < 10 && ((size_t)1 << (3 * (bits - 2))) < e - b) bits++;
        rb[nr] = b;
        re[nr] = e;
        rbits[nr] = bits;
        e = b;
    }
    /* Keys in input order (the coordinates read sequentially, not in the
     * shuffled order: for 10^6 points that gather was a cache miss per
     * point), each written at its point's shuffled position. */
    int32_t *pos = (int32_t *)(a + n); /* inverse of the shuffle; that half of a is the sort's scratch later */
    for (size_t k = 0; k < n; k++) pos[ord[k]] = (int32_t)k;
    for (size_t i = 0; i < n; i++) {
        size_t k = (size_t)pos[i];
        int r = 0;
        while (k < rb[r]) r++;
        int bits = rbits[r];
        double sc = span > 0 ? (double)((1u << bits) - 1) / span : 0.0;
        uint32_t q[3];
        for (int c = 0; c < 3; c++) {
            double v = (xyz[3 * i + c] - lo[c]) * sc;
            q[c] = v <= 0 ? 0u : (v >= (double)((1u << bits) - 1) ? (1u << bits) - 1 : (uint32_t)v);
        }
        a[k] = ((uint64_t)hilbert3(q[0], q[1], q[2], bits) << 32) | (uint32_t)i;
    }
    for (int r = 0; r < nr; r++) {
        size_t b = rb[r], m = re[r] - b;
        radix_sort_hi(a + b, a + n, m, 3 * rbits[r]);
        /* The rounds are inserted coarsest first, i.e. in the reverse of the
         * order built here; reversing every other round makes each one start
         * near where the previous one ended (the last round runs forward). */
        for (size_t k = 0; k < m; k++) ord[b + k] = (int32_t)(a[b + ((r & 1) ? m - 1 - k : k)] & 0xffffffffu);
    }
    free(a);
    return THX_OK;
}

/* ---- driver ---------------------------------------------------------------------- */

typedef struct {
    double x, y, z;
    int32_t i;
} xyz_rec;

static int cmp_xyz(const void *pa, const void *pb)
{
    const xyz_rec *u = pa, *v = pb;
    if (u->x != v->x) return u->x < v->x ? -1 : 1;
    if (u->y != v->y) return u->y < v->y ? -1 : 1;
    if (u->z != v->z) return u->z < v->z ? -1 : 1;
    return (u->i > v->i) - (u->i < v->i);
}

/* Reports the first pair of coinciding points (by sorting), or THX_OK. */
static thx_status check_duplicates(thx_ctx *ctx, const double *xyz, size_t n)
{
    xyz_rec *r = thx_malloc(ctx, (n ? n : 1) * sizeof *r);
    if (!r) return THX_ENOMEM;
    for (size_t i = 0; i < n; i++) {
        r[i].x = xyz[3 * i]; r[i].y = xyz[3 * i + 1]; r[i].z = xyz[3 * i + 2]; r[i].i = (int32_t)i;
    }
    qsort(r, n, sizeof *r, cmp_xyz);
    thx_status st = THX_OK;
    for (size_t i = 1; i < n; i++)
        if (r[i].x == r[i - 1].x && r[i].y == r[i - 1].y && r[i].z == r[i - 1].z) {
            int32_t a = r[i - 1].i < r[i].i ? r[i - 1].i : r[i].i, b = r[i - 1].i < r[i].i ? r[i].i : r[i - 1].i;
            st = thx_error(ctx, THX_EGEOM, "delaunay3d: points %d and %d coincide (%.17g, %.17g, %.17g)", (int)a,
                           (int)b, r[i].x, r[i].y, r[i].z);
            break;
        }
    free(r);
    return st;
}

static void dt_free(dt_t *m)
{
    free(m->p);
    free(m->orig);
    free(m->rank);
    free(m->vt);
    free(m->sstack);
    free(m->t);
    free(m->mark);
    free(m->freel);
    free(m->stack);
    free(m->cav);
    free(m->bnd);
    free(m->h);
    free(m->vloc);
    free(m->newt);
    free(m->ltab);
}

/* Builds the first solid tetrahedron s (positive) and its four ghosts. */
static thx_status seed(dt_t *m, const int32_t s[4])
{
    int32_t ids[5];
    for (int k = 0; k < 5; k++) THX_CHECK(tet_new(m, &ids[k]));
    tet_t *t0 = &m->t[ids[0]];
    for (int k = 0; k < 4; k++) t0->v[k] = s[k];
    /* Ghost k: the solid one with vertex k replaced by INF (a point beyond face
     * k is on the other side from v_k, so that alone would be negative) and
     * two other vertices swapped to make it positive. */
    for (int k = 0; k < 4; k++) {
        tet_t *g = &m->t[ids[1 + k]];
        for (int j = 0; j < 4; j++) g->v[j] = s[j];
        g->v[k] = INF;
        int a = (k + 1) & 3, b = (k + 2) & 3;
        int32_t tmp = g->v[a]; g->v[a] = g->v[b]; g->v[b] = tmp;
    }
    /* link by matching vertex sets (5 tetrahedra: brute force) */
    for (int x = 0; x < 5; x++)
        for (int i = 0; i < 4; i++) {
            tet_t *tx = &m->t[ids[x]];
            int32_t fx[3] = {tx->v[FACE[i][0]], tx->v[FACE[i][1]], tx->v[FACE[i][2]]};
            int found = 0;
            for (int y = 0; y < 5 && !found; y++) {
                if (y == x) continue;
                const tet_t *ty = &m->t[ids[y]];
                for (int j = 0; j < 4 && !found; j++) {
                    int match = 0;
                    for (int u = 0; u < 3; u++)
                        for (int w = 0; w < 3; w++) match += fx[u] == ty->v[FACE[j][w]];
                    if (match == 3) {
                        tx->n[i] = (ids[y] << 2) | j;
                        found = 1;
                    }
                }
            }
            if (!found) return thx_error(m->ctx, THX_EINTERNAL, "delaunay3d: seed tetrahedra not closed");
        }
    m->last = ids[0];
    return THX_OK;
}

/* Builds the Delaunay tetrahedralization of the n input points into *m (zeroed by the
 * caller; m->ctx set). On failure m may hold partial storage: dt_free it. */
static thx_status dt_build(thx_ctx *ctx, const double *xyz, size_t n, dt_t *m, double *t_sort, double *t_insert)
{
    if (n > MAX_POINTS) return thx_error(ctx, THX_EINPUT, "delaunay3d: too many points (%zu > %zu)", n, MAX_POINTS);
    for (size_t i = 0; i < 3 * n; i++)
        if (!isfinite(xyz[i]))
            return thx_error(ctx, THX_EINPUT, "delaunay3d: point %zu has a non-finite coordinate", i / 3);
    if (n < 4) {
        THX_CHECK(check_duplicates(ctx, xyz, n));
        return thx_error(ctx, THX_EGEOM, "delaunay3d: %zu points: a tetrahedralization needs at least 4", n);
    }
    m->ctx = ctx;
    m->np = (int32_t)n;
    m->pcap = n;
    m->rnd = 0x2545F4914F6CDD1Dull;
    double t_start = thx_wtime();

    m->orig = thx_malloc(ctx, n * sizeof *m->orig);
    if (!m->orig) return THX_ENOMEM;
    THX_CHECK(brio_order(ctx, xyz, n, m->orig));
    /* A copy of the coordinates in insertion order: consecutive insertions
     * then touch nearby memory (for 10^6 points this halves the run time). */
    m->p = thx_malloc(ctx, 3 * n * sizeof *m->p);
    if (!m->p) return THX_ENOMEM;
    for (size_t k = 0; k < n; k++) memcpy(m->p + 3 * k, xyz + 3 * (size_t)m->orig[k], 3 * sizeof *m->p);
    double t_sorted = thx_wtime();

    /* Seed: the first point, the next distinct one, the next not collinear,
     * the next not coplanar (in insertion order; s[] holds insertion ranks). */
    int32_t s[4] = {0, -1, -1, -1};
    {
        const double *p0 = P(m, s[0]);
        for (size_t k = 1; k < n && s[1] < 0; k++) {
            const double *q = P(m, (int32_t)k);
            if (q[0] != p0[0] || q[1] != p0[1] || q[2] != p0[2]) s[1] = (int32_t)k;
        }
        if (s[1] >= 0) {
            /* collinear iff all three 2D projections are (exact) */
            const double *p1 = P(m, s[1]);
            for (size_t k = 1; k < n && s[2] < 0; k++) {
                const double *q = P(m, (int32_t)k);
                double xy[3][2] = {{p0[0], p0[1]}, {p1[0], p1[1]}, {q[0], q[1]}};
                double yz[3][2] = {{p0[1], p0[2]}, {p1[1], p1[2]}, {q[1], q[2]}};
                double zx[3][2] = {{p0[2], p0[0]}, {p1[2], p1[0]}, {q[2], q[0]}};
                if (thx_orient2d(xy[0], xy[1], xy[2]) != 0 || thx_orient2d(yz[0], yz[1], yz[2]) != 0 ||
                    thx_orient2d(zx[0], zx[1], zx[2]) != 0) {
                    s[2] = (int32_t)k;
                }
            }
        }
        if (s[2] >= 0)
            for (size_t k = 1; k < n && s[3] < 0; k++)
                if (orient(P(m, s[0]), P(m, s[1]), P(m, s[2]), P(m, (int32_t)k)) != 0) s[3] = (int32_t)k;
    }
    if (s[3] < 0) {
        THX_CHECK(check_duplicates(ctx, xyz, n));
        return thx_error(ctx, THX_EGEOM, "delaunay3d: all %zu points are %s: no tetrahedron", n,
                         s[2] < 0 ? "collinear" : "coplanar");
    }
    if (orient(P(m, s[0]), P(m, s[1]), P(m, s[2]), P(m, s[3])) < 0) { int32_t t = s[1]; s[1] = s[2]; s[2] = t; }

    m->tcap = 7 * n + 64; /* ~6.5 tetrahedra per point for random points, plus the ghosts */
    m->t = tets_alloc(ctx, m->tcap, NULL, 0);
    m->vloc = thx_calloc(ctx, n, sizeof *m->vloc);
    m->ltab = thx_malloc(ctx, LT * LT * sizeof *m->ltab);
    if (!m->t || !m->vloc || !m->ltab) return THX_ENOMEM;
    THX_CHECK(seed(m, s));
    for (size_t k = 1; k < n; k++) {
        if ((int32_t)k == s[1] || (int32_t)k == s[2] || (int32_t)k == s[3]) continue;
        THX_CHECK(insert_point(m, (int32_t)k));
    }
    if (t_sort) *t_sort = t_sorted - t_start;
    if (t_insert) *t_insert = thx_wtime() - t_sorted;
    return THX_OK;
}

/* Output. The hull links are cut first (a solid's code pointing to a ghost
 * becomes -1); then solids from the end fill the ghost and free slots
 * below, their neighbours' back-links following. The solids end up in
 * [0, cnt), in storage order except the few moved ones, and the output is
 * one sequential pass: no index map read at random (for 10^6 points that
 * map cost 0.6 s in cache misses). Consumes the structure's tetrahedra. */
static thx_status dt_output(dt_t *m, int32_t **tets, int32_t **nbrs, size_t *n_tets, size_t *n_hull)
{
    size_t hull = 0;
    for (size_t t = 0; t < m->nt; t++) {
        const tet_t *tt = &m->t[t];
        if (tt->v[0] == DEAD || !is_ghost(tt)) continue;
        hull++;
        int32_t code = tt->n[inf_slot(tt)];
        m->t[code >> 2].n[code & 3] = -1;
    }
    size_t lo = 0, hi = m->nt;
    for (;;) {
        while (lo < hi && m->t[lo].v[0] != DEAD && !is_ghost(&m->t[lo])) lo++;
        while (hi > lo && (m->t[hi - 1].v[0] == DEAD || is_ghost(&m->t[hi - 1]))) hi--;
        if (lo >= hi) break;
        /* lo < hi - 1: slot lo is free or a ghost, hi - 1 is solid */
        m->t[lo] = m->t[hi - 1];
        for (int k = 0; k < 4; k++) {
            int32_t code = m->t[lo].n[k];
            if (code >= 0) m->t[code >> 2].n[code & 3] = (int32_t)(lo << 2) | k;
        }
        hi--;
        lo++;
    }
    m->nt = lo;
    size_t cnt = lo;
    int32_t *nb = nbrs ? thx_malloc(m->ctx, 4 * (cnt ? cnt : 1) * sizeof *nb) : NULL;
    if (nbrs && !nb) return THX_ENOMEM;
    if (nb)
        for (size_t t = 0; t < cnt; t++)
            for (int k = 0; k < 4; k++) {
                int32_t code = m->t[t].n[k];
                nb[4 * t + k] = code < 0 ? -1 : code >> 2;
            }
    /* The vertices are written over the tetrahedron array itself (entry t
     * goes to bytes [16t, 16t + 16), at or before where it was read), which
     * is then shrunk: the output takes no fresh memory (for 10^6 points,
     * 108 MB less to fault in and zero). */
    int32_t *out = (int32_t *)m->t;
    for (size_t t = 0; t < cnt; t++) {
        int32_t v[4];
        memcpy(v, m->t[t].v, sizeof v);
        for (int k = 0; k < 4; k++) out[4 * t + k] = m->orig[v[k]];
    }
    int32_t *shrunk = realloc(out, 4 * (cnt ? cnt : 1) * sizeof *out);
    if (shrunk) out = shrunk; /* a failed shrink keeps the larger block */
    m->t = NULL;
    m->nt = m->tcap = 0;
    *tets = out;
    if (nbrs) *nbrs = nb;
    *n_tets = cnt;
    if (n_hull) *n_hull = hull;
    return THX_OK;
}

thx_status thx_delaunay3d(thx_ctx *ctx, const double *xyz, size_t n, int32_t **tets, int32_t **nbrs,
                          size_t *n_tets, thx_delaunay_stats *stats)
{
    *tets = NULL;
    if (nbrs) *nbrs = NULL;
    *n_tets = 0;
    if (stats) memset(stats, 0, sizeof *stats);
    dt_t m;
    memset(&m, 0, sizeof m);
    double ts = 0, ti = 0;
    thx_status st = dt_build(ctx, xyz, n, &m, &ts, &ti);
    if (st == THX_OK) {
        double t_inserted = thx_wtime();
        size_t hull = 0;
        st = dt_output(&m, tets, nbrs, n_tets, &hull);
        if (st == THX_OK && stats) {
            stats->n_points = n;
            stats->n_tets = *n_tets;
            stats->n_hull_faces = hull;
            stats->walk_steps = m.walk_steps;
            stats->cavity_tets = m.cavity_tets;
            stats->n_degenerate = m.n_degenerate;
            stats->t_sort = ts;
            stats->t_insert = ti;
            stats->t_output = thx_wtime() - t_inserted;
        }
    }
    dt_free(&m);
    return st;
}

/* ---- incremental use (thx_dt) ------------------------------------------------- */

struct thx_dt {
    dt_t m;
    size_t n_input;    /* points given to thx_dt_create */
    int32_t (*quad)[4]; /* thx_dt_star's answer */
    size_t quad_cap;
};

thx_status thx_dt_create(thx_ctx *ctx, const double *xyz, size_t n, thx_dt **out)
{
    *out = NULL;
    thx_dt *d = thx_calloc(ctx, 1, sizeof *d);
    if (!d) return THX_ENOMEM;
    thx_status st = dt_build(ctx, xyz, n, &d->m, NULL, NULL);
    if (st == THX_OK) {
        d->n_input = n;
        dt_t *m = &d->m;
        m->rank = thx_malloc(ctx, n * sizeof *m->rank);
        m->vt = thx_malloc(ctx, n * sizeof *m->vt);
        if (!m->rank || !m->vt) st = THX_ENOMEM;
        else {
            for (size_t k = 0; k < n; k++) m->rank[m->orig[k]] = (int32_t)k;
            for (size_t t = 0; t < m->nt; t++) {
                const tet_t *tt = &m->t[t];
                if (tt->v[0] == DEAD) continue;
                for (int k = 0; k < 4; k++)
                    if (tt->v[k] >= 0) m->vt[tt->v[k]] = (int32_t)t;
            }
        }
    }
    if (st != THX_OK) {
        dt_free(&d->m);
        free(d);
        return st;
    }
    *out = d;
    return THX_OK;
}

void thx_dt_destroy(thx_dt **d)
{
    if (!d || !*d) return;
    dt_free(&(*d)->m);
    free((*d)->quad);
    free(*d);
    *d = NULL;
}

size_t thx_dt_n_points(const thx_dt *d) { return (size_t)d->m.np; }

const double *thx_dt_point(const thx_dt *d, int32_t i) { return P(&d->m, d->m.rank[i]); }

thx_status thx_dt_insert(thx_dt *d, const double p[3], int32_t near, int32_t *index)
{
    dt_t *m = &d->m;
    if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2]))
        return thx_error(m->ctx, THX_EINPUT, "delaunay3d: inserted point has a non-finite coordinate");
    if ((size_t)m->np >= MAX_POINTS) return thx_error(m->ctx, THX_EINPUT, "delaunay3d: too many points");
    if ((size_t)m->np == m->pcap) {
        size_t cap = m->pcap + m->pcap / 2 + 16;
        double *np_ = thx_realloc(m->ctx, m->p, 3 * cap * sizeof *np_);
        if (!np_) return THX_ENOMEM;
        m->p = np_;
        int32_t *o = thx_realloc(m->ctx, m->orig, cap * sizeof *o);
        if (!o) return THX_ENOMEM;
        m->orig = o;
        int32_t *r = thx_realloc(m->ctx, m->rank, cap * sizeof *r);
        if (!r) return THX_ENOMEM;
        m->rank = r;
        int32_t *v = thx_realloc(m->ctx, m->vt, cap * sizeof *v);
        if (!v) return THX_ENOMEM;
        m->vt = v;
        uint8_t *vl = thx_realloc(m->ctx, m->vloc, cap * sizeof *vl);
        if (!vl) return THX_ENOMEM;
        memset(vl + m->pcap, 0, (cap - m->pcap) * sizeof *vl);
        m->vloc = vl;
        m->pcap = cap;
    }
    int32_t k = m->np;
    memcpy(m->p + 3 * (size_t)k, p, 3 * sizeof *p);
    m->orig[k] = k; /* appended points keep their insertion rank as index */
    m->rank[k] = k;
    if (near >= 0 && near < m->np) m->last = m->vt[m->rank[near]];
    m->np++;
    thx_status st = insert_point(m, k);
    if (st != THX_OK) {
        m->np--; /* the structure is unchanged when the point is refused (duplicate) */
        return st;
    }
    *index = k;
    return THX_OK;
}

/* The tetrahedra around input point a (face-connected search of its star), their
 * vertex quads (input indices, INF = -1) in d->quad; returns the count, -1 on no memory. */
int thx_dt_star(thx_dt *d, int32_t a, const int32_t (**quads)[4])
{
    dt_t *m = &d->m;
    int32_t ra = m->rank[a];
    if (!m->mark && !(m->mark = thx_calloc(m->ctx, m->tcap, sizeof *m->mark))) return -1;
    if (m->stamp >= UINT32_MAX - 4) {
        memset(m->mark, 0, m->tcap * sizeof *m->mark);
        m->stamp = 0;
    }
    m->stamp += 2;
    const uint32_t st = m->stamp;
    size_t ns = 0, count = 0;
    int32_t t0 = m->vt[ra];
    if (push_i32(m, &m->sstack, &m->sstack_cap, ns++, t0) != THX_OK) return -1;
    m->mark[t0] = st;
    while (ns > 0) {
        int32_t c = m->sstack[--ns];
        if (count >= d->quad_cap && thx_grow(m->ctx, (void **)&d->quad, &d->quad_cap, count + 1, sizeof *d->quad) != THX_OK)
            return -1;
        const tet_t *tc = &m->t[c];
        for (int k = 0; k < 4; k++) d->quad[count][k] = tc->v[k] < 0 ? -1 : m->orig[tc->v[k]];
        count++;
        for (int i = 0; i < 4; i++) {
            if (tc->v[i] == ra) continue; /* the face opposite a does not hold a */
            int32_t o = tc->n[i] >> 2;
            if (m->mark[o] == st) continue;
            m->mark[o] = st;
            if (push_i32(m, &m->sstack, &m->sstack_cap, ns++, o) != THX_OK) return -1;
        }
    }
    *quads = (const int32_t (*)[4])d->quad;
    return (int)count;
}

thx_status thx_dt_insert_checked(thx_dt *d, const double p[3], int32_t near,
                                 int (*reject)(void *user, int32_t a, int32_t b, int32_t c, int interior), void *user,
                                 int32_t *index,
                                 int32_t face[3])
{
    dt_t *m = &d->m;
    m->reject = reject;
    m->reject_user = user;
    m->rejected = 0;
    int32_t idx = -1;
    thx_status st = thx_dt_insert(d, p, near, &idx);
    m->reject = NULL;
    if (st != THX_OK) return st;
    if (m->rejected) {
        m->np--; /* the point was appended, nothing else changed */
        *index = -1;
        memcpy(face, m->rejected_face, sizeof m->rejected_face);
        return THX_OK;
    }
    *index = idx;
    return THX_OK;
}

thx_status thx_dt_tets(thx_dt *d, int32_t **quads, size_t *n)
{
    dt_t *m = &d->m;
    *quads = NULL;
    *n = 0;
    size_t cnt = 0;
    for (size_t t = 0; t < m->nt; t++) cnt += m->t[t].v[0] != DEAD && !is_ghost(&m->t[t]);
    int32_t *q = thx_malloc(m->ctx, 4 * (cnt ? cnt : 1) * sizeof *q);
    if (!q) return THX_ENOMEM;
    size_t k = 0;
    for (size_t t = 0; t < m->nt; t++) {
        const tet_t *tt = &m->t[t];
        if (tt->v[0] == DEAD || is_ghost(tt)) continue;
        for (int j = 0; j < 4; j++) q[4 * k + j] = m->orig[tt->v[j]];
        k++;
    }
    *quads = q;
    *n = cnt;
    return THX_OK;
}

int thx_dt_has_tet(thx_dt *d, const int32_t q[4])
{
    const int32_t (*s)[4];
    int n = thx_dt_star(d, q[0], &s);
    for (int i = 0; i < n; i++) {
        int hits = 0;
        for (int k = 0; k < 4; k++)
            for (int j = 1; j < 4; j++) hits += s[i][k] == q[j];
        if (hits == 3) return 1;
    }
    return 0;
}

int thx_dt_new_tets(thx_dt *d, const int32_t (**quads)[4])
{
    dt_t *m = &d->m;
    size_t n = m->last_nb;
    if (n > d->quad_cap && thx_grow(m->ctx, (void **)&d->quad, &d->quad_cap, n, sizeof *d->quad) != THX_OK) return -1;
    for (size_t k = 0; k < n; k++) {
        for (int j = 0; j < 3; j++) d->quad[k][j] = m->bnd[k].f[j] < 0 ? -1 : m->orig[m->bnd[k].f[j]];
        d->quad[k][3] = m->orig[m->last_p];
    }
    *quads = (const int32_t (*)[4])d->quad;
    return (int)n;
}

int thx_dt_has_edge(thx_dt *d, int32_t a, int32_t b)
{
    const int32_t (*q)[4];
    int n = thx_dt_star(d, a, &q);
    for (int i = 0; i < n; i++)
        for (int k = 0; k < 4; k++)
            if (q[i][k] == b) return 1;
    return 0;
}

int thx_dt_has_face(thx_dt *d, int32_t a, int32_t b, int32_t c)
{
    const int32_t (*q)[4];
    int n = thx_dt_star(d, a, &q);
    for (int i = 0; i < n; i++) {
        int hb = 0, hc = 0;
        for (int k = 0; k < 4; k++) { hb |= q[i][k] == b; hc |= q[i][k] == c; }
        if (hb && hc) return 1;
    }
    return 0;
}

thx_status thx_dt_finish(thx_dt **d, int32_t **tets, int32_t **nbrs, size_t *n_tets)
{
    *tets = NULL;
    if (nbrs) *nbrs = NULL;
    *n_tets = 0;
    thx_status st = dt_output(&(*d)->m, tets, nbrs, n_tets, NULL);
    thx_dt_destroy(d);
    return st;
}
