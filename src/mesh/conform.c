/*
 * Conforming Delaunay tetrahedralization by Steiner points on the surfaces
 * (see conform.h and docs/decisions.md, "Conformity by Steiner points").
 *
 * Bookkeeping. Every surface edge (a, b), a < b in volume node numbers, keeps
 * the chain of points on it, sorted by the parameter t in [0, 1] along a -> b
 * (its pieces are consecutive pairs). Every surface triangle keeps the points
 * added inside it. The points of a triangle are its corners, the inner points
 * of its three chains and its own inner points; each carries a mask of the
 * triangle's edges it lies on (corner 0 on edges 0 and 2, and so on), so that
 * three points on one edge are never taken for a piece of the triangle.
 *
 * Coverage test (exact, combinatorial): the faces of the tetrahedralization
 * whose three corners are points of the triangle, not all on one edge, are
 * collected from the stars of those points. The triangle is covered iff every
 * piece of its edges is an edge of exactly one of those faces and every other
 * edge of them is an edge of exactly two: the faces then form a disc whose
 * boundary is the triangle's, and faces of one tetrahedralization do not
 * overlap, so their union is the triangle.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mesh/conform.h"
#include "thorax/geom/cdt.h"
#include "thorax/geom/predicates.h"
#define MIN_PIECE 1e-4 /* mm: shorter pieces mean surfaces touching or crossing */
#define MAX_ROUNDS 200
#define MAX_DEPTH 22 /* bits of an edge point's parameter */

typedef struct { double t; int32_t node; } cpt;

typedef struct {
    int32_t a, b;      /* volume nodes, a < b */
    int32_t surf, tri; /* the first triangle holding the edge (for the Steiner record) */
    int32_t t0, t1;    /* the triangles holding the edge (t1 = -1 on an open surface) */
    cpt *pt;           /* the chain, sorted by t, ends included */
    size_t n, cap;
} cedge;

typedef struct {
    int32_t c[3];      /* corners, volume nodes, the surface's orientation */
    int32_t e[3];      /* edge k joins c[k] and c[k+1] */
    int32_t surf, tri;
    int32_t *in;       /* Steiner points inside */
    size_t n_in, cap_in;
    int covered;
} ctri;

/* a point of a triangle: node, edges it lies on (bits 0..2), 2D position */
typedef struct { int32_t node; unsigned mask; double x, y; } tpt;

typedef struct {
    thx_ctx *ctx;
    thx_dt *dt;
    cedge *E;
    size_t nE;
    ctri *T;
    size_t nT;
    thx_steiner *st;
    size_t n_st, cap_st, max_st;
    /* scratch of one triangle */
    tpt *P;
    size_t nP, capP;
    int32_t (*F)[3];
    size_t nF, capF;
    /* which triangles each node lies on (corners: all triangles at it; edge points: the edge's; inner
       points: their own), as linked lists in a pool; and the edge an edge point lies on */
    int32_t *own_head, *node_edge;
    size_t own_cap;
    struct { int32_t tri, next; } *pool;
    size_t n_pool, pool_cap;
    const double *probe; /* the point the refinement tries to insert */
    const conform_quality *Q; /* the options (progress) */
    int32_t *lidx;       /* node -> local index in P, valid where lstamp == lclock */
    uint32_t *lstamp, lclock;
    size_t lcap;
    /* what an insertion may have changed: triangles and edges to look at again */
    unsigned char *tdirty, *edirty;
    int32_t *tlist, *elist;
    size_t ntl, nel;
    /* the refinement's work list: tetrahedra to judge (vertex quads) */
    int refining;
    int32_t (*rq)[4];
    size_t nrq, rq_cap;
    double unit;         /* every coordinate is a multiple of this power of two */
    conform_stats S;
} conformer;

/* x on the binary grid of spacing C->unit (a power of two: exact). */
static double snap(const conformer *C, double x) { return nearbyint(x / C->unit) * C->unit; }

static const double *X(const conformer *C, int32_t i) { return thx_dt_point(C->dt, i); }

static double dist3(const double *a, const double *b)
{
    double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
    return sqrt(dx * dx + dy * dy + dz * dz);
}

/* ---- which triangles a node lies on ---- */

static thx_status own_reserve(conformer *C, size_t n_nodes)
{
    if (n_nodes <= C->own_cap) return THX_OK;
    size_t cap = n_nodes + n_nodes / 2 + 64;
    int32_t *h = thx_realloc(C->ctx, C->own_head, cap * sizeof *h);
    if (!h) return THX_ENOMEM;
    C->own_head = h;
    int32_t *e = thx_realloc(C->ctx, C->node_edge, cap * sizeof *e);
    if (!e) return THX_ENOMEM;
    C->node_edge = e;
    for (size_t i = C->own_cap; i < cap; i++) C->own_head[i] = C->node_edge[i] = -1;
    C->own_cap = cap;
    return THX_OK;
}

static thx_status own_add(conformer *C, int32_t node, int32_t tri)
{
    THX_CHECK(own_reserve(C, (size_t)node + 1));
    if (C->n_pool >= C->pool_cap) THX_CHECK(thx_grow(C->ctx, (void **)&C->pool, &C->pool_cap, C->n_pool + 1, sizeof *C->pool));
    C->pool[C->n_pool].tri = tri;
    C->pool[C->n_pool].next = C->own_head[node];
    C->own_head[node] = (int32_t)C->n_pool++;
    return THX_OK;
}

static int owns(const conformer *C, int32_t node, int32_t tri)
{
    if (node < 0 || (size_t)node >= C->own_cap) return 0;
    for (int32_t k = C->own_head[node]; k >= 0; k = C->pool[k].next)
        if (C->pool[k].tri == tri) return 1;
    return 0;
}

/* The edges of triangle ti that node lies on (bits 0..2). */
static unsigned edge_mask(const conformer *C, size_t ti, int32_t node)
{
    const ctri *T = &C->T[ti];
    if (node == T->c[0]) return 5u;
    if (node == T->c[1]) return 3u;
    if (node == T->c[2]) return 6u;
    int32_t e = (size_t)node < C->own_cap ? C->node_edge[node] : -1;
    for (int k = 0; k < 3; k++)
        if (e >= 0 && T->e[k] == e) return 1u << k;
    return 0;
}

/* The triangle that face (a, b, c) is a piece of, or -1. */
static int32_t face_triangle(const conformer *C, int32_t a, int32_t b, int32_t c)
{
    if (a < 0 || (size_t)a >= C->own_cap) return -1;
    for (int32_t k = C->own_head[a]; k >= 0; k = C->pool[k].next) {
        int32_t t = C->pool[k].tri;
        if (!owns(C, b, t) || !owns(C, c, t)) continue;
        if (edge_mask(C, (size_t)t, a) & edge_mask(C, (size_t)t, b) & edge_mask(C, (size_t)t, c)) continue;
        return t;
    }
    return -1;
}

/* The refinement's veto: a piece of a surface would be removed, or the new point (C->probe) lies
 * in the diametral sphere of a piece it would be joined to (it encroaches upon it). */
static int veto(void *user, int32_t a, int32_t b, int32_t c, int interior)
{
    conformer *C = user;
    if (face_triangle(C, a, b, c) < 0) return 0;
    if (interior) return 1;
    const double *A = X(C, a), *B = X(C, b), *Cc = X(C, c), *p = C->probe;
    /* centre of the circle through A, B, C in their plane */
    double u[3], v[3], n[3];
    for (int k = 0; k < 3; k++) { u[k] = B[k] - A[k]; v[k] = Cc[k] - A[k]; }
    n[0] = u[1] * v[2] - u[2] * v[1];
    n[1] = u[2] * v[0] - u[0] * v[2];
    n[2] = u[0] * v[1] - u[1] * v[0];
    double nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
    if (!(nn > 0)) return 0;
    double uu = u[0] * u[0] + u[1] * u[1] + u[2] * u[2], vv = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
    double nxu[3] = {n[1] * u[2] - n[2] * u[1], n[2] * u[0] - n[0] * u[2], n[0] * u[1] - n[1] * u[0]};
    double vxn[3] = {v[1] * n[2] - v[2] * n[1], v[2] * n[0] - v[0] * n[2], v[0] * n[1] - v[1] * n[0]};
    double cc[3];
    for (int k = 0; k < 3; k++) cc[k] = A[k] + (vv * nxu[k] + uu * vxn[k]) / (2 * nn);
    double r = dist3(cc, A);
    return dist3(cc, p) < r;
}

