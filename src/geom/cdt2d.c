/*
 * 2D constrained Delaunay triangulation (see thorax/geom/cdt.h).
 *
 * Method.
 *  1. Delaunay triangulation by incremental Bowyer–Watson insertion. Points
 *     are inserted in Hilbert-curve order; each is located by a visibility
 *     walk from the last created triangle (short walks thanks to the order).
 *     The region outside the convex hull is covered by "ghost" triangles that
 *     share a vertex at infinity (INF), so hull growth is an ordinary cavity:
 *     a ghost (u, v, INF) (hull edge u->v, the hull interior to its right) is
 *     in conflict with p iff orient2d(u, v, p) > 0, or p lies on the open
 *     segment uv. A solid triangle is in conflict iff p is strictly inside
 *     its circumcircle. With exact predicates the cavity is star-shaped from
 *     p and the result is a valid Delaunay triangulation even with collinear
 *     and cocircular input (points on a hull edge become hull vertices).
 *  2. Constraint recovery by edge flips (Sloan 1993): the edges crossed by a
 *     segment are collected by walking from one end to the other (this walk
 *     detects segments through input points and crossings of constraints);
 *     each is flipped when its quadrilateral is strictly convex, re-queued
 *     while it still crosses. Then the edges created are made constrained
 *     Delaunay again by Lawson flips that never flip a constrained edge.
 *
 * Triangle storage: v[3] counterclockwise (ghosts: (u, v, INF) in cyclic
 * order), n[i] = triangle across the edge opposite v[i], cs[i] = id of the
 * constraint segment on that edge or -1. Invariant: n is symmetric, and every
 * triangle (solid or ghost) has three neighbours.
 */
#include "thorax/geom/cdt.h"
#include "thorax/geom/predicates.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define INF (-1)

typedef struct {
    int32_t v[3];
    int32_t n[3];
    int32_t cs[3];
} tri_t;

typedef struct {
    int32_t e0, e1, out; /* boundary edge e0->e1 of the cavity, triangle beyond it */
} bedge;

typedef struct {
    thx_ctx *ctx;
    const thx_vec2 *p;
    int32_t np;
    tri_t *t;
    size_t nt, tcap;
    int32_t *v2t;        /* a triangle incident to each vertex (np) */
    uint32_t *mark;      /* cavity stamps, per triangle (tcap) */
    size_t mcap;
    uint32_t stamp;
    int32_t *start_of;   /* np + 1 (INF at np): new triangle starting at a vertex */
    int32_t last;        /* walk start */
    uint64_t rnd;
    /* scratch */
    int32_t *stack, *cav;
    size_t stack_cap, cav_cap;
    bedge *bnd;
    size_t bnd_cap;
    int32_t *eq;         /* edge queue (pairs) */
    size_t eq_cap;
} cdt_t;

static inline int next3(int i) { return i == 2 ? 0 : i + 1; }
static inline int prev3(int i) { return i == 0 ? 2 : i - 1; }

/* The predicates are called millions of times: their floating-point filters
 * are repeated inline here (same error bounds as predicates.c: 5u and 12u
 * times the permanent, u = 2^-53), and the exact predicates are called only
 * when the filter cannot decide. */
static inline double orient(const cdt_t *m, int32_t a, int32_t b, int32_t c)
{
    const thx_vec2 A = m->p[a], B = m->p[b], C = m->p[c];
    double l = (A.x - C.x) * (B.y - C.y), r = (A.y - C.y) * (B.x - C.x);
    double det = l - r, bound = (5.0 / 9007199254740992.0) * (fabs(l) + fabs(r));
    if (det > bound || -det > bound) return det;
    const double a2[2] = {A.x, A.y}, b2[2] = {B.x, B.y}, c2[2] = {C.x, C.y};
    return thx_orient2d(a2, b2, c2);
}

