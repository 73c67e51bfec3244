/*
 * Does a closed loop touch itself? (thorax/geom/predicates.h, thx_loop_touch)
 *
 * Shamos and Hoey's sweep: the edges are ordered by the height at which
 * they cross a line sweeping over the points in (x, y) order; two edges that
 * touch are neighbours in that order at some moment before the sweep passes
 * their first common point, so only edges that become neighbours (at an
 * insertion or a removal) are tested. O(n log n): the order is a treap
 * (random priorities, a fixed seed so runs repeat). Every comparison and
 * test is exact (thx_orient2d, thx_segments_touch), so touching counts as
 * well as crossing. At a point, the edges starting there go in before those
 * ending there go out, so edges that only share an end point still meet;
 * the two edges of the loop at one of its nodes share it by construction
 * and are never reported.
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/geom/predicates.h"
typedef struct {
    const double *p;     /* n points, x y */
    size_t n;
    int32_t *lo, *hi;    /* per edge: its first and last point in sweep order */
    int32_t *l, *r, *up; /* treap links per edge, -1 for none */
    uint32_t *pri;
    int32_t root;
    size_t found_i, found_j;
    int found;
} sweep;

static const double *P(const sweep *S, int32_t i) { return S->p + 2 * (size_t)i; }

/* (x, y) order of points a, b: -1, 0, 1 */
static int pcmp(const double *a, const double *b)
{
    if (a[0] != b[0]) return a[0] < b[0] ? -1 : 1;
    if (a[1] != b[1]) return a[1] < b[1] ? -1 : 1;
    return 0;
}

static int adjacent(const sweep *S, size_t i, size_t j)
{
    return i == j || (i + 1) % S->n == j || (j + 1) % S->n == i;
}

/* edges i and j touch (and are not the two edges at one node): recorded */
static void test(sweep *S, int32_t i, int32_t j)
{
    if (S->found || i < 0 || j < 0 || adjacent(S, (size_t)i, (size_t)j)) return;
    if (thx_segments_touch(P(S, S->lo[i]), P(S, S->hi[i]), P(S, S->lo[j]), P(S, S->hi[j]))) {
        S->found = 1;
        S->found_i = (size_t)(i < j ? i : j);
        S->found_j = (size_t)(i < j ? j : i);
    }
}

/* Is edge e (being inserted at its first point) above edge t? */
static int above(const sweep *S, int32_t e, int32_t t)
{
    const double *a = P(S, S->lo[t]), *b = P(S, S->hi[t]);
    double o = thx_orient2d(a, b, P(S, S->lo[e]));
    if (o == 0) o = thx_orient2d(a, b, P(S, S->hi[e])); /* through t's line: by its direction */
    if (o == 0) return e > t;                           /* collinear: touching, and tested */
    return o > 0;
}

static void rotate_up(sweep *S, int32_t x)
{
    int32_t p = S->up[x], g = S->up[p];
    if (S->l[p] == x) { /* right rotation */
        S->l[p] = S->r[x];
        if (S->r[x] >= 0) S->up[S->r[x]] = p;
        S->r[x] = p;
    } else {
        S->r[p] = S->l[x];
        if (S->l[x] >= 0) S->up[S->l[x]] = p;
        S->l[x] = p;
    }
    S->up[p] = x;
    S->up[x] = g;
    if (g < 0) S->root = x;
    else if (S->l[g] == p) S->l[g] = x;
    else S->r[g] = x;
}

static int32_t next(const sweep *S, int32_t x) /* the edge just above x */
{
    if (S->r[x] >= 0) {
        x = S->r[x];
        while (S->l[x] >= 0) x = S->l[x];
        return x;
    }
    while (S->up[x] >= 0 && S->r[S->up[x]] == x) x = S->up[x];
    return S->up[x];
}

static int32_t prev(const sweep *S, int32_t x) /* the edge just below x */
{
    if (S->l[x] >= 0) {
        x = S->l[x];
        while (S->r[x] >= 0) x = S->r[x];
        return x;
    }
    while (S->up[x] >= 0 && S->l[S->up[x]] == x) x = S->up[x];
    return S->up[x];
}

/* Does the active edge t pass through point q? */
static int through(const sweep *S, int32_t t, const double *q)
{
    const double *a = P(S, S->lo[t]), *b = P(S, S->hi[t]);
    return thx_orient2d(a, b, q) == 0 && pcmp(a, q) <= 0 && pcmp(q, b) <= 0;
}