/* The veto near small pieces: only a piece of a surface that would be removed. */
static int veto_removal(void *user, int32_t a, int32_t b, int32_t c, int interior)
{
    return interior && face_triangle(user, a, b, c) >= 0;
}

/* ---- what changed ---- */

static void mark_tri(conformer *C, int32_t t)
{
    if (C->tdirty[t]) return;
    C->tdirty[t] = 1;
    C->tlist[C->ntl++] = t;
    for (int k = 0; k < 3; k++) {
        int32_t e = C->T[t].e[k];
        if (C->edirty[e]) continue;
        C->edirty[e] = 1;
        C->elist[C->nel++] = e;
    }
}

/* The insertions' recorder: a piece of a surface triangle among the faces an insertion removes
 * makes that triangle (and its edges) dirty. Never vetoes. */
static int face_triangle(const conformer *C, int32_t a, int32_t b, int32_t c);
static int record_removed(void *user, int32_t a, int32_t b, int32_t c, int interior)
{
    conformer *C = user;
    if (!interior) return 0;
    int32_t t = face_triangle(C, a, b, c);
    if (t >= 0) mark_tri(C, t);
    return 0;
}

/* After an insertion of point idx (its triangles known): they are looked at again; during the
 * refinement the new tetrahedra are judged. */
static thx_status after_insert(conformer *C, int32_t idx)
{
    if (idx >= 0 && (size_t)idx < C->own_cap)
        for (int32_t j = C->own_head[idx]; j >= 0; j = C->pool[j].next) mark_tri(C, C->pool[j].tri);
    if (C->refining) {
        const int32_t (*q)[4];
        int n = thx_dt_new_tets(C->dt, &q);
        if (n < 0) return THX_ENOMEM;
        if (C->nrq + (size_t)n > C->rq_cap) THX_CHECK(thx_grow(C->ctx, (void **)&C->rq, &C->rq_cap, C->nrq + (size_t)n, sizeof *C->rq));
        for (int i = 0; i < n; i++) {
            if (q[i][0] < 0 || q[i][1] < 0 || q[i][2] < 0) continue;
            memcpy(C->rq[C->nrq++], q[i], sizeof *C->rq);
        }
    }
    return THX_OK;
}

/* ---- edges ---- */

typedef struct { int32_t a, b, t, k; } erec;
static int cmp_erec(const void *x, const void *y)
{
    const erec *p = x, *q = y;
    if (p->a != q->a) return p->a < q->a ? -1 : 1;
    if (p->b != q->b) return p->b < q->b ? -1 : 1;
    return (p->t > q->t) - (p->t < q->t);
}

static thx_status build(conformer *C, const thx_surface *const *surf, const size_t *offset, size_t ns)
{
    size_t nT = 0;
    for (size_t s = 0; s < ns; s++) nT += surf[s]->n_tris;
    C->T = thx_calloc(C->ctx, nT ? nT : 1, sizeof *C->T);
    erec *r = thx_malloc(C->ctx, 3 * (nT ? nT : 1) * sizeof *r);
    if (!C->T || !r) { free(r); return THX_ENOMEM; }
    size_t k = 0;
    for (size_t s = 0; s < ns; s++)
        for (size_t i = 0; i < surf[s]->n_tris; i++, k++) {
            ctri *T = &C->T[k];
            for (int j = 0; j < 3; j++) T->c[j] = (int32_t)(offset[s] + (size_t)surf[s]->tri[3 * i + j]);
            T->surf = (int32_t)s;
            T->tri = (int32_t)i;
            for (int j = 0; j < 3; j++) {
                int32_t a = T->c[j], b = T->c[(j + 1) % 3];
                r[3 * k + j] = (erec){a < b ? a : b, a < b ? b : a, (int32_t)k, j};
            }
        }
    C->nT = nT;
    qsort(r, 3 * nT, sizeof *r, cmp_erec);
    size_t nE = 0;
    for (size_t i = 0; i < 3 * nT; i++) nE += i == 0 || r[i].a != r[i - 1].a || r[i].b != r[i - 1].b;
    C->E = thx_calloc(C->ctx, nE ? nE : 1, sizeof *C->E);
    if (!C->E) { free(r); return THX_ENOMEM; }
    size_t e = 0;
    for (size_t i = 0; i < 3 * nT; i++) {
        if (i == 0 || r[i].a != r[i - 1].a || r[i].b != r[i - 1].b) {
            cedge *E = &C->E[e++];
            E->a = r[i].a;
            E->b = r[i].b;
            E->surf = C->T[r[i].t].surf;
            E->tri = C->T[r[i].t].tri;
            E->t0 = r[i].t;
            E->t1 = -1;
            E->pt = thx_malloc(C->ctx, 4 * sizeof *E->pt);
            if (!E->pt) { free(r); return THX_ENOMEM; }
            E->cap = 4;
            E->n = 2;
            E->pt[0] = (cpt){0.0, E->a};
            E->pt[1] = (cpt){1.0, E->b};
        }
        C->T[r[i].t].e[r[i].k] = (int32_t)(e - 1);
        if (C->E[e - 1].t0 != r[i].t) C->E[e - 1].t1 = r[i].t;
    }
    C->nE = nE;
    free(r);
    for (size_t t = 0; t < nT; t++)
        for (int j = 0; j < 3; j++) THX_CHECK(own_add(C, C->T[t].c[j], (int32_t)t));
    return THX_OK;
}

static thx_status add_record(conformer *C, int32_t node, int32_t s, int32_t tri, const double w[3])
{
    if (C->n_st >= C->cap_st) THX_CHECK(thx_grow(C->ctx, (void **)&C->st, &C->cap_st, C->n_st + 1, sizeof *C->st));
    thx_steiner *r = &C->st[C->n_st++];
    r->node = node;
    r->surf = s;
    r->tri = tri;
    r->bary[0] = w[0];
    r->bary[1] = w[1];
    r->bary[2] = w[2];
    return THX_OK;
}

static thx_status too_fine(conformer *C, int32_t s, int32_t tri, const double *p, const char *why,
                           const thx_surface *const *surf)
{
    return thx_error(C->ctx, THX_EGEOM,
                     "mesh: surface \"%s\", triangle %ld near (%.3f, %.3f, %.3f): %s; the surfaces touch, cross or "
                     "come too close there (check the model with thorax check)",
                     surf[s]->name, (long)tri + 1, p[0], p[1], p[2], why);
}