static inline double incircle(const cdt_t *m, int32_t a, int32_t b, int32_t c, int32_t d)
{
    const thx_vec2 A = m->p[a], B = m->p[b], C = m->p[c], D = m->p[d];
    double adx = A.x - D.x, ady = A.y - D.y, bdx = B.x - D.x, bdy = B.y - D.y, cdx = C.x - D.x, cdy = C.y - D.y;
    double bc1 = bdx * cdy, bc2 = cdx * bdy, ca1 = cdx * ady, ca2 = adx * cdy, ab1 = adx * bdy, ab2 = bdx * ady;
    double al = adx * adx + ady * ady, bl = bdx * bdx + bdy * bdy, cl = cdx * cdx + cdy * cdy;
    double det = al * (bc1 - bc2) + bl * (ca1 - ca2) + cl * (ab1 - ab2);
    double perm = (fabs(bc1) + fabs(bc2)) * al + (fabs(ca1) + fabs(ca2)) * bl + (fabs(ab1) + fabs(ab2)) * cl;
    double bound = (12.0 / 9007199254740992.0) * perm;
    if (det > bound || -det > bound) return det;
    const double a2[2] = {A.x, A.y}, b2[2] = {B.x, B.y}, c2[2] = {C.x, C.y}, d2[2] = {D.x, D.y};
    return thx_incircle(a2, b2, c2, d2);
}

static inline int is_ghost(const tri_t *t) { return t->v[0] == INF || t->v[1] == INF || t->v[2] == INF; }

/* p strictly between u and v, given that u, v, p are collinear (exact
 * coordinate comparisons along a non-constant axis). */
static int strictly_between(const cdt_t *m, int32_t u, int32_t v, int32_t p)
{
    thx_vec2 a = m->p[u], b = m->p[v], q = m->p[p];
    if (a.x != b.x) return (q.x > a.x && q.x < b.x) || (q.x < a.x && q.x > b.x);
    return (q.y > a.y && q.y < b.y) || (q.y < a.y && q.y > b.y);
}

static thx_status tri_new(cdt_t *m, int32_t *out)
{
    if (m->nt == m->tcap) {
        size_t cap = m->tcap;
        THX_CHECK(thx_grow(m->ctx, (void **)&m->t, &cap, m->nt + 1, sizeof *m->t));
        m->tcap = cap;
    }
    if (m->mcap < m->tcap) {
        uint32_t *mk = thx_realloc(m->ctx, m->mark, m->tcap * sizeof *mk);
        if (!mk) return THX_ENOMEM;
        memset(mk + m->mcap, 0, (m->tcap - m->mcap) * sizeof *mk);
        m->mark = mk;
        m->mcap = m->tcap;
    }
    *out = (int32_t)m->nt++;
    return THX_OK;
}

static void set_v2t(cdt_t *m, int32_t ti)
{
    for (int k = 0; k < 3; k++)
        if (m->t[ti].v[k] != INF) m->v2t[m->t[ti].v[k]] = ti;
}

/* Index in triangle t of the vertex that is neither a nor b. */
static inline int opposite_index(const tri_t *t, int32_t a, int32_t b)
{
    for (int k = 0; k < 3; k++)
        if (t->v[k] != a && t->v[k] != b) return k;
    return -1;
}

/* Ghost (u, v, INF) conflict test. */
static int ghost_conflict(const cdt_t *m, const tri_t *t, int32_t pi)
{
    int k = t->v[0] == INF ? 0 : (t->v[1] == INF ? 1 : 2);
    int32_t u = t->v[next3(k)], v = t->v[prev3(k)];
    double o = orient(m, u, v, pi);
    if (o > 0) return 1;
    if (o < 0) return 0;
    return strictly_between(m, u, v, pi);
}

static int in_conflict(const cdt_t *m, int32_t ti, int32_t pi)
{
    const tri_t *t = &m->t[ti];
    if (is_ghost(t)) return ghost_conflict(m, t, pi);
    return incircle(m, t->v[0], t->v[1], t->v[2], pi) > 0;
}

/* Visibility walk to a triangle in conflict with point pi: the solid triangle
 * containing it (closed), or a ghost whose hull edge it lies beyond. Sets
 * *dup to the vertex pi coincides with, else -1. */
static int32_t locate(cdt_t *m, int32_t pi, int32_t *dup)
{
    int32_t ti = m->last;
    *dup = -1;
    if (is_ghost(&m->t[ti])) {
        int k = m->t[ti].v[0] == INF ? 0 : (m->t[ti].v[1] == INF ? 1 : 2);
        ti = m->t[ti].n[k];
    }
    thx_vec2 p = m->p[pi];
    for (;;) {
        const tri_t *t = &m->t[ti];
        if (is_ghost(t)) return ti;
        /* start at a pseudo-random edge so that the walk cannot cycle */
        m->rnd = m->rnd * 6364136223846793005ull + 1442695040888963407ull;
        int r = (int)((m->rnd >> 33) % 3), moved = 0;
        for (int s = 0; s < 3; s++) {
            int i = (r + s) % 3;
            if (orient(m, t->v[next3(i)], t->v[prev3(i)], pi) < 0) {
                ti = t->n[i];
                moved = 1;
                break;
            }
        }
        if (!moved) {
            for (int k = 0; k < 3; k++) {
                thx_vec2 q = m->p[t->v[k]];
                if (q.x == p.x && q.y == p.y) *dup = t->v[k];
            }
            return ti;
        }
    }
}

