/* The sharp folds of a surface of given potentials and the graded size around them (folds.h). */
#include "mesh/folds.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct {
    int32_t a, b; /* a < b */
    int32_t t, third;
} half_edge;

static int cmp_half(const void *x, const void *y)
{
    const half_edge *p = x, *q = y;
    if (p->a != q->a) return p->a < q->a ? -1 : 1;
    if (p->b != q->b) return p->b < q->b ? -1 : 1;
    return p->t < q->t ? -1 : p->t > q->t;
}

static void sub3(const double *a, const double *b, double *r) { r[0] = a[0] - b[0]; r[1] = a[1] - b[1]; r[2] = a[2] - b[2]; }
static void cross3(const double *u, const double *v, double *r)
{
    r[0] = u[1] * v[2] - u[2] * v[1];
    r[1] = u[2] * v[0] - u[0] * v[2];
    r[2] = u[0] * v[1] - u[1] * v[0];
}
static double dot3(const double *u, const double *v) { return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]; }

double mesh_interior_dihedral(const double a[3], const double b[3], const double c[3], const double d[3])
{
    /* outward normals of (a, b, c) and of the other triangle (b, a, d) */
    double u[3], v[3], n1[3], n2[3];
    sub3(b, a, u);
    sub3(c, a, v);
    cross3(u, v, n1);
    sub3(a, b, u);
    sub3(d, b, v);
    cross3(u, v, n2);
    double l1 = sqrt(dot3(n1, n1)), l2 = sqrt(dot3(n2, n2));
    if (!(l1 > 0) || !(l2 > 0)) return 180.0; /* a degenerate triangle: no fold to speak of */
    double c12 = dot3(n1, n2) / (l1 * l2);
    c12 = c12 < -1 ? -1 : c12 > 1 ? 1 : c12;
    double open = 180.0 - acos(c12) * 180.0 / M_PI; /* between the two faces, on the side the normals leave */
    /* convex edge: d lies below the plane of (a, b, c), the interior angle is the opening; reflex: 360 - it */
    double w[3];
    sub3(d, a, w);
    return dot3(w, n1) <= 0 ? open : 360.0 - open;
}

thx_status mesh_folds_find(thx_ctx *ctx, const thx_surface *s, double max_deg, double h0, double grade, double hmax,
                           mesh_folds *f)
{
    memset(f, 0, sizeof *f);
    f->h0 = h0;
    f->grade = grade;
    f->hmax = hmax;
    if (!(max_deg > 0) || s->n_tris == 0) return THX_OK;
    size_t nh = 3 * s->n_tris;
    half_edge *H = thx_malloc(ctx, nh * sizeof *H);
    if (!H) return THX_ENOMEM;
    for (size_t t = 0; t < s->n_tris; t++)
        for (int k = 0; k < 3; k++) {
            int32_t p = s->tri[3 * t + k], q = s->tri[3 * t + (k + 1) % 3], r = s->tri[3 * t + (k + 2) % 3];
            H[3 * t + k] = (half_edge){p < q ? p : q, p < q ? q : p, (int32_t)t, r};
        }
    qsort(H, nh, sizeof *H, cmp_half);
    size_t cap = 0;
    thx_status st = THX_OK;
    for (size_t i = 0; i < nh;) {
        size_t j = i;
        while (j < nh && H[j].a == H[i].a && H[j].b == H[i].b) j++;
        if (j - i == 2) {
            /* triangle H[i].t holds the edge as (p, q) in its own order: find which way */
            const int32_t *T = s->tri + 3 * (size_t)H[i].t;
            int32_t p = H[i].a, q = H[i].b;
            for (int k = 0; k < 3; k++)
                if (T[k] == H[i].b && T[(k + 1) % 3] == H[i].a) { p = H[i].b; q = H[i].a; }
            const double *P = s->xyz;
            double ang = mesh_interior_dihedral(P + 3 * (size_t)p, P + 3 * (size_t)q, P + 3 * (size_t)H[i].third,
                                                P + 3 * (size_t)H[i + 1].third);
            if (ang < max_deg) {
                if (f->n >= cap && thx_grow(ctx, (void **)&f->seg, &cap, f->n + 1, 6 * sizeof *f->seg) != THX_OK) {
                    st = THX_ENOMEM;
                    break;
                }
                memcpy(f->seg + 6 * f->n, P + 3 * (size_t)p, 3 * sizeof *f->seg);
                memcpy(f->seg + 6 * f->n + 3, P + 3 * (size_t)q, 3 * sizeof *f->seg);
                f->n++;
            }
        }
        i = j;
    }
    free(H);
    if (st == THX_OK && f->n) {
        double *lo = thx_malloc(ctx, 3 * f->n * sizeof *lo), *hi = thx_malloc(ctx, 3 * f->n * sizeof *hi);
        if (!lo || !hi) st = THX_ENOMEM;
        for (size_t k = 0; st == THX_OK && k < f->n; k++)
            for (int d = 0; d < 3; d++) {
                lo[3 * k + d] = fmin(f->seg[6 * k + d], f->seg[6 * k + 3 + d]);
                hi[3 * k + d] = fmax(f->seg[6 * k + d], f->seg[6 * k + 3 + d]);
            }
        if (st == THX_OK) st = thx_bvh_create(ctx, lo, hi, f->n, &f->bvh);
        free(lo);
        free(hi);
    }
    if (st != THX_OK) mesh_folds_free(f);
    return st;
}

typedef struct {
    const mesh_folds *f;
    const double *p;
    double best; /* squared */
} near_fold;

static int visit(void *user, size_t k)
{
    near_fold *n = user;
    const double *a = n->f->seg + 6 * k, *b = a + 3;
    double ab[3], ap[3];
    sub3(b, a, ab);
    sub3(n->p, a, ap);
    double l2 = dot3(ab, ab), t = l2 > 0 ? dot3(ab, ap) / l2 : 0;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    double q[3] = {ap[0] - t * ab[0], ap[1] - t * ab[1], ap[2] - t * ab[2]};
    double d2 = dot3(q, q);
    if (d2 < n->best) n->best = d2;
    return 0;
}

double mesh_folds_size(const mesh_folds *f, const double p[3])
{
    if (!f || !f->n || !(f->grade > 0) || f->h0 >= f->hmax) return INFINITY;
    double reach = (f->hmax - f->h0) / f->grade; /* beyond this distance there is no bound */
    double lo[3] = {p[0] - reach, p[1] - reach, p[2] - reach}, hi[3] = {p[0] + reach, p[1] + reach, p[2] + reach};
    near_fold n = {f, p, reach * reach};
    thx_bvh_query_box(f->bvh, lo, hi, visit, &n);
    double h = f->h0 + f->grade * sqrt(n.best);
    return h < f->hmax ? h : INFINITY;
}

void mesh_folds_free(mesh_folds *f)
{
    if (!f) return;
    free(f->seg);
    thx_bvh_destroy(&f->bvh);
    memset(f, 0, sizeof *f);
}