/* Splits piece k (pt[k], pt[k+1]) of edge e at its middle. */
static thx_status split_piece(conformer *C, size_t e, size_t k, const thx_surface *const *surf)
{
    cedge *E = &C->E[e];
    const double *A = X(C, E->a), *B = X(C, E->b);
    double t = 0.5 * (E->pt[k].t + E->pt[k + 1].t);
    /* Concentric shells (Ruppert; Shewchuk 2000): a piece that touches a surface node (and not both
       ends) is split at a power-of-two distance from that node, so that the points on all edges at a
       node lie at the same distances from it and edges meeting at small angles do not cut each other
       into ever shorter pieces. The parameter keeps 22 bits (exactness, below). */
    if (E->n > 2 && (k == 0 || k + 2 == E->n)) {
        double L = dist3(A, B), lo = E->pt[k].t, hi = E->pt[k + 1].t;
        double len = (hi - lo) * L;
        double sh = exp2(floor(log2(2.0 * len / 3.0))); /* in [len/3, 2 len/3] */
        double ts = k == 0 ? sh / L : 1.0 - sh / L;
        ts = ldexp(nearbyint(ldexp(ts, 16)), -16); /* room for 6 more halvings */
        if (ts > lo && ts < hi) t = ts;
    }
    double p[3];
    /* exact: A, B on the grid, t dyadic with few bits (checked below) */
    for (int d = 0; d < 3; d++) p[d] = A[d] + t * (B[d] - A[d]);
    if (ldexp(t, MAX_DEPTH) != nearbyint(ldexp(t, MAX_DEPTH)))
        return too_fine(C, E->surf, E->tri, p, "a surface edge would be cut in more than 2^22 pieces", surf);
    {
        /* exactly on the edge: coplanar with both triangles holding it */
        int32_t tt[2] = {E->t0, E->t1};
        for (int j = 0; j < 2; j++) {
            if (tt[j] < 0) continue;
            const ctri *T = &C->T[tt[j]];
            if (thx_orient3d(X(C, T->c[0]), X(C, T->c[1]), X(C, T->c[2]), p) != 0)
                return too_fine(C, E->surf, E->tri, p, "a point on a surface edge is not exactly on it (coordinates too large for the grid)", surf);
        }
    }
    double len = dist3(X(C, E->pt[k].node), X(C, E->pt[k + 1].node));
    if (len < 2 * MIN_PIECE) return too_fine(C, E->surf, E->tri, p, "a surface edge would be cut into pieces shorter than 1e-4 mm", surf);
    if (C->n_st >= C->max_st) return too_fine(C, E->surf, E->tri, p, "too many points were added to make it a union of faces", surf);
    int32_t idx;
    int32_t fdummy[3];
    thx_status st = thx_dt_insert_checked(C->dt, p, E->pt[k].node, record_removed, C, &idx, fdummy);
    if (st == THX_EGEOM) return too_fine(C, E->surf, E->tri, p, "a point added on a surface edge falls on another node", surf);
    THX_CHECK(st);
    if (E->n >= E->cap) THX_CHECK(thx_grow(C->ctx, (void **)&E->pt, &E->cap, E->n + 1, sizeof *E->pt));
    memmove(E->pt + k + 2, E->pt + k + 1, (E->n - k - 1) * sizeof *E->pt);
    E->pt[k + 1] = (cpt){t, idx};
    E->n++;
    /* the record: barycentric in the first triangle holding the edge */
    const ctri *T = &C->T[E->t0];
    double w[3];
    for (int j = 0; j < 3; j++) w[j] = T->c[j] == E->a ? 1 - t : T->c[j] == E->b ? t : 0;
    THX_CHECK(add_record(C, idx, E->surf, E->tri, w));
    THX_CHECK(own_add(C, idx, E->t0));
    if (E->t1 >= 0) THX_CHECK(own_add(C, idx, E->t1));
    C->node_edge[idx] = (int32_t)e;
    C->S.n_edge_points++;
    return after_insert(C, idx);
}

/* Makes every piece of every dirty surface edge an edge of the tetrahedralization (splits mark
 * their neighbourhood dirty again). Returns the number of points added (in *added). */
static thx_status edge_pass(conformer *C, const thx_surface *const *surf, size_t *added)
{
    *added = 0;
    while (C->nel > 0) {
        int32_t e = C->elist[--C->nel];
        C->edirty[e] = 0;
        const cedge *E = &C->E[e];
        for (size_t k = 0; k + 1 < E->n; k++) {
            if (thx_dt_has_edge(C->dt, E->pt[k].node, E->pt[k + 1].node)) continue;
            THX_CHECK(split_piece(C, (size_t)e, k, surf)); /* marks e dirty again */
            (*added)++;
            break;
        }
    }
    return THX_OK;
}

/* Gathers the points of triangle ti into C->P (2D positions in the triangle's plane). */
static thx_status gather(conformer *C, size_t ti)
{
    const ctri *T = &C->T[ti];
    const double *c0 = X(C, T->c[0]), *c1 = X(C, T->c[1]), *c2 = X(C, T->c[2]);
    double u[3], v[3], n[3], w[3];
    for (int d = 0; d < 3; d++) { u[d] = c1[d] - c0[d]; v[d] = c2[d] - c0[d]; }
    n[0] = u[1] * v[2] - u[2] * v[1];
    n[1] = u[2] * v[0] - u[0] * v[2];
    n[2] = u[0] * v[1] - u[1] * v[0];
    double lu = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    for (int d = 0; d < 3; d++) u[d] /= lu;
    w[0] = n[1] * u[2] - n[2] * u[1];
    w[1] = n[2] * u[0] - n[0] * u[2];
    w[2] = n[0] * u[1] - n[1] * u[0];
    double lw = sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
    for (int d = 0; d < 3; d++) w[d] /= lw;
    C->nP = 0;
    size_t need = 3 + T->n_in;
    for (int k = 0; k < 3; k++) need += C->E[T->e[k]].n - 2;
    if (need > C->capP) THX_CHECK(thx_grow(C->ctx, (void **)&C->P, &C->capP, need, sizeof *C->P));
    size_t np_all = thx_dt_n_points(C->dt);
    if (np_all > C->lcap) {
        size_t cap = np_all + np_all / 2 + 64;
        int32_t *li = thx_realloc(C->ctx, C->lidx, cap * sizeof *li);
        if (!li) return THX_ENOMEM;
        C->lidx = li;
        uint32_t *ls = thx_realloc(C->ctx, C->lstamp, cap * sizeof *ls);
        if (!ls) return THX_ENOMEM;
        memset(ls + C->lcap, 0, (cap - C->lcap) * sizeof *ls);
        C->lstamp = ls;
        C->lcap = cap;
    }
    if (++C->lclock == 0) { memset(C->lstamp, 0, C->lcap * sizeof *C->lstamp); C->lclock = 1; }
#define ADD(nd, mk)                                                                                   \
    do {                                                                                              \
        const double *q_ = X(C, nd);                                                                  \
        C->lidx[nd] = (int32_t)C->nP;                                                                 \
        C->lstamp[nd] = C->lclock;                                                                    \
        double r_[3] = {q_[0] - c0[0], q_[1] - c0[1], q_[2] - c0[2]};                                 \
        C->P[C->nP++] = (tpt){nd, mk, r_[0] * u[0] + r_[1] * u[1] + r_[2] * u[2],                     \
                              r_[0] * w[0] + r_[1] * w[1] + r_[2] * w[2]};                            \
    } while (0)
    ADD(T->c[0], 5u);
    ADD(T->c[1], 3u);
    ADD(T->c[2], 6u);
    for (int k = 0; k < 3; k++) {
        const cedge *E = &C->E[T->e[k]];
        for (size_t i = 1; i + 1 < E->n; i++) ADD(E->pt[i].node, 1u << k);
    }
    for (size_t i = 0; i < T->n_in; i++) ADD(T->in[i], 0u);
#undef ADD
    return THX_OK;
}

/* The local index of node among the points gathered last, or -1. */
static int find_pt(const conformer *C, int32_t node)
{
    if (node < 0 || (size_t)node >= C->lcap || C->lstamp[node] != C->lclock) return -1;
    return C->lidx[node];
}

typedef struct { int32_t a, b; int n; } fedge;