static thx_status push_i32(cdt_t *m, int32_t **arr, size_t *cap, size_t n, int32_t v)
{
    if (n >= *cap) THX_CHECK(thx_grow(m->ctx, (void **)arr, cap, n + 1, sizeof **arr));
    (*arr)[n] = v;
    return THX_OK;
}

/* Bowyer–Watson insertion of point pi. */
static thx_status insert_point(cdt_t *m, int32_t pi)
{
    int32_t dup;
    int32_t t0 = locate(m, pi, &dup);
    if (dup >= 0)
        return thx_error(m->ctx, THX_EGEOM, "cdt2d: points %d and %d coincide (%.17g, %.17g)", (int)dup, (int)pi,
                         m->p[pi].x, m->p[pi].y);
    uint32_t st = ++m->stamp;
    size_t ns = 0, nc = 0, nb = 0;
    THX_CHECK(push_i32(m, &m->stack, &m->stack_cap, ns++, t0));
    THX_CHECK(push_i32(m, &m->cav, &m->cav_cap, nc++, t0));
    m->mark[t0] = st;
    while (ns > 0) {
        int32_t c = m->stack[--ns];
        for (int i = 0; i < 3; i++) {
            int32_t o = m->t[c].n[i];
            if (m->mark[o] == st) continue;
            if (in_conflict(m, o, pi)) {
                m->mark[o] = st;
                THX_CHECK(push_i32(m, &m->stack, &m->stack_cap, ns++, o));
                THX_CHECK(push_i32(m, &m->cav, &m->cav_cap, nc++, o));
            } else {
                if (nb >= m->bnd_cap) THX_CHECK(thx_grow(m->ctx, (void **)&m->bnd, &m->bnd_cap, nb + 1, sizeof *m->bnd));
                m->bnd[nb].e0 = m->t[c].v[next3(i)];
                m->bnd[nb].e1 = m->t[c].v[prev3(i)];
                m->bnd[nb].out = o;
                nb++;
            }
        }
    }
    /* One new triangle per boundary edge (nb = nc + 2); reuse cavity slots. */
    for (size_t k = 0; k < nb; k++) {
        int32_t ti;
        if (k < nc) ti = m->cav[k];
        else THX_CHECK(tri_new(m, &ti));
        bedge b = m->bnd[k];
        tri_t *t = &m->t[ti];
        t->v[0] = b.e0; t->v[1] = b.e1; t->v[2] = pi;
        t->n[2] = b.out;
        t->cs[0] = t->cs[1] = -1;
        /* the boundary edge keeps its constraint mark (from the outside triangle) */
        tri_t *o = &m->t[b.out];
        int j = opposite_index(o, b.e0, b.e1);
        o->n[j] = ti;
        t->cs[2] = o->cs[j];
        m->start_of[b.e0 == INF ? m->np : b.e0] = ti;
        m->mark[ti] = 0;
        set_v2t(m, ti);
        m->bnd[k].out = ti; /* reuse the record: new triangle id */
    }
    for (size_t k = 0; k < nb; k++) {
        int32_t ti = m->bnd[k].out;
        int32_t e1 = m->t[ti].v[1];
        int32_t mi = m->start_of[e1 == INF ? m->np : e1];
        m->t[ti].n[0] = mi;
        m->t[mi].n[1] = ti;
    }
    m->last = m->bnd[0].out;
    return THX_OK;
}

/* ---- Hilbert order ------------------------------------------------------ */

/* Index of (x, y) along the Hilbert curve filling a side x side grid
 * (side a power of two). */