/* Edge e against every edge through its event point q: those are next to each other in the order
 * (before any touch is found the order is a true vertical order), so the scan runs over them only
 * and stops after at most the two edges next to e along the loop. This finds the touches a third
 * edge through q would hide (one collinear with e's neighbour, say). */
static void scan(sweep *S, int32_t e, const double *q)
{
    for (int32_t t = next(S, e); t >= 0 && !S->found && through(S, t, q); t = next(S, t)) test(S, e, t);
    for (int32_t t = prev(S, e); t >= 0 && !S->found && through(S, t, q); t = prev(S, t)) test(S, e, t);
}

static void insert(sweep *S, int32_t e)
{
    S->l[e] = S->r[e] = S->up[e] = -1;
    if (S->root < 0) { S->root = e; return; }
    int32_t t = S->root;
    for (;;) {
        int32_t *child = above(S, e, t) ? &S->r[t] : &S->l[t];
        if (*child < 0) { *child = e; S->up[e] = t; break; }
        t = *child;
    }
    while (S->up[e] >= 0 && S->pri[S->up[e]] < S->pri[e]) rotate_up(S, e);
    test(S, e, next(S, e));
    test(S, e, prev(S, e));
    scan(S, e, P(S, S->lo[e]));
}

static void erase(sweep *S, int32_t e)
{
    scan(S, e, P(S, S->hi[e]));
    if (S->found) return;
    int32_t a = next(S, e), b = prev(S, e);
    /* rotate e down to a leaf, then cut it off */
    while (S->l[e] >= 0 || S->r[e] >= 0) {
        int32_t c = S->l[e] < 0 ? S->r[e] : S->r[e] < 0 ? S->l[e] : S->pri[S->l[e]] > S->pri[S->r[e]] ? S->l[e] : S->r[e];
        rotate_up(S, c);
    }
    int32_t p = S->up[e];
    if (p < 0) S->root = -1;
    else if (S->l[p] == e) S->l[p] = -1;
    else S->r[p] = -1;
    S->up[e] = -1;
    test(S, a, b);
}

typedef struct { int32_t pt, edge, start; } event;
static int cmp_event(const void *x, const void *y, void *pts)
{
    const event *a = x, *b = y;
    const double *q = pts;
    int c = pcmp(q + 2 * (size_t)a->pt, q + 2 * (size_t)b->pt);
    if (c) return c;
    if (a->start != b->start) return a->start ? -1 : 1; /* at one point: insertions first */
    return (a->edge > b->edge) - (a->edge < b->edge);
}

int thx_loop_touch(const double *xy, size_t n, size_t *ei, size_t *ej)
{
    if (n < 4) return 0; /* a triangle (or less) cannot touch itself but through its own nodes */
    sweep S;
    memset(&S, 0, sizeof S);
    S.p = xy;
    S.n = n;
    S.root = -1;
    S.lo = malloc(n * sizeof *S.lo);
    S.hi = malloc(n * sizeof *S.hi);
    S.l = malloc(n * sizeof *S.l);
    S.r = malloc(n * sizeof *S.r);
    S.up = malloc(n * sizeof *S.up);
    S.pri = malloc(n * sizeof *S.pri);
    event *ev = malloc(2 * n * sizeof *ev);
    int rc = -1;
    if (!S.lo || !S.hi || !S.l || !S.r || !S.up || !S.pri || !ev) goto done;
    uint32_t seed = 2463534242u;
    for (size_t i = 0; i < n; i++) {
        int32_t a = (int32_t)i, b = (int32_t)((i + 1) % n);
        int c = pcmp(xy + 2 * (size_t)a, xy + 2 * (size_t)b);
        S.lo[i] = c <= 0 ? a : b;
        S.hi[i] = c <= 0 ? b : a;
        seed ^= seed << 13; seed ^= seed >> 17; seed ^= seed << 5; /* xorshift */
        S.pri[i] = seed;
        ev[2 * i] = (event){S.lo[i], (int32_t)i, 1};
        ev[2 * i + 1] = (event){S.hi[i], (int32_t)i, 0};
    }
    qsort_r(ev, 2 * n, sizeof *ev, cmp_event, (void *)xy);
    for (size_t k = 0; k < 2 * n && !S.found; k++) {
        if (ev[k].start) insert(&S, ev[k].edge);
        else erase(&S, ev[k].edge);
    }
    rc = S.found;
    if (S.found) { *ei = S.found_i; *ej = S.found_j; }
done:
    free(S.lo); free(S.hi); free(S.l); free(S.r); free(S.up); free(S.pri); free(ev);
    return rc;
}