/* The faces on triangle ti (in C->F, local point indices) and whether they cover it. */
static thx_status cover(conformer *C, size_t ti, int *covered)
{
    *covered = 0;
    C->nF = 0;
    for (size_t i = 0; i < C->nP; i++) {
        const int32_t (*q)[4];
        int n = thx_dt_star(C->dt, C->P[i].node, &q);
        if (n < 0) return THX_ENOMEM;
        for (int t = 0; t < n; t++) {
            int loc[4], ok = 1;
            for (int k = 0; k < 4; k++) {
                if (q[t][k] < 0) { loc[k] = -1; continue; }
                loc[k] = q[t][k] == C->P[i].node ? (int)i : find_pt(C, q[t][k]);
            }
            (void)ok;
            for (int f = 0; f < 4; f++) { /* face opposite corner f */
                int a = -1, b = -1, c = -1, m = 0;
                for (int k = 0; k < 4; k++) {
                    if (k == f) continue;
                    int l = loc[k];
                    if (m == 0) a = l; else if (m == 1) b = l; else c = l;
                    m++;
                }
                if (a < 0 || b < 0 || c < 0) continue;
                /* counted once: from its smallest local point */
                int lo = a < b ? (a < c ? a : c) : (b < c ? b : c);
                if (lo != (int)i) continue;
                if (C->P[a].mask & C->P[b].mask & C->P[c].mask) continue; /* three points on one edge */
                int x = a, y = b, z = c, tmp;
                if (x > y) { tmp = x; x = y; y = tmp; }
                if (y > z) { tmp = y; y = z; z = tmp; }
                if (x > y) { tmp = x; x = y; y = tmp; }
                int dup = 0;
                for (size_t j = 0; j < C->nF && !dup; j++) dup = C->F[j][0] == x && C->F[j][1] == y && C->F[j][2] == z;
                if (dup) continue;
                if (C->nF >= C->capF) THX_CHECK(thx_grow(C->ctx, (void **)&C->F, &C->capF, C->nF + 1, sizeof *C->F));
                C->F[C->nF][0] = x;
                C->F[C->nF][1] = y;
                C->F[C->nF][2] = z;
                C->nF++;
            }
        }
    }
    if (C->nF == 0) return THX_OK;
    /* edge counts */
    fedge ed[3 * 64];
    fedge *E = ed;
    size_t ne = 0, cap = 3 * 64;
    fedge *heap = NULL;
    if (3 * C->nF > cap) {
        heap = malloc(3 * C->nF * sizeof *heap);
        if (!heap) return thx_error(C->ctx, THX_ENOMEM, "out of memory");
        E = heap;
    }
    for (size_t j = 0; j < C->nF; j++)
        for (int k = 0; k < 3; k++) {
            int32_t a = C->F[j][k], b = C->F[j][(k + 1) % 3];
            if (a > b) { int32_t t = a; a = b; b = t; }
            size_t x = 0;
            while (x < ne && !(E[x].a == a && E[x].b == b)) x++;
            if (x == ne) E[ne++] = (fedge){a, b, 0};
            E[x].n++;
        }
    /* boundary pieces: consecutive points of each edge chain */
    const ctri *T = &C->T[ti];
    int ok = 1;
    size_t n_boundary = 0;
    for (int k = 0; k < 3 && ok; k++) {
        const cedge *G = &C->E[T->e[k]];
        for (size_t i = 0; i + 1 < G->n && ok; i++) {
            int a = find_pt(C, G->pt[i].node), b = find_pt(C, G->pt[i + 1].node);
            if (a > b) { int t = a; a = b; b = t; }
            size_t x = 0;
            while (x < ne && !(E[x].a == a && E[x].b == b)) x++;
            if (x == ne || E[x].n != 1) ok = 0;
            else E[x].n = -1; /* seen as boundary */
            n_boundary++;
        }
    }
    for (size_t x = 0; x < ne && ok; x++)
        if (E[x].n != -1 && E[x].n != 2) ok = 0;
    free(heap);
    *covered = ok;
    return THX_OK;
}

/* Inserts a point inside triangle ti at barycentric coordinates w (rounded to a dyadic grid);
 * *done (if not NULL) says whether it was: with done, a point on an existing node is left out
 * instead of an error. */
static thx_status add_inside_at(conformer *C, size_t ti, const double w[3], const thx_surface *const *surf, int *done)
{
    if (done) *done = 0;
    ctri *T = &C->T[ti];
    const double *c0 = X(C, T->c[0]), *c1 = X(C, T->c[1]), *c2 = X(C, T->c[2]);
    double p[3];
    /* barycentric coordinates on a dyadic grid: then p = c0 + w1 (c1 - c0) + w2 (c2 - c0) is exact and
       exactly in the triangle's plane */
    double w1 = ldexp(nearbyint(ldexp(w[1], 20)), -20), w2 = ldexp(nearbyint(ldexp(w[2], 20)), -20);
    double ww[3] = {1 - w1 - w2, w1, w2};
    for (int d = 0; d < 3; d++) p[d] = c0[d] + w1 * (c1[d] - c0[d]) + w2 * (c2[d] - c0[d]);
    if (thx_orient3d(c0, c1, c2, p) != 0)
        return too_fine(C, T->surf, T->tri, p, "a point inside a surface triangle is not exactly in its plane (coordinates too large for the grid)", surf);
    if (!(ww[0] > 0 && ww[1] > 0 && ww[2] > 0)) return THX_OK;
    if (C->n_st >= C->max_st) return too_fine(C, T->surf, T->tri, p, "too many points were added to make it a union of faces", surf);
    int32_t idx;
    int32_t fdummy[3];
    thx_status st = thx_dt_insert_checked(C->dt, p, T->c[0], record_removed, C, &idx, fdummy);
    if (st == THX_EGEOM && done) { thx_ctx_clear(C->ctx); return THX_OK; }
    if (st == THX_EGEOM) return too_fine(C, T->surf, T->tri, p, "a point added on a surface triangle falls on another node", surf);
    THX_CHECK(st);
    if (T->n_in >= T->cap_in) THX_CHECK(thx_grow(C->ctx, (void **)&T->in, &T->cap_in, T->n_in + 1, sizeof *T->in));
    T->in[T->n_in++] = idx;
    THX_CHECK(add_record(C, idx, T->surf, T->tri, ww));
    THX_CHECK(own_add(C, idx, (int32_t)ti));
    C->S.n_face_points++;
    if (done) *done = 1;
    return after_insert(C, idx);
}

static thx_status add_inside(conformer *C, size_t ti, const double w[3], const thx_surface *const *surf)
{
    return add_inside_at(C, ti, w, surf, NULL);
}

/* Splits the longest piece of triangle ti's edges (points gathered). */
static thx_status split_longest(conformer *C, size_t ti, const thx_surface *const *surf)
{
    const ctri *T = &C->T[ti];
    size_t long_e = 0, long_k = 0;
    double long_len = -1;
    for (int k = 0; k < 3; k++) {
        const cedge *G = &C->E[T->e[k]];
        for (size_t i = 0; i + 1 < G->n; i++) {
            double len = dist3(X(C, G->pt[i].node), X(C, G->pt[i + 1].node));
            if (len > long_len) { long_len = len; long_e = (size_t)T->e[k]; long_k = i; }
        }
    }
    return split_piece(C, long_e, long_k, surf);
}

/* A new point for triangle ti at (cx, cy) of its 2D frame (points gathered): there, unless that
 * lies outside the triangle or in the diametral circle of a piece of its edges, which is then
 * split instead (the encroached piece, else the one nearest the point). */