static uint32_t hilbert_d(uint32_t side, uint32_t x, uint32_t y)
{
    uint32_t d = 0;
    for (uint32_t s = side / 2; s > 0; s /= 2) {
        uint32_t rx = (x & s) > 0, ry = (y & s) > 0;
        d += s * s * ((3 * rx) ^ ry);
        if (ry == 0) { /* rotate the sub-square so the curve stays continuous */
            if (rx == 1) {
                x = side - 1 - x;
                y = side - 1 - y;
            }
            uint32_t t = x;
            x = y;
            y = t;
        }
    }
    return d;
}

/* Stable LSD radix sort of a[0..n) by the `key_bits` bits above bit 32
 * (11-bit digits); tmp holds n elements. Ties keep the index order. */
static void radix_sort_hi(uint64_t *a, uint64_t *tmp, size_t n, uint32_t key_bits)
{
    size_t count[2048];
    for (uint32_t shift = 0; shift < key_bits; shift += 11) {
        memset(count, 0, sizeof count);
        for (size_t i = 0; i < n; i++) count[(a[i] >> (32 + shift)) & 2047]++;
        size_t sum = 0;
        for (int d = 0; d < 2048; d++) { size_t c = count[d]; count[d] = sum; sum += c; }
        for (size_t i = 0; i < n; i++) tmp[count[(a[i] >> (32 + shift)) & 2047]++] = a[i];
        memcpy(a, tmp, n * sizeof *a);
    }
}

/* ---- constrained edges ---------------------------------------------------- */

/* Finds the triangle t with edge a->b (a, b in counterclockwise order of t);
 * *i = index of the vertex opposite the edge. Returns 0 if the edge is absent. */
static int find_edge(const cdt_t *m, int32_t a, int32_t b, int32_t *tout, int *iout)
{
    int32_t start = m->v2t[a], ti = start;
    do {
        const tri_t *t = &m->t[ti];
        int k = t->v[0] == a ? 0 : (t->v[1] == a ? 1 : 2);
        if (t->v[next3(k)] == b) { *tout = ti; *iout = prev3(k); return 1; }
        /* rotate clockwise around a: across the edge (a, v[k+1]) */
        ti = t->n[prev3(k)];
    } while (ti != start);
    return 0;
}

static void flip(cdt_t *m, int32_t ti, int i)
{
    tri_t *t = &m->t[ti];
    int32_t ni = t->n[i];
    tri_t *u = &m->t[ni];
    int32_t x = t->v[i], p = t->v[next3(i)], q = t->v[prev3(i)];
    int j = opposite_index(u, p, q);
    int32_t r = u->v[j];
    int32_t A = t->n[next3(i)], cA = t->cs[next3(i)]; /* edge (q, x) */
    int32_t B = t->n[prev3(i)], cB = t->cs[prev3(i)]; /* edge (x, p) */
    int32_t C = u->n[next3(j)], cC = u->cs[next3(j)]; /* edge (p, r): opposite q in u */
    int32_t D = u->n[prev3(j)], cD = u->cs[prev3(j)]; /* edge (r, q) */
    if (u->v[next3(j)] != q) { /* u = (r, q, p) always; guard the invariant */
        C = u->n[prev3(j)]; cC = u->cs[prev3(j)];
        D = u->n[next3(j)]; cD = u->cs[next3(j)];
    }
    t->v[0] = x; t->v[1] = p; t->v[2] = r;
    t->n[0] = C; t->n[1] = ni; t->n[2] = B;
    t->cs[0] = cC; t->cs[1] = -1; t->cs[2] = cB;
    u->v[0] = r; u->v[1] = q; u->v[2] = x;
    u->n[0] = A; u->n[1] = ti; u->n[2] = D;
    u->cs[0] = cA; u->cs[1] = -1; u->cs[2] = cD;
    tri_t *tc = &m->t[C];
    for (int k = 0; k < 3; k++)
        if (tc->n[k] == ni) { tc->n[k] = ti; break; }
    tri_t *ta = &m->t[A];
    for (int k = 0; k < 3; k++)
        if (ta->n[k] == ti) { ta->n[k] = ni; break; }
    set_v2t(m, ti);
    set_v2t(m, ni);
}

static int sgn(double v) { return (v > 0) - (v < 0); }

/* Segment (x, y) crosses segment (a, b) at a point interior to both. */
static int proper_cross(const cdt_t *m, int32_t a, int32_t b, int32_t x, int32_t y)
{
    if (x == a || x == b || y == a || y == b) return 0;
    int s1 = sgn(orient(m, a, b, x)), s2 = sgn(orient(m, a, b, y));
    if (s1 * s2 >= 0) return 0;
    int s3 = sgn(orient(m, x, y, a)), s4 = sgn(orient(m, x, y, b));
    return s3 * s4 < 0;
}

