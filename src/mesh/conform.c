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
#include "thorax/cdt.h"

#define MIN_PIECE 1e-4 /* mm: shorter pieces mean surfaces touching or crossing */
#define MAX_ROUNDS 200

typedef struct { double t; int32_t node; } cpt;

typedef struct {
    int32_t a, b;      /* volume nodes, a < b */
    int32_t surf, tri; /* the first triangle holding the edge (for the Steiner record) */
    int32_t t0;        /* that triangle's index in the conformer */
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
    conform_stats S;
} conformer;

static double stored(double x)
{
    char buf[64];
    snprintf(buf, sizeof buf, "%.6f", x);
    return strtod(buf, NULL);
}

static const double *X(const conformer *C, int32_t i) { return thx_dt_point(C->dt, i); }

static double dist3(const double *a, const double *b)
{
    double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
    return sqrt(dx * dx + dy * dy + dz * dz);
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
            E->pt = thx_malloc(C->ctx, 4 * sizeof *E->pt);
            if (!E->pt) { free(r); return THX_ENOMEM; }
            E->cap = 4;
            E->n = 2;
            E->pt[0] = (cpt){0.0, E->a};
            E->pt[1] = (cpt){1.0, E->b};
        }
        C->T[r[i].t].e[r[i].k] = (int32_t)(e - 1);
    }
    C->nE = nE;
    free(r);
    return THX_OK;
}

/* Barycentric coordinates of point p in triangle T (corners a, b, c), by least squares in its plane. */
static void barycentric(const double *a, const double *b, const double *c, const double *p, double w[3])
{
    double u[3], v[3], q[3];
    for (int k = 0; k < 3; k++) { u[k] = b[k] - a[k]; v[k] = c[k] - a[k]; q[k] = p[k] - a[k]; }
    double uu = u[0] * u[0] + u[1] * u[1] + u[2] * u[2], vv = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
    double uv = u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
    double qu = q[0] * u[0] + q[1] * u[1] + q[2] * u[2], qv = q[0] * v[0] + q[1] * v[1] + q[2] * v[2];
    double det = uu * vv - uv * uv;
    double s = (qu * vv - qv * uv) / det, t = (qv * uu - qu * uv) / det;
    w[0] = 1 - s - t;
    w[1] = s;
    w[2] = t;
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
    double p[3];
    for (int d = 0; d < 3; d++) p[d] = stored(A[d] + t * (B[d] - A[d]));
    double len = dist3(X(C, E->pt[k].node), X(C, E->pt[k + 1].node));
    if (len < 2 * MIN_PIECE) return too_fine(C, E->surf, E->tri, p, "a surface edge would be cut into pieces shorter than 1e-4 mm", surf);
    if (C->n_st >= C->max_st) return too_fine(C, E->surf, E->tri, p, "too many points were added to make it a union of faces", surf);
    int32_t idx;
    thx_status st = thx_dt_insert(C->dt, p, E->pt[k].node, &idx);
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
    C->S.n_edge_points++;
    return THX_OK;
}

/* Makes every piece of every surface edge an edge of the tetrahedralization. Returns the
 * number of points added (in *added). */