static thx_status place(conformer *C, size_t ti, double cx, double cy, const thx_surface *const *surf)
{
    const ctri *T = &C->T[ti];
    size_t best_e = 0, best_k = 0, near_e = 0, near_k = 0;
    double best_len = -1, near_d = INFINITY;
    for (int k = 0; k < 3; k++) {
        size_t e = (size_t)T->e[k];
        const cedge *G = &C->E[e];
        for (size_t i = 0; i + 1 < G->n; i++) {
            int a = find_pt(C, G->pt[i].node), b = find_pt(C, G->pt[i + 1].node);
            double ax = C->P[a].x, ay = C->P[a].y, bx = C->P[b].x, by = C->P[b].y;
            double mx = 0.5 * (ax + bx), my = 0.5 * (ay + by);
            double len = hypot(bx - ax, by - ay);
            if (hypot(cx - mx, cy - my) < 0.5 * len && len > best_len) { best_len = len; best_e = e; best_k = i; }
            double dx = bx - ax, dy = by - ay, t = ((cx - ax) * dx + (cy - ay) * dy) / (dx * dx + dy * dy);
            t = t < 0 ? 0 : t > 1 ? 1 : t;
            double dd = hypot(cx - ax - t * dx, cy - ay - t * dy);
            if (dd < near_d) { near_d = dd; near_e = e; near_k = i; }
        }
    }
    if (best_len > 0) return split_piece(C, best_e, best_k, surf);
    /* barycentric coordinates of the point (2D frame: corner 0 at the origin) */
    const tpt *p0 = &C->P[0], *p1 = &C->P[1], *p2 = &C->P[2];
    double det = (p1->x - p0->x) * (p2->y - p0->y) - (p2->x - p0->x) * (p1->y - p0->y);
    double w1 = ((cx - p0->x) * (p2->y - p0->y) - (p2->x - p0->x) * (cy - p0->y)) / det;
    double w2 = ((p1->x - p0->x) * (cy - p0->y) - (cx - p0->x) * (p1->y - p0->y)) / det;
    double w[3] = {1 - w1 - w2, w1, w2};
    const double margin = 1e-9;
    if (w[0] < margin || w[1] < margin || w[2] < margin) return split_piece(C, near_e, near_k, surf);
    return add_inside(C, ti, w, surf);
}

/* 2D circumcentre of three gathered points. */
static int circumcentre2(const tpt *a, const tpt *b, const tpt *c, double *cx, double *cy, double *r)
{
    double bx = b->x - a->x, by = b->y - a->y, qx = c->x - a->x, qy = c->y - a->y;
    double d = 2 * (bx * qy - by * qx);
    if (!(fabs(d) > 0)) return 0;
    double b2 = bx * bx + by * by, q2 = qx * qx + qy * qy;
    double ux = (qy * b2 - by * q2) / d, uy = (bx * q2 - qx * b2) / d;
    *cx = a->x + ux;
    *cy = a->y + uy;
    *r = sqrt(ux * ux + uy * uy);
    return 1;
}

/* Refines triangle ti once (it is not covered): a circumcentre inside, or a split of a piece of its edges. */
static thx_status refine(conformer *C, size_t ti, const thx_surface *const *surf)
{
    THX_CHECK(gather(C, ti));
    thx_vec2 *pts = thx_malloc(C->ctx, C->nP * sizeof *pts);
    if (!pts) return THX_ENOMEM;
    for (size_t i = 0; i < C->nP; i++) pts[i] = (thx_vec2){C->P[i].x, C->P[i].y};
    int32_t *tris = NULL;
    size_t nt = 0;
    thx_status st = thx_cdt2d(C->ctx, pts, C->nP, NULL, 0, &tris, &nt);
    free(pts);
    if (st != THX_OK) {
        thx_ctx_clear(C->ctx);
        nt = 0;
        tris = NULL;
    }
    /* the largest missing piece */
    double best_r = -1, cx = 0, cy = 0;
    for (size_t j = 0; j < nt; j++) {
        const tpt *a = &C->P[tris[3 * j]], *b = &C->P[tris[3 * j + 1]], *c = &C->P[tris[3 * j + 2]];
        if (a->mask & b->mask & c->mask) continue;
        if (thx_dt_has_face(C->dt, a->node, b->node, c->node)) continue;
        double ux, uy, r;
        if (!circumcentre2(a, b, c, &ux, &uy, &r)) continue;
        if (r > best_r) { best_r = r; cx = ux; cy = uy; }
    }
    free(tris);
    if (best_r < 0) return split_longest(C, ti, surf); /* no missing piece seen */
    return place(C, ti, cx, cy, surf);
}

/* ---- small input angles at sharp folds ---- */

#define FIN_CORNER_DEG 8.0 /* corners of a triangle below this... */
#define FIN_FOLD_DEG 60.0  /* ...on an edge where the surface folds to less than this */

static double angle3(const double *u, const double *v)
{
    double d = u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
    double lu = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]), lv = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    double c = d / (lu * lv);
    return acos(c < -1 ? -1 : c > 1 ? 1 : c);
}

/* The unit vector from the line through A along unit e to the point P, perpendicular to e. */
static int perp_unit(const double *A, const double *e, const double *P, double out[3])
{
    double d[3] = {P[0] - A[0], P[1] - A[1], P[2] - A[2]};
    double t = d[0] * e[0] + d[1] * e[1] + d[2] * e[2];
    for (int k = 0; k < 3; k++) out[k] = d[k] - t * e[k];
    double l = sqrt(out[0] * out[0] + out[1] * out[1] + out[2] * out[2]);
    if (!(l > 0)) return 0;
    for (int k = 0; k < 3; k++) out[k] /= l;
    return 1;
}

/* The triangle across edge e from triangle ti (-1: none), and its corner off e. */
static int32_t across(const conformer *C, int32_t e, int32_t ti, int32_t *off)
{
    const cedge *G = &C->E[e];
    int32_t tn = G->t0 == ti ? G->t1 : G->t0;
    *off = -1;
    if (tn < 0) return -1;
    for (int j = 0; j < 3; j++)
        if (C->T[tn].c[j] != G->a && C->T[tn].c[j] != G->b) *off = C->T[tn].c[j];
    return *off < 0 ? -1 : tn;
}

/* Puts a point inside triangle tn at distance r from its corner v and angle phi from its edge v-f
 * (unless one is there already or it falls outside the triangle); *added counts it. */
static thx_status fold_point(conformer *C, int32_t tn, int32_t v, int32_t f, double phi, double r,
                             const thx_surface *const *surf, size_t *added)
{
    const ctri *U = &C->T[tn];
    int32_t off = -1;
    for (int j = 0; j < 3; j++)
        if (U->c[j] != v && U->c[j] != f) off = U->c[j];
    const double *V = X(C, v), *F = X(C, f);
    double L = dist3(V, F), ed[3], nu[3];
    if (off < 0 || !(L > 0)) return THX_OK;
    for (int d = 0; d < 3; d++) ed[d] = (F[d] - V[d]) / L;
    if (!perp_unit(V, ed, X(C, off), nu)) return THX_OK;
    double y[3];
    for (int d = 0; d < 3; d++) y[d] = V[d] + r * (cos(phi) * ed[d] + sin(phi) * nu[d]);
    for (size_t j = 0; j < U->n_in; j++)
        if (dist3(X(C, U->in[j]), y) < 1e-3 * r) return THX_OK; /* an earlier round's */
    const double *c0 = X(C, U->c[0]), *c1 = X(C, U->c[1]), *c2 = X(C, U->c[2]);
    double a1[3], a2[3], dv[3];
    for (int d = 0; d < 3; d++) { a1[d] = c1[d] - c0[d]; a2[d] = c2[d] - c0[d]; dv[d] = y[d] - c0[d]; }
    double g11 = a1[0] * a1[0] + a1[1] * a1[1] + a1[2] * a1[2], g12 = a1[0] * a2[0] + a1[1] * a2[1] + a1[2] * a2[2],
           g22 = a2[0] * a2[0] + a2[1] * a2[1] + a2[2] * a2[2], det = g11 * g22 - g12 * g12;
    if (!(det > 0)) return THX_OK;
    double b1 = a1[0] * dv[0] + a1[1] * dv[1] + a1[2] * dv[2], b2 = a2[0] * dv[0] + a2[1] * dv[1] + a2[2] * dv[2];
    double w1 = (g22 * b1 - g12 * b2) / det, w2 = (g11 * b2 - g12 * b1) / det;
    double w[3] = {1 - w1 - w2, w1, w2};
    if (!(w[0] > 1e-6 && w[1] > 1e-6 && w[2] > 1e-6)) return THX_OK;
    int done = 0;
    THX_CHECK(add_inside_at(C, (size_t)tn, w, surf, &done));
    *added += (size_t)done;
    return THX_OK;
}