static thx_status seg_error_through(cdt_t *m, size_t k, int32_t a, int32_t b, int32_t v)
{
    return thx_error(m->ctx, THX_EGEOM, "cdt2d: segment %zu (%d-%d) passes through point %d (%.17g, %.17g)", k,
                     (int)a, (int)b, (int)v, m->p[v].x, m->p[v].y);
}

/* Lawson flips from the queued edges, never flipping constrained ones. */
static thx_status restore_delaunay(cdt_t *m, size_t nq)
{
    size_t guard = 0;
    while (nq > 0) {
        nq -= 2;
        int32_t u = m->eq[nq], w = m->eq[nq + 1];
        int32_t ti;
        int i;
        if (!find_edge(m, u, w, &ti, &i)) continue; /* flipped away meanwhile */
        tri_t *t = &m->t[ti];
        if (t->cs[i] >= 0 || is_ghost(t)) continue;
        int32_t ni = t->n[i];
        tri_t *o = &m->t[ni];
        if (is_ghost(o)) continue;
        int32_t r = o->v[opposite_index(o, u, w)];
        if (incircle(m, t->v[0], t->v[1], t->v[2], r) <= 0) continue;
        int32_t x = t->v[i];
        flip(m, ti, i);
        if (++guard > 100000000u) return thx_error(m->ctx, THX_EINTERNAL, "cdt2d: Delaunay restoration does not end");
        /* the four outer edges of the quadrilateral x, u, r, w */
        int32_t outer[8] = {x, u, u, r, r, w, w, x};
        for (int k = 0; k < 4; k++) {
            if (nq + 2 > m->eq_cap) THX_CHECK(thx_grow(m->ctx, (void **)&m->eq, &m->eq_cap, nq + 2, sizeof *m->eq));
            m->eq[nq++] = outer[2 * k];
            m->eq[nq++] = outer[2 * k + 1];
        }
    }
    return THX_OK;
}