static thx_status edge_pass(conformer *C, const thx_surface *const *surf, size_t *added)
{
    *added = 0;
    for (size_t e = 0; e < C->nE; e++) {
        cedge *E = &C->E[e];
        for (size_t k = 0; k + 1 < E->n;) {
            if (thx_dt_has_edge(C->dt, E->pt[k].node, E->pt[k + 1].node)) { k++; continue; }
            THX_CHECK(split_piece(C, e, k, surf));
            (*added)++;
            E = &C->E[e];
            /* the new piece k (left half) is tested again */
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
#define ADD(nd, mk)                                                                                   \
    do {                                                                                              \
        const double *q_ = X(C, nd);                                                                  \
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

static int find_pt(const conformer *C, int32_t node)
{
    for (size_t i = 0; i < C->nP; i++)
        if (C->P[i].node == node) return (int)i;
    return -1;
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

/* Inserts a point inside triangle ti at 2D position (x, y) of its frame. */
static thx_status add_inside(conformer *C, size_t ti, const double w[3], const thx_surface *const *surf)
{
    ctri *T = &C->T[ti];
    const double *c0 = X(C, T->c[0]), *c1 = X(C, T->c[1]), *c2 = X(C, T->c[2]);
    double p[3];
    for (int d = 0; d < 3; d++) p[d] = stored(w[0] * c0[d] + w[1] * c1[d] + w[2] * c2[d]);
    if (C->n_st >= C->max_st) return too_fine(C, T->surf, T->tri, p, "too many points were added to make it a union of faces", surf);
    int32_t idx;
    thx_status st = thx_dt_insert(C->dt, p, T->c[0], &idx);
    if (st == THX_EGEOM) return too_fine(C, T->surf, T->tri, p, "a point added on a surface triangle falls on another node", surf);
    THX_CHECK(st);
    if (T->n_in >= T->cap_in) THX_CHECK(thx_grow(C->ctx, (void **)&T->in, &T->cap_in, T->n_in + 1, sizeof *T->in));
    T->in[T->n_in++] = idx;
    double wb[3];
    barycentric(c0, c1, c2, p, wb);
    THX_CHECK(add_record(C, idx, T->surf, T->tri, wb));
    C->S.n_face_points++;
    return THX_OK;
}

/* Refines triangle ti once (it is not covered): a circumcentre inside, or a split of a piece of its edges. */
static thx_status refine(conformer *C, size_t ti, const thx_surface *const *surf)
{
    THX_CHECK(gather(C, ti));
    ctri *T = &C->T[ti];
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
        double bx = b->x - a->x, by = b->y - a->y, qx = c->x - a->x, qy = c->y - a->y;
        double d = 2 * (bx * qy - by * qx);
        if (!(fabs(d) > 0)) continue;
        double b2 = bx * bx + by * by, q2 = qx * qx + qy * qy;
        double ux = (qy * b2 - by * q2) / d, uy = (bx * q2 - qx * b2) / d;
        double r = sqrt(ux * ux + uy * uy);
        if (r > best_r) { best_r = r; cx = a->x + ux; cy = a->y + uy; }
    }
    free(tris);
    /* the pieces of the triangle's edges: is the centre in one's diametral circle, or outside? */
    size_t best_e = 0, best_k = 0;
    double best_len = -1, near_d = INFINITY;
    size_t near_e = 0, near_k = 0, long_e = 0, long_k = 0;
    double long_len = -1;
    for (int k = 0; k < 3; k++) {
        size_t e = (size_t)T->e[k];
        const cedge *G = &C->E[e];
        for (size_t i = 0; i + 1 < G->n; i++) {
            int a = find_pt(C, G->pt[i].node), b = find_pt(C, G->pt[i + 1].node);
            double ax = C->P[a].x, ay = C->P[a].y, bx = C->P[b].x, by = C->P[b].y;
            double mx = 0.5 * (ax + bx), my = 0.5 * (ay + by);
            double len = hypot(bx - ax, by - ay);
            if (len > long_len) { long_len = len; long_e = e; long_k = i; }
            if (best_r < 0) continue;
            if (hypot(cx - mx, cy - my) < 0.5 * len && len > best_len) { best_len = len; best_e = e; best_k = i; }
            /* distance from the centre to the piece */
            double dx = bx - ax, dy = by - ay, s = ((cx - ax) * dx + (cy - ay) * dy) / (dx * dx + dy * dy);
            s = s < 0 ? 0 : s > 1 ? 1 : s;
            double dd = hypot(cx - ax - s * dx, cy - ay - s * dy);
            if (dd < near_d) { near_d = dd; near_e = e; near_k = i; }
        }
    }
    if (best_r < 0) return split_piece(C, long_e, long_k, surf); /* no missing piece seen: split the longest */
    if (best_len > 0) return split_piece(C, best_e, best_k, surf);
    /* barycentric coordinates of the centre (2D frame: corner 0 at the origin) */
    const tpt *p0 = &C->P[0], *p1 = &C->P[1], *p2 = &C->P[2];
    double det = (p1->x - p0->x) * (p2->y - p0->y) - (p2->x - p0->x) * (p1->y - p0->y);
    double w1 = ((cx - p0->x) * (p2->y - p0->y) - (p2->x - p0->x) * (cy - p0->y)) / det;
    double w2 = ((p1->x - p0->x) * (cy - p0->y) - (cx - p0->x) * (p1->y - p0->y)) / det;
    double w[3] = {1 - w1 - w2, w1, w2};
    const double margin = 1e-9;
    if (w[0] < margin || w[1] < margin || w[2] < margin) return split_piece(C, near_e, near_k, surf);
    return add_inside(C, ti, w, surf);
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

thx_status mesh_conform(thx_ctx *ctx, thx_dt *dt, const thx_surface *const *surf, const size_t *offset, size_t n_surf,
                        size_t max_steiner, thx_steiner **steiner, size_t *n_steiner, mesh_subface **sub, size_t *n_sub,
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
    thx_status st = build(&C, surf, offset, n_surf);
    if (st != THX_OK) goto done;
    C.max_st = max_steiner ? max_steiner : 20 * C.nT + 1000;
    C.S.n_triangles = C.nT;
    for (size_t ti = 0; ti < C.nT; ti++)
        C.S.missing_before += !thx_dt_has_face(dt, C.T[ti].c[0], C.T[ti].c[1], C.T[ti].c[2]);
    for (size_t round = 0;; round++) {
        if (round >= MAX_ROUNDS) {
            st = thx_error(ctx, THX_EGEOM, "mesh: the surfaces could not be made faces of the mesh in %d rounds", MAX_ROUNDS);
            goto done;
        }
        size_t added = 0, refined = 0;
        st = edge_pass(&C, surf, &added);
        if (st != THX_OK) goto done;
        for (size_t ti = 0; ti < C.nT; ti++) {
            ctri *T = &C.T[ti];
            int covered;
            if (T->n_in == 0 && C.E[T->e[0]].n == 2 && C.E[T->e[1]].n == 2 && C.E[T->e[2]].n == 2)
                covered = thx_dt_has_face(dt, T->c[0], T->c[1], T->c[2]);
            else {
                st = gather(&C, ti);
                if (st == THX_OK) st = cover(&C, ti, &covered);
                if (st != THX_OK) goto done;
            }
            if (covered) continue;
            /* a piece of its edges may have gone since the edge pass: those first */
            int edges_ok = 1;
            for (int k = 0; k < 3 && edges_ok; k++) {
                const cedge *G = &C.E[T->e[k]];
                for (size_t i = 0; i + 1 < G->n && edges_ok; i++)
                    edges_ok = thx_dt_has_edge(dt, G->pt[i].node, G->pt[i + 1].node);
            }
            if (!edges_ok) continue; /* the next edge pass */
            st = refine(&C, ti, surf);
            if (st != THX_OK) goto done;
            refined++;
        }
        C.S.rounds = round + 1;
        if (added == 0 && refined == 0) {
            /* nothing added in a whole round: every edge piece and triangle is there */
            size_t more = 0;
            st = edge_pass(&C, surf, &more);
            if (st != THX_OK) goto done;
            if (more == 0) break;
        }
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
    return st;
}