/* Small corners at sharp folds (ECGSim's heart: triangle 214 has a 2.05 deg corner at node 195 whose
 * edge 195-197 is a fold where the surface turns back to a 16 deg wedge, triangle 213 on its other
 * side, while triangle 365 continues 214 across its other edge 195-196, 3.5 deg off its plane).
 * The concentric shells (split_piece) put points a and b on the corner's two edges at the same
 * distances r from the apex v, so the corner's piece (v, a, b) is a well-shaped needle; but inside
 * the wedge the tetrahedron on that piece must take its fourth point on the fold's other side, and
 * the nearest one there, c on the other edge of triangle 213 at psi = 42 deg from the fold, makes a
 * tetrahedron (v, a, b, c) of smallest dihedral angle 0.88 deg whatever the radii (b lies 2.05 deg
 * from the fold, so only 0.01 r off the plane of v, a and c): no flip or free node of the repair can
 * help. Seen on a small sphere around v (the link of v: the tetrahedra at v as spherical
 * triangles), the wedge is a lune of width W holding b at alpha from the fold on one side and c at
 * psi on the other, and every triangle of the link joining b to two points of the other side is flat
 * (for any two: b is almost on that side's great circle). So the lune gets one point on each side,
 * every shell: on the fold's other side at phi = sqrt(alpha psi) from the fold (9.3 deg for ECGSim:
 * the triangle (fold, b, that point) has angles of several degrees, e.g. 4.5 deg at r), and on b's
 * side, in the triangle beyond the corner's other edge, halfway across that triangle's corner at v
 * (then b's link triangles in the lune are (fold, b, phi point) and (b, phi point, that point); with
 * only the first point the tetrahedralization may still take (b, phi point, c): 0.889 deg with
 * --repair 0; a point on b's side close to b's edge, at phi as well, made a 0.83 deg flat
 * tetrahedron across the 3.5 deg bend between 214 and 365 instead). For every point of the fold
 * edge's chain at distance r from v (the shells), the two are put inside those triangles at
 * distance r from v: surface points (recorded like the others), after which the surfaces are made
 * unions of faces again (fold_loop). Returns the number of points added in *added. */
static thx_status protect_folds(conformer *C, const thx_surface *const *surf, size_t *added)
{
    *added = 0;
    const double lim = FIN_CORNER_DEG * M_PI / 180.0, fold = FIN_FOLD_DEG * M_PI / 180.0;
    for (size_t ti = 0; ti < C->nT; ti++) {
        for (int k = 0; k < 3; k++) {
            const ctri *T = &C->T[ti];
            int32_t v = T->c[k], p = T->c[(k + 1) % 3], q = T->c[(k + 2) % 3];
            /* a copy: the points' array moves when fold_point inserts */
            double V[3];
            memcpy(V, X(C, v), sizeof V);
            double u1[3], u2[3];
            for (int d = 0; d < 3; d++) { u1[d] = X(C, p)[d] - V[d]; u2[d] = X(C, q)[d] - V[d]; }
            double alpha = angle3(u1, u2);
            if (!(alpha > 0 && alpha < lim)) continue;
            /* either edge at v may be the fold: edge k joins v and p, edge k+2 joins q and v */
            for (int side = 0; side < 2; side++) {
                int32_t e = T->e[side ? (k + 2) % 3 : k], e2 = T->e[side ? k : (k + 2) % 3];
                int32_t far = side ? q : p, far2 = side ? p : q; /* the fold's other end; the other edge's */
                int32_t w_u, w_2;
                int32_t tn = across(C, e, (int32_t)ti, &w_u), t2 = across(C, e2, (int32_t)ti, &w_2);
                if (tn < 0) continue;
                double F[3];
                memcpy(F, X(C, far), sizeof F);
                double L = dist3(V, F), ed[3];
                if (!(L > 0)) continue;
                for (int d = 0; d < 3; d++) ed[d] = (F[d] - V[d]) / L;
                double nt[3], nu[3];
                if (!perp_unit(V, ed, X(C, far2), nt) || !perp_unit(V, ed, X(C, w_u), nu)) continue;
                double W = angle3(nt, nu); /* the wedge between the two triangles */
                if (!(W < fold)) continue;
                double uw[3];
                for (int d = 0; d < 3; d++) uw[d] = X(C, w_u)[d] - V[d];
                double psi = angle3(ed, uw); /* the other triangle's angle at v */
                double phi = sqrt(alpha * psi);
                if (!(phi < 0.5 * psi)) continue;
                double psi2 = -1;
                if (t2 >= 0) {
                    double u3[3], u4[3];
                    for (int d = 0; d < 3; d++) { u3[d] = X(C, far2)[d] - V[d]; u4[d] = X(C, w_2)[d] - V[d]; }
                    psi2 = angle3(u3, u4);
                }
                for (size_t i = 1; i + 1 < C->E[e].n; i++) {
                    double r = dist3(V, X(C, C->E[e].pt[i].node));
                    /* across the fold, phi from it; on this side, halfway across the next triangle's corner */
                    THX_CHECK(fold_point(C, tn, v, far, phi, r, surf, added));
                    if (t2 >= 0 && psi2 > 0) THX_CHECK(fold_point(C, t2, v, far2, 0.5 * psi2, r, surf, added));
                }
            }
        }
    }
    return THX_OK;
}

/* ---- Delaunay refinement for quality ---- */