static thx_status insert_segment(cdt_t *m, size_t k, int32_t a, int32_t b)
{
    int32_t ti;
    int ei;
    if (find_edge(m, a, b, &ti, &ei) || find_edge(m, b, a, &ti, &ei)) {
        tri_t *t = &m->t[ti];
        if (t->cs[ei] < 0) {
            t->cs[ei] = (int32_t)k;
            tri_t *o = &m->t[t->n[ei]];
            o->cs[opposite_index(o, t->v[next3(ei)], t->v[prev3(ei)])] = (int32_t)k;
        }
        return THX_OK;
    }
    /* Find the triangle at a whose wedge contains the direction of b. */
    thx_vec2 pa = m->p[a], pb = m->p[b];
    int32_t start = m->v2t[a], cur = start, R = -1, L = -1;
    do {
        const tri_t *t = &m->t[cur];
        int kk = t->v[0] == a ? 0 : (t->v[1] == a ? 1 : 2);
        int32_t u = t->v[next3(kk)], w = t->v[prev3(kk)];
        if (!is_ghost(t)) {
            double ou = orient(m, a, b, u), ow = orient(m, a, b, w);
            for (int s = 0; s < 2; s++) {
                int32_t v = s ? w : u;
                double ov = s ? ow : ou;
                if (ov == 0) {
                    thx_vec2 q = m->p[v];
                    int same = (pb.x != pa.x) ? ((q.x > pa.x) == (pb.x > pa.x)) : ((q.y > pa.y) == (pb.y > pa.y));
                    if (same) return seg_error_through(m, k, a, b, v);
                }
            }
            if (ou < 0 && ow > 0) { R = u; L = w; ti = cur; break; }
        }
        cur = t->n[prev3(kk)];
    } while (cur != start);
    if (R < 0) return thx_error(m->ctx, THX_EINTERNAL, "cdt2d: segment %zu (%d-%d): no start triangle", k, (int)a, (int)b);
    /* Walk to b collecting crossed edges. */
    size_t nq = 0;
    for (;;) {
        tri_t *t = &m->t[ti];
        int i = opposite_index(t, R, L);
        if (t->cs[i] >= 0) {
            int32_t o = t->cs[i];
            return thx_error(m->ctx, THX_EGEOM, "cdt2d: segment %zu (%d-%d) crosses segment %d (edge %d-%d)", k,
                             (int)a, (int)b, (int)o, (int)R, (int)L);
        }
        if (nq + 2 > m->eq_cap) THX_CHECK(thx_grow(m->ctx, (void **)&m->eq, &m->eq_cap, nq + 2, sizeof *m->eq));
        m->eq[nq++] = R;
        m->eq[nq++] = L;
        int32_t ni = t->n[i];
        tri_t *o = &m->t[ni];
        if (is_ghost(o)) return thx_error(m->ctx, THX_EINTERNAL, "cdt2d: segment %zu leaves the hull", k);
        int32_t x = o->v[opposite_index(o, R, L)];
        if (x == b) break;
        double ox = orient(m, a, b, x);
        if (ox == 0) return seg_error_through(m, k, a, b, x);
        if (ox < 0) R = x;
        else L = x;
        ti = ni;
    }
    /* Sloan's flipping: a FIFO of crossing edges (pairs in eq[head..nq)); the
     * edges created that no longer cross go to `fresh` for the Delaunay pass. */
    size_t head = 0, iter = 0, limit = 64 * (nq / 2 + 4) * (nq / 2 + 4);
    int32_t *fresh = NULL;
    size_t nfresh = 0, fresh_cap = 0;
    thx_status st = THX_OK;
    while (head < nq) {
        int32_t u = m->eq[head], w = m->eq[head + 1];
        head += 2;
        if (++iter > limit) { st = thx_error(m->ctx, THX_EINTERNAL, "cdt2d: segment %zu: flipping does not end", k); goto done; }
        int32_t t1;
        int i;
        if (!find_edge(m, u, w, &t1, &i)) { st = thx_error(m->ctx, THX_EINTERNAL, "cdt2d: lost edge %d-%d", (int)u, (int)w); goto done; }
        tri_t *t = &m->t[t1];
        tri_t *o = &m->t[t->n[i]];
        int32_t x = t->v[i], r = o->v[opposite_index(o, u, w)];
        /* t = (x, u, w), o = (r, w, u): the flip is valid iff (x, u, r) and (r, w, x) are strictly CCW */
        int convex = orient(m, x, u, r) > 0 && orient(m, r, w, x) > 0;
        if (head > 1024 && head * 2 > nq) { /* compact the queue */
            memmove(m->eq, m->eq + head, (nq - head) * sizeof *m->eq);
            nq -= head;
            head = 0;
        }
        if (!convex) {
            if (nq + 2 > m->eq_cap) THX_TRY(thx_grow(m->ctx, (void **)&m->eq, &m->eq_cap, nq + 2, sizeof *m->eq));
            m->eq[nq++] = u;
            m->eq[nq++] = w;
            continue;
        }
        flip(m, t1, i);
        if (proper_cross(m, a, b, x, r)) {
            if (nq + 2 > m->eq_cap) THX_TRY(thx_grow(m->ctx, (void **)&m->eq, &m->eq_cap, nq + 2, sizeof *m->eq));
            m->eq[nq++] = x;
            m->eq[nq++] = r;
        } else {
            if (nfresh + 2 > fresh_cap) THX_TRY(thx_grow(m->ctx, (void **)&fresh, &fresh_cap, nfresh + 2, sizeof *fresh));
            fresh[nfresh++] = x;
            fresh[nfresh++] = r;
        }
    }
    if (!find_edge(m, a, b, &ti, &ei) && !find_edge(m, b, a, &ti, &ei)) {
        st = thx_error(m->ctx, THX_EINTERNAL, "cdt2d: segment %zu (%d-%d) not recovered", k, (int)a, (int)b);
        goto done;
    }
    {
        tri_t *t = &m->t[ti];
        t->cs[ei] = (int32_t)k;
        tri_t *o = &m->t[t->n[ei]];
        o->cs[opposite_index(o, t->v[next3(ei)], t->v[prev3(ei)])] = (int32_t)k;
    }
    /* Make the new edges constrained Delaunay. */
    if (nfresh > m->eq_cap) THX_TRY(thx_grow(m->ctx, (void **)&m->eq, &m->eq_cap, nfresh, sizeof *m->eq));
    if (nfresh) memcpy(m->eq, fresh, nfresh * sizeof *fresh);
    st = restore_delaunay(m, nfresh);
done:
    free(fresh);
    return st;
}