/* Circumcentre of tetrahedron (a, b, c, d); 0 if flat. */
static int circumcentre3(const double *a, const double *b, const double *c, const double *d, double cc[3])
{
    double u[3], v[3], w[3];
    for (int k = 0; k < 3; k++) { u[k] = b[k] - a[k]; v[k] = c[k] - a[k]; w[k] = d[k] - a[k]; }
    double vw[3] = {v[1] * w[2] - v[2] * w[1], v[2] * w[0] - v[0] * w[2], v[0] * w[1] - v[1] * w[0]};
    double wu[3] = {w[1] * u[2] - w[2] * u[1], w[2] * u[0] - w[0] * u[2], w[0] * u[1] - w[1] * u[0]};
    double uv[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    double det = 2 * (u[0] * vw[0] + u[1] * vw[1] + u[2] * vw[2]);
    if (!(fabs(det) > 0)) return 0;
    double uu = u[0] * u[0] + u[1] * u[1] + u[2] * u[2], vv = v[0] * v[0] + v[1] * v[1] + v[2] * v[2],
           ww = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
    for (int k = 0; k < 3; k++) cc[k] = a[k] + (uu * vw[k] + vv * wu[k] + ww * uv[k]) / det;
    return 1;
}

/* Smallest dihedral angle (degrees), radius-edge ratio and circumradius of a tetrahedron (a flat
 * one: 0, INFINITY, INFINITY). */
static void shape(const double *p[4], double *min_dih, double *radius_edge, double *radius)
{
    static const int fv[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
    double n[4][3];
    for (int f = 0; f < 4; f++) {
        const double *a = p[fv[f][0]], *b = p[fv[f][1]], *c = p[fv[f][2]];
        double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        double x = u[1] * v[2] - u[2] * v[1], y = u[2] * v[0] - u[0] * v[2], z = u[0] * v[1] - u[1] * v[0];
        double l = sqrt(x * x + y * y + z * z);
        if (!(l > 0)) { *min_dih = 0; *radius_edge = *radius = INFINITY; return; }
        n[f][0] = x / l; n[f][1] = y / l; n[f][2] = z / l;
        /* outward: away from the opposite corner */
        const double *o = p[f];
        if (n[f][0] * (o[0] - a[0]) + n[f][1] * (o[1] - a[1]) + n[f][2] * (o[2] - a[2]) > 0)
            for (int k = 0; k < 3; k++) n[f][k] = -n[f][k];
    }
    double best = 180;
    for (int f = 0; f < 4; f++)
        for (int g = f + 1; g < 4; g++) {
            double dot = n[f][0] * n[g][0] + n[f][1] * n[g][1] + n[f][2] * n[g][2];
            double ang = 180.0 - acos(dot < -1 ? -1 : dot > 1 ? 1 : dot) * 180.0 / M_PI;
            if (ang < best) best = ang;
        }
    *min_dih = best;
    double cc[3];
    if (!circumcentre3(p[0], p[1], p[2], p[3], cc)) { *radius_edge = *radius = INFINITY; return; }
    double r = dist3(cc, p[0]), e = INFINITY;
    *radius = r;
    for (int i = 0; i < 4; i++)
        for (int j = i + 1; j < 4; j++) { double l = dist3(p[i], p[j]); if (l < e) e = l; }
    *radius_edge = r / e;
}

/* Splits the piece face (a, b, c) of triangle ti: at its circumcentre, or a piece of the edges. */
static thx_status split_face(conformer *C, size_t ti, const int32_t f[3], const thx_surface *const *surf)
{
    THX_CHECK(gather(C, ti));
    int ia = find_pt(C, f[0]), ib = find_pt(C, f[1]), ic = find_pt(C, f[2]);
    double cx, cy, r;
    if (ia < 0 || ib < 0 || ic < 0 || !circumcentre2(&C->P[ia], &C->P[ib], &C->P[ic], &cx, &cy, &r))
        return split_longest(C, ti, surf);
    return place(C, ti, cx, cy, surf);
}

static thx_status conform_loop(conformer *C, const thx_surface *const *surf);

/* Delaunay refinement (Shewchuk; what TetGen's -q does): the circumcentre of every tetrahedron of
 * the domain whose radius-edge ratio or smallest dihedral angle is bad is inserted, unless the
 * insertion would remove a piece of a surface or encroach upon one, which is then split instead
 * and the surfaces made faces again. A work list: every tetrahedron at the start, then those each
 * insertion makes. */
static thx_status refine_quality(conformer *C, const conform_quality *Q, const thx_surface *const *surf)
{
    double t0 = thx_wtime();
    size_t start = thx_dt_n_points(C->dt);
    size_t limit = Q->max_points ? Q->max_points : 2 * start;
    thx_status st = THX_OK;
    {
        int32_t *tq = NULL;
        size_t nt = 0;
        THX_CHECK(thx_dt_tets(C->dt, &tq, &nt));
        free(C->rq);
        C->rq = (int32_t (*)[4])tq;
        C->nrq = C->rq_cap = nt;
    }
    C->refining = 1;
    size_t head = 0;
    while (head < C->nrq) {
        if (Q->progress && (head & 8191) == 0) Q->progress(Q->progress_user, "refinement", (double)head / (double)C->nrq);
        int32_t q[4];
        memcpy(q, C->rq[head++], sizeof q);
        if (head > (1u << 20) && head * 2 > C->nrq) { /* drop what was judged */
            memmove(C->rq, C->rq + head, (C->nrq - head) * sizeof *C->rq);
            C->nrq -= head;
            head = 0;
        }
        const double *p[4];
        for (int k = 0; k < 4; k++) p[k] = X(C, q[k]);
        double dih, re, rad;
        shape(p, &dih, &re, &rad);
        int bad = (Q->radius_edge > 0 && re > Q->radius_edge) || (Q->min_dihedral > 0 && dih < Q->min_dihedral);
        double c[3];
        for (int k = 0; k < 3; k++) c[k] = 0.25 * (p[0][k] + p[1][k] + p[2][k] + p[3][k]);
        if (!bad && Q->size) bad = isfinite(rad) && rad > Q->size(Q->user, c);
        if (!bad) continue;
        if (!Q->inside(Q->user, c)) continue;
        if (!thx_dt_has_tet(C->dt, q)) continue;
        if (thx_dt_n_points(C->dt) - start >= limit) { C->S.refine_limited = 1; break; }
        double cc[3];
        if (!circumcentre3(p[0], p[1], p[2], p[3], cc)) continue;
        for (int k = 0; k < 3; k++) cc[k] = snap(C, cc[k]);
        int32_t idx, f[3];
        C->probe = cc;
        st = thx_dt_insert_checked(C->dt, cc, q[0], veto, C, &idx, f);
        if (st == THX_EGEOM) { thx_ctx_clear(C->ctx); st = THX_OK; continue; } /* on an existing node */
        if (st != THX_OK) break;
        if (idx >= 0) {
            C->S.n_refine_points++;
            st = after_insert(C, -1); /* vetted: no piece of a surface among the faces removed */
            if (st != THX_OK) break;
            /* the tetrahedron may come back if the centre was vetoed elsewhere: nothing to redo */
            continue;
        }
        int32_t ti = face_triangle(C, f[0], f[1], f[2]);
        if (ti < 0) continue;
        {
            /* a piece already much smaller than its triangle is not split for quality: where the
               surfaces meet at small angles or come close, refinement would not end */
            const ctri *T = &C->T[ti];
            double e0 = fmin(fmin(dist3(X(C, T->c[0]), X(C, T->c[1])), dist3(X(C, T->c[1]), X(C, T->c[2]))),
                             dist3(X(C, T->c[2]), X(C, T->c[0])));
            double ef = fmax(fmax(dist3(X(C, f[0]), X(C, f[1])), dist3(X(C, f[1]), X(C, f[2]))), dist3(X(C, f[2]), X(C, f[0])));
            if (ef < Q->min_piece_ratio * e0) {
                /* the centre is inserted anyway where that removes no piece of a surface (it lies on
                   the tetrahedron's side of every surface): close to a surface, but conforming */
                st = thx_dt_insert_checked(C->dt, cc, q[0], veto_removal, C, &idx, f);
                if (st == THX_EGEOM) { thx_ctx_clear(C->ctx); st = THX_OK; }
                if (st != THX_OK) break;
                if (idx >= 0) {
                    C->S.n_refine_points++;
                    C->S.n_refine_near++;
                    st = after_insert(C, -1);
                    if (st != THX_OK) break;
                } else
                    C->S.n_refine_skipped++;
                continue;
            }
        }
        size_t before = C->n_st;
        st = split_face(C, (size_t)ti, f, surf);
        if (st == THX_OK) st = conform_loop(C, surf);
        if (st != THX_OK) break;
        C->S.n_refine_surface += C->n_st - before;
        /* judge this tetrahedron again later (if it survived) */
        if (C->nrq >= C->rq_cap && thx_grow(C->ctx, (void **)&C->rq, &C->rq_cap, C->nrq + 1, sizeof *C->rq) != THX_OK) {
            st = THX_ENOMEM;
            break;
        }
        memcpy(C->rq[C->nrq++], q, sizeof q);
    }
    C->refining = 0;
    if (Q->progress) Q->progress(Q->progress_user, "refinement", 1.0);
    C->S.refine_rounds = 1;
    C->S.t_refine = thx_wtime() - t0;
    return st;
}

/* Collects the final faces on every triangle, oriented like it. */
static thx_status collect(conformer *C, mesh_subface **sub, size_t *n_sub)
{
    size_t cap = C->nT + C->n_st * 2 + 16, n = 0;
    mesh_subface *out = thx_malloc(C->ctx, cap * sizeof *out);
    if (!out) return THX_ENOMEM;
    for (size_t ti = 0; ti < C->nT; ti++) {
        const ctri *T = &C->T[ti];
        int covered = 0;
        thx_status st = gather(C, ti);
        if (st == THX_OK) st = cover(C, ti, &covered);
        if (st != THX_OK) { free(out); return st; }
        if (!covered) {
            free(out);
            return thx_error(C->ctx, THX_EINTERNAL, "mesh: surface triangle %ld not covered after conforming", (long)T->tri + 1);
        }
        if (C->nF > 1) C->S.n_split_triangles++;
        const double *c0 = X(C, T->c[0]), *c1 = X(C, T->c[1]), *c2 = X(C, T->c[2]);
        double nrm[3], u[3], v[3];
        for (int d = 0; d < 3; d++) { u[d] = c1[d] - c0[d]; v[d] = c2[d] - c0[d]; }
        nrm[0] = u[1] * v[2] - u[2] * v[1];
        nrm[1] = u[2] * v[0] - u[0] * v[2];
        nrm[2] = u[0] * v[1] - u[1] * v[0];
        for (size_t j = 0; j < C->nF; j++) {
            int32_t a = C->P[C->F[j][0]].node, b = C->P[C->F[j][1]].node, c = C->P[C->F[j][2]].node;
            const double *A = X(C, a), *B = X(C, b), *Cc = X(C, c);
            double x[3], y[3];
            for (int d = 0; d < 3; d++) { x[d] = B[d] - A[d]; y[d] = Cc[d] - A[d]; }
            double fn[3] = {x[1] * y[2] - x[2] * y[1], x[2] * y[0] - x[0] * y[2], x[0] * y[1] - x[1] * y[0]};
            if (fn[0] * nrm[0] + fn[1] * nrm[1] + fn[2] * nrm[2] < 0) { int32_t t = b; b = c; c = t; }
            if (n >= cap) {
                if (thx_grow(C->ctx, (void **)&out, &cap, n + 1, sizeof *out) != THX_OK) { free(out); return THX_ENOMEM; }
            }
            out[n++] = (mesh_subface){{a, b, c}, T->surf, T->tri};
        }
    }
    *sub = out;
    *n_sub = n;
    return THX_OK;
}

/* Adds points on the surfaces until every piece of every surface edge is a mesh edge and every
 * surface triangle is covered by mesh faces, looking only at what insertions touched. */
static thx_status conform_loop(conformer *C, const thx_surface *const *surf)
{
    size_t budget = 200 * (C->nT + 16), work = 0;
    for (;;) {
        if (C->Q && C->Q->progress && !C->refining && (work & 1023) == 0)
            C->Q->progress(C->Q->progress_user, "conformity", 1.0 - (double)C->ntl / (double)(C->nT ? C->nT : 1));
        size_t added = 0;
        THX_CHECK(edge_pass(C, surf, &added));
        if (C->ntl == 0) break;
        int32_t ti = C->tlist[--C->ntl];
        C->tdirty[ti] = 0;
        if (++work > budget)
            return thx_error(C->ctx, THX_EGEOM, "mesh: the surfaces could not be made faces of the mesh (surface \"%s\", "
                             "triangle %ld keeps changing)", surf[C->T[ti].surf]->name, (long)C->T[ti].tri + 1);
        const ctri *T = &C->T[ti];
        int covered;
        if (T->n_in == 0 && C->E[T->e[0]].n == 2 && C->E[T->e[1]].n == 2 && C->E[T->e[2]].n == 2)
            covered = thx_dt_has_face(C->dt, T->c[0], T->c[1], T->c[2]);
        else {
            THX_CHECK(gather(C, (size_t)ti));
            THX_CHECK(cover(C, (size_t)ti, &covered));
        }
        if (covered) continue;
        /* a piece of its edges missing: the edge pass first, then this triangle again */
        int edges_ok = 1;
        for (int k = 0; k < 3 && edges_ok; k++) {
            const cedge *G = &C->E[T->e[k]];
            for (size_t i = 0; i + 1 < G->n && edges_ok; i++)
                edges_ok = thx_dt_has_edge(C->dt, G->pt[i].node, G->pt[i + 1].node);
        }
        if (!edges_ok) {
            C->tdirty[ti] = 0;
            mark_tri(C, ti);
            for (int k = 0; k < 3; k++)
                if (!C->edirty[T->e[k]]) { C->edirty[T->e[k]] = 1; C->elist[C->nel++] = T->e[k]; }
            continue;
        }
        THX_CHECK(refine(C, (size_t)ti, surf)); /* marks ti dirty again */
        C->S.rounds++;
    }
    return THX_OK;
}

/* The points at small corners on folds, and the surfaces made faces again, until no more are added
 * (the conformity makes new shells; at most 8 rounds). */
static thx_status fold_loop(conformer *C, const thx_surface *const *surf)
{
    for (int round = 0; round < 8; round++) {
        size_t added = 0;
        THX_CHECK(protect_folds(C, surf, &added));
        if (!added) break;
        C->S.n_fold_points += added;
        THX_CHECK(conform_loop(C, surf));
    }
    return THX_OK;
}

thx_status mesh_conform(thx_ctx *ctx, thx_dt *dt, const thx_surface *const *surf, const size_t *offset, size_t n_surf,
                        double unit, size_t max_steiner, const conform_quality *quality, thx_steiner **steiner, size_t *n_steiner, mesh_subface **sub, size_t *n_sub,
                        conform_stats *stats)
{
    double t0 = thx_wtime();
    *steiner = NULL;
    *n_steiner = 0;
    *sub = NULL;
    *n_sub = 0;
    conformer C;
    memset(&C, 0, sizeof C);
    C.ctx = ctx;
    C.dt = dt;
    C.unit = unit;
    C.Q = quality;
    thx_status st = build(&C, surf, offset, n_surf);
    if (st != THX_OK) goto done;
    C.max_st = max_steiner ? max_steiner : 20 * C.nT + 1000;
    C.tdirty = thx_calloc(ctx, C.nT ? C.nT : 1, 1);
    C.edirty = thx_calloc(ctx, C.nE ? C.nE : 1, 1);
    C.tlist = thx_malloc(ctx, (C.nT ? C.nT : 1) * sizeof *C.tlist);
    C.elist = thx_malloc(ctx, (C.nE ? C.nE : 1) * sizeof *C.elist);
    if (!C.tdirty || !C.edirty || !C.tlist || !C.elist) { st = THX_ENOMEM; goto done; }
    for (size_t t = C.nT; t-- > 0;) mark_tri(&C, (int32_t)t);
    C.S.n_triangles = C.nT;
    for (size_t ti = 0; ti < C.nT; ti++)
        C.S.missing_before += !thx_dt_has_face(dt, C.T[ti].c[0], C.T[ti].c[1], C.T[ti].c[2]);
    st = conform_loop(&C, surf);
    if (st != THX_OK) goto done;
    st = fold_loop(&C, surf);
    if (st != THX_OK) goto done;
    if (quality && quality->progress) quality->progress(quality->progress_user, "conformity", 1.0);
    if (quality && (quality->radius_edge > 0 || quality->min_dihedral > 0 || quality->size)) {
        st = refine_quality(&C, quality, surf);
        if (st != THX_OK) goto done;
        st = fold_loop(&C, surf); /* the refinement made new shells */
        if (st != THX_OK) goto done;
    }
    st = collect(&C, sub, n_sub);
    if (st != THX_OK) goto done;
    {
        double mn = INFINITY;
        for (size_t e = 0; e < C.nE; e++)
            for (size_t i = 0; i + 1 < C.E[e].n; i++) {
                double l = dist3(X(&C, C.E[e].pt[i].node), X(&C, C.E[e].pt[i + 1].node));
                if (l < mn) mn = l;
            }
        C.S.min_piece = mn;
    }
    *steiner = C.st;
    *n_steiner = C.n_st;
    C.st = NULL;
done:
    C.S.seconds = thx_wtime() - t0;
    if (stats) *stats = C.S;
    for (size_t e = 0; e < C.nE; e++) free(C.E[e].pt);
    for (size_t t = 0; t < C.nT; t++) free(C.T[t].in);
    free(C.E);
    free(C.T);
    free(C.st);
    free(C.P);
    free(C.F);
    free(C.own_head);
    free(C.lidx);
    free(C.lstamp);
    free(C.tdirty);
    free(C.edirty);
    free(C.tlist);
    free(C.elist);
    free(C.rq);
    free(C.node_edge);
    free(C.pool);
    return st;
}