/* ---- driver --------------------------------------------------------------- */

static void cdt_free(cdt_t *m)
{
    free(m->t);
    free(m->v2t);
    free(m->mark);
    free(m->start_of);
    free(m->stack);
    free(m->cav);
    free(m->bnd);
    free(m->eq);
}

/* Links the neighbours of a few triangles by brute force (initial setup). */
static void link_brute(cdt_t *m, const int32_t *ids, int cnt)
{
    for (int a = 0; a < cnt; a++)
        for (int i = 0; i < 3; i++) {
            tri_t *t = &m->t[ids[a]];
            int32_t e0 = t->v[next3(i)], e1 = t->v[prev3(i)];
            for (int b = 0; b < cnt; b++) {
                if (b == a) continue;
                tri_t *o = &m->t[ids[b]];
                for (int j = 0; j < 3; j++)
                    if (o->v[next3(j)] == e1 && o->v[prev3(j)] == e0) t->n[i] = ids[b];
            }
        }
}

typedef struct {
    double x, y;
    int32_t i;
} xy_rec;

static int cmp_xy(const void *a, const void *b)
{
    const xy_rec *u = a, *v = b;
    if (u->x != v->x) return u->x < v->x ? -1 : 1;
    if (u->y != v->y) return u->y < v->y ? -1 : 1;
    return (u->i > v->i) - (u->i < v->i);
}

/* Reports coinciding points (used when no triangle could be seeded). */
static thx_status check_duplicates(thx_ctx *ctx, const thx_vec2 *p, size_t n)
{
    xy_rec *r = thx_malloc(ctx, n * sizeof *r);
    if (!r) return THX_ENOMEM;
    for (size_t i = 0; i < n; i++) { r[i].x = p[i].x; r[i].y = p[i].y; r[i].i = (int32_t)i; }
    qsort(r, n, sizeof *r, cmp_xy);
    thx_status st = THX_OK;
    for (size_t i = 1; i < n; i++)
        if (r[i].x == r[i - 1].x && r[i].y == r[i - 1].y) {
            st = thx_error(ctx, THX_EGEOM, "cdt2d: points %d and %d coincide (%.17g, %.17g)", (int)r[i - 1].i,
                           (int)r[i].i, r[i].x, r[i].y);
            break;
        }
    free(r);
    return st;
}

thx_status thx_cdt2d(thx_ctx *ctx, const thx_vec2 *pts, size_t n, const int32_t *segs, size_t n_segs,
                     int32_t **tris, size_t *n_tris)
{
    *tris = NULL;
    *n_tris = 0;
    if (n > (size_t)INT32_MAX / 4) return thx_error(ctx, THX_EINPUT, "cdt2d: too many points (%zu)", n);
    for (size_t i = 0; i < n; i++)
        if (!isfinite(pts[i].x) || !isfinite(pts[i].y))
            return thx_error(ctx, THX_EINPUT, "cdt2d: point %zu has a non-finite coordinate", i);
    for (size_t k = 0; k < n_segs; k++) {
        int32_t a = segs[2 * k], b = segs[2 * k + 1];
        if (a < 0 || b < 0 || (size_t)a >= n || (size_t)b >= n)
            return thx_error(ctx, THX_EINPUT, "cdt2d: segment %zu (%d-%d): index out of range [0, %zu)", k, (int)a,
                             (int)b, n);
        if (a == b) return thx_error(ctx, THX_EINPUT, "cdt2d: segment %zu joins point %d to itself", k, (int)a);
    }
    if (n < 3) return n == 2 ? check_duplicates(ctx, pts, n) : THX_OK;

    cdt_t m;
    memset(&m, 0, sizeof m);
    m.ctx = ctx;
    m.p = pts;
    m.np = (int32_t)n;
    m.rnd = 0x2545F4914F6CDD1Dull;
    thx_status st = THX_OK;
    uint64_t *order = NULL;

    /* Hilbert order on a 2^bits grid over the bounding box, bits ~ log4(n) + 2
     * (finer cells would only order points that are neighbours anyway). */
    order = thx_malloc(ctx, 2 * n * sizeof *order);
    if (!order) return THX_ENOMEM;
    double x0 = pts[0].x, x1 = x0, y0 = pts[0].y, y1 = y0;
    for (size_t i = 1; i < n; i++) {
        x0 = fmin(x0, pts[i].x); x1 = fmax(x1, pts[i].x);
        y0 = fmin(y0, pts[i].y); y1 = fmax(y1, pts[i].y);
    }
    uint32_t bits = 2;
    while (bits < 16 && ((size_t)1 << (2 * (bits - 2))) < n) bits++;
    uint32_t side = 1u << bits;
    double span = fmax(x1 - x0, y1 - y0);
    double sc = span > 0 ? (side - 1) / span : 0.0;
    for (size_t i = 0; i < n; i++) {
        uint32_t qx = (uint32_t)((pts[i].x - x0) * sc), qy = (uint32_t)((pts[i].y - y0) * sc);
        if (qx >= side) qx = side - 1;
        if (qy >= side) qy = side - 1;
        order[i] = ((uint64_t)hilbert_d(side, qx, qy) << 32) | (uint64_t)i;
    }
    radix_sort_hi(order, order + n, n, 2 * bits);

    /* Seed triangle: the first point, the next distinct one, the next not collinear. */
    int32_t s0 = (int32_t)(order[0] & 0xffffffffu), s1 = -1, s2 = -1;
    size_t k1 = 0, k2 = 0;
    for (size_t k = 1; k < n && s1 < 0; k++) {
        int32_t c = (int32_t)(order[k] & 0xffffffffu);
        if (pts[c].x != pts[s0].x || pts[c].y != pts[s0].y) { s1 = c; k1 = k; }
    }
    if (s1 >= 0)
        for (size_t k = 1; k < n && s2 < 0; k++) {
            int32_t c = (int32_t)(order[k] & 0xffffffffu);
            if (k != k1 && orient(&m, s0, s1, c) != 0) { s2 = c; k2 = k; }
        }
    if (s2 < 0) { /* all collinear: no triangle */
        free(order);
        return check_duplicates(ctx, pts, n);
    }
    if (orient(&m, s0, s1, s2) < 0) { int32_t t = s1; s1 = s2; s2 = t; }

    m.v2t = thx_malloc(ctx, n * sizeof *m.v2t);
    m.start_of = thx_malloc(ctx, (n + 1) * sizeof *m.start_of);
    if (!m.v2t || !m.start_of) { st = THX_ENOMEM; goto done; }
    m.tcap = 2 * n + 16;
    m.t = thx_malloc(ctx, m.tcap * sizeof *m.t);
    m.mark = thx_calloc(ctx, m.tcap, sizeof *m.mark);
    m.mcap = m.tcap;
    if (!m.t || !m.mark) { st = THX_ENOMEM; goto done; }
    {
        int32_t ids[4];
        for (int k = 0; k < 4; k++) THX_TRY(tri_new(&m, &ids[k]));
        const int32_t tv[4][3] = {{s0, s1, s2}, {s2, s1, INF}, {s0, s2, INF}, {s1, s0, INF}};
        for (int k = 0; k < 4; k++) {
            for (int j = 0; j < 3; j++) { m.t[ids[k]].v[j] = tv[k][j]; m.t[ids[k]].cs[j] = -1; m.t[ids[k]].n[j] = -1; }
        }
        link_brute(&m, ids, 4);
        for (int k = 0; k < 4; k++) set_v2t(&m, ids[k]);
        m.last = ids[0];
    }
    for (size_t k = 1; k < n; k++) {
        if (k == k1 || k == k2) continue;
        THX_TRY(insert_point(&m, (int32_t)(order[k] & 0xffffffffu)));
    }
    for (size_t k = 0; k < n_segs; k++) THX_TRY(insert_segment(&m, k, segs[2 * k], segs[2 * k + 1]));

    {
        size_t cnt = 0;
        for (size_t t = 0; t < m.nt; t++) cnt += !is_ghost(&m.t[t]);
        int32_t *out = thx_malloc(ctx, 3 * cnt * sizeof *out);
        if (!out) { st = THX_ENOMEM; goto done; }
        size_t w = 0;
        for (size_t t = 0; t < m.nt; t++)
            if (!is_ghost(&m.t[t])) {
                out[w++] = m.t[t].v[0];
                out[w++] = m.t[t].v[1];
                out[w++] = m.t[t].v[2];
            }
        *tris = out;
        *n_tris = cnt;
    }
done:
    free(order);
    cdt_free(&m);
    return st;
}
