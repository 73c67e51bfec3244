/* Picking: the nearest surface, triangle and node along a ray (see thorax/geom/pick.h). */
#include "thorax/geom/pick.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/geom/predicates.h"
#include "thorax/geom/spatial.h"

struct thx_pick_index {
    size_t n;
    const thx_surface **surf; /* n borrowed surfaces (the array is ours) */
    thx_bvh **bvh;            /* one tree per surface over its triangles' boxes */
    double *lo, *hi;          /* 3 per surface: its bounding box (empty surface: lo > hi) */
};

void thx_pick_opts_default(thx_pick_opts *o)
{
    memset(o, 0, sizeof *o);
    o->t_max = INFINITY;
}

int thx_pick_ray_prepare(thx_ray *r, const double origin[3], const double dir[3])
{
    for (int a = 0; a < 3; a++)
        if (!isfinite(origin[a]) || !isfinite(dir[a])) return -1;
    double len = sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
    if (!(len > 0) || !isfinite(len)) return -1;
    for (int a = 0; a < 3; a++) {
        r->o[a] = origin[a];
        r->d[a] = dir[a] / len;
    }
    /* the axis the ray runs along most becomes z; x and y follow cyclically, swapped when the ray
     * runs toward -z so that the projection keeps the triangles' winding */
    int kz = 0;
    if (fabs(dir[1]) > fabs(dir[kz])) kz = 1;
    if (fabs(dir[2]) > fabs(dir[kz])) kz = 2;
    int kx = (kz + 1) % 3, ky = (kx + 1) % 3;
    if (r->d[kz] < 0) {
        int t = kx;
        kx = ky;
        ky = t;
    }
    r->kx = kx;
    r->ky = ky;
    r->kz = kz;
    /* the shear from the direction as given (a ratio: the same for any length), so that a direction
     * of small integers gives exact projections and a ray through a vertex exact zeros */
    r->sx = dir[kx] / dir[kz];
    r->sy = dir[ky] / dir[kz];
    r->sz = 1.0 / r->d[kz];
    return 0;
}

/*
 * The edge function of the projected edge p -> q at the ray (the origin of the projected plane):
 * q.x p.y - q.y p.x, its sign exact (thx_orient2d). The same edge seen from the neighbouring
 * triangle (q -> p) gives exactly the opposite value and sign. A zero (the ray through the edge's
 * line) takes the sign of the function at the perturbed ray (e, e^2), e -> 0+: the sign of its
 * gradient there, (q.y - p.y, p.x - q.x), first component first. *sign is 0 only for an edge of
 * zero length in projection.
 */
static double edge_fn(const double p[2], const double q[2], int *sign)
{
    static const double zero[2] = {0.0, 0.0};
    double f = thx_orient2d(q, p, zero);
    if (f > 0) *sign = 1;
    else if (f < 0) *sign = -1;
    else {
        double gx = q[1] - p[1], gy = p[0] - q[0];
        *sign = gx > 0 ? 1 : gx < 0 ? -1 : gy > 0 ? 1 : gy < 0 ? -1 : 0;
    }
    return f;
}

/* The vertex v in the ray's sheared frame: (x, y) in the projected plane and the scaled depth z. */
static void project(const thx_ray *r, const double v[3], double xy[2], double *z)
{
    double a[3] = {v[0] - r->o[0], v[1] - r->o[1], v[2] - r->o[2]};
    xy[0] = a[r->kx] - r->sx * a[r->kz];
    xy[1] = a[r->ky] - r->sy * a[r->kz];
    *z = r->sz * a[r->kz];
}

int thx_pick_triangle(const thx_ray *r, const double a[3], const double b[3], const double c[3], double *t,
                      double bary[3])
{
    double A[2], B[2], C[2], az, bz, cz;
    project(r, a, A, &az);
    project(r, b, B, &bz);
    project(r, c, C, &cz);
    int su, sv, sw;
    double U = edge_fn(B, C, &su); /* edge b-c: the weight of a */
    double V = edge_fn(C, A, &sv); /* edge c-a: the weight of b */
    double W = edge_fn(A, B, &sw); /* edge a-b: the weight of c */
    if (su == 0 || su != sv || su != sw) return 0;
    double det = U + V + W;
    if (det == 0) return 0; /* the ray lies in the triangle's plane */
    if (t) *t = (U * az + V * bz + W * cz) / det;
    if (bary) {
        bary[0] = U / det;
        bary[1] = V / det;
        bary[2] = W / det;
    }
    return 1;
}

static int clip_keeps(const thx_pick_opts *o, const double p[3])
{
    for (size_t k = 0; k < o->n_clip; k++) {
        const thx_pick_plane *pl = &o->clip[k];
        if (!(pl->n[0] * p[0] + pl->n[1] * p[1] + pl->n[2] * p[2] + pl->d >= 0)) return 0;
    }
    return 1;
}

static thx_status check_opts(thx_ctx *ctx, const thx_pick_opts *o, const char *what)
{
    for (size_t k = 0; k < o->n_clip; k++) {
        const thx_pick_plane *pl = &o->clip[k];
        if (!isfinite(pl->n[0]) || !isfinite(pl->n[1]) || !isfinite(pl->n[2]) || !isfinite(pl->d))
            return thx_error(ctx, THX_EINPUT, "%s: clip plane %zu is not finite", what, k + 1);
    }
    if (isnan(o->t_max)) return thx_error(ctx, THX_EINPUT, "%s: t_max is not a number", what);
    return THX_OK;
}

static void hit_clear(thx_pick_hit *hit)
{
    memset(hit, 0, sizeof *hit);
    hit->surface = -1;
    hit->tri = (size_t)-1;
    hit->t = INFINITY;
}

/* The search for the nearest hit: one ray, the options, the best hit so far. */
typedef struct {
    thx_ray ray;
    const thx_pick_opts *o;
    const thx_surface *s;
    int si;
    thx_pick_hit *best;
} search;

/* Tests triangle ti of the current surface and keeps it if it is the nearest accepted hit so far
 * (order: t, then surface, then triangle: the answer does not depend on the visiting order). */
static void try_triangle(search *q, size_t ti)
{
    const thx_surface *s = q->s;
    const int32_t *tv = s->tri + 3 * ti;
    const double *a = s->xyz + 3 * (size_t)tv[0], *b = s->xyz + 3 * (size_t)tv[1], *c = s->xyz + 3 * (size_t)tv[2];
    double t, w[3];
    if (!thx_pick_triangle(&q->ray, a, b, c, &t, w)) return;
    if (!(t >= 0) || t > q->o->t_max) return;
    thx_pick_hit *h = q->best;
    if (t > h->t || (t == h->t && (q->si > h->surface || (q->si == h->surface && ti > h->tri)))) return;
    double p[3];
    for (int k = 0; k < 3; k++) p[k] = w[0] * a[k] + w[1] * b[k] + w[2] * c[k];
    if (!clip_keeps(q->o, p)) return;
    h->surface = q->si;
    h->tri = ti;
    h->t = t;
    memcpy(h->bary, w, sizeof w);
    memcpy(h->point, p, sizeof p);
}

static int visit(void *user, size_t box)
{
    try_triangle(user, box);
    return 0;
}

/* Fills the derived fields of the best hit: nearest node, face. */
static void finish_hit(const thx_surface *const *surf, const thx_ray *r, thx_pick_hit *h)
{
    if (h->surface < 0) {
        hit_clear(h);
        return;
    }
    const thx_surface *s = surf[h->surface];
    const int32_t *tv = s->tri + 3 * h->tri;
    double best = INFINITY, e1[3], e2[3];
    for (int k = 0; k < 3; k++) {
        const double *v = s->xyz + 3 * (size_t)tv[k];
        double dx = v[0] - h->point[0], dy = v[1] - h->point[1], dz = v[2] - h->point[2];
        double d2 = dx * dx + dy * dy + dz * dz;
        if (d2 < best) {
            best = d2;
            h->node = (size_t)tv[k];
        }
    }
    const double *a = s->xyz + 3 * (size_t)tv[0], *b = s->xyz + 3 * (size_t)tv[1], *c = s->xyz + 3 * (size_t)tv[2];
    for (int k = 0; k < 3; k++) {
        e1[k] = b[k] - a[k];
        e2[k] = c[k] - a[k];
    }
    double nx = e1[1] * e2[2] - e1[2] * e2[1], ny = e1[2] * e2[0] - e1[0] * e2[2], nz = e1[0] * e2[1] - e1[1] * e2[0];
    h->front = nx * r->d[0] + ny * r->d[1] + nz * r->d[2] < 0;
    h->dist = 0;
}

static thx_status prepare(thx_ctx *ctx, thx_ray *r, const double origin[3], const double dir[3],
                          const thx_pick_opts *o, const char *what)
{
    if (thx_pick_ray_prepare(r, origin, dir))
        return thx_error(ctx, THX_EINPUT, "%s: ray origin (%g, %g, %g) direction (%g, %g, %g): not finite, or a zero "
                         "direction", what, origin[0], origin[1], origin[2], dir[0], dir[1], dir[2]);
    return check_opts(ctx, o, what);
}

thx_status thx_pick_ray_brute(thx_ctx *ctx, const thx_surface *const *surf, size_t n, const double origin[3],
                              const double dir[3], const thx_pick_opts *o, thx_pick_hit *hit)
{
    thx_pick_opts def;
    if (!o) {
        thx_pick_opts_default(&def);
        o = &def;
    }
    hit_clear(hit);
    search q = {.o = o, .best = hit};
    THX_CHECK(prepare(ctx, &q.ray, origin, dir, o, "pick"));
    for (size_t s = 0; s < n; s++) {
        if (o->skip && o->skip[s]) continue;
        q.s = surf[s];
        q.si = (int)s;
        for (size_t t = 0; t < surf[s]->n_tris; t++) try_triangle(&q, t);
    }
    finish_hit(surf, &q.ray, hit);
    return THX_OK;
}

/* The part [*t0, *t1] of the ray inside every kept half space, widened a little (the hits are then
 * decided by the point test): 0 when the ray misses the kept region. */
static int clip_interval(const thx_ray *r, const thx_pick_opts *o, double *t0, double *t1)
{
    for (size_t k = 0; k < o->n_clip; k++) {
        const thx_pick_plane *pl = &o->clip[k];
        double g0 = pl->n[0] * r->o[0] + pl->n[1] * r->o[1] + pl->n[2] * r->o[2] + pl->d;
        double gd = pl->n[0] * r->d[0] + pl->n[1] * r->d[1] + pl->n[2] * r->d[2];
        double scale = fabs(pl->n[0] * r->o[0]) + fabs(pl->n[1] * r->o[1]) + fabs(pl->n[2] * r->o[2]) + fabs(pl->d);
        double nn = fabs(pl->n[0]) + fabs(pl->n[1]) + fabs(pl->n[2]);
        if (gd == 0) {
            if (g0 < -1e-9 * scale) return 0;
            continue;
        }
        double tc = -g0 / gd, slack = 1e-9 * (scale + nn) / fabs(gd) + 1e-9 * fabs(tc);
        if (gd > 0) *t0 = fmax(*t0, tc - slack);
        else *t1 = fmin(*t1, tc + slack);
    }
    return *t0 <= *t1;
}

thx_status thx_pick_ray(thx_ctx *ctx, const thx_pick_index *idx, const double origin[3], const double dir[3],
                        const thx_pick_opts *o, thx_pick_hit *hit)
{
    thx_pick_opts def;
    if (!o) {
        thx_pick_opts_default(&def);
        o = &def;
    }
    hit_clear(hit);
    search q = {.o = o, .best = hit};
    THX_CHECK(prepare(ctx, &q.ray, origin, dir, o, "pick"));
    const thx_ray *r = &q.ray;
    for (size_t s = 0; s < idx->n; s++) {
        if (o->skip && o->skip[s]) continue;
        const double *lo = idx->lo + 3 * s, *hi = idx->hi + 3 * s;
        if (!(lo[0] <= hi[0])) continue; /* no triangles */
        /* the farthest the ray can meet the surface: its box's farthest corner */
        double far2 = 0;
        for (int a = 0; a < 3; a++) {
            double m = fmax(fabs(r->o[a] - lo[a]), fabs(r->o[a] - hi[a]));
            far2 += m * m;
        }
        double t0 = 0, t1 = fmin(sqrt(far2) * (1 + 1e-9) + 1e-9, o->t_max * (1 + 1e-12) + 1e-12);
        if (!clip_interval(r, o, &t0, &t1)) continue;
        if (t1 > hit->t) t1 = hit->t * (1 + 1e-12) + 1e-12; /* a nearer hit is known */
        if (t0 > t1) continue;
        double p[3], e[3];
        for (int a = 0; a < 3; a++) {
            p[a] = r->o[a] + t0 * r->d[a];
            e[a] = r->o[a] + t1 * r->d[a];
        }
        q.s = idx->surf[s];
        q.si = (int)s;
        thx_bvh_query_segment(idx->bvh[s], p, e, visit, &q);
    }
    finish_hit(idx->surf, r, hit);
    return THX_OK;
}

thx_status thx_pick_node(thx_ctx *ctx, const thx_pick_index *idx, const double origin[3], const double dir[3],
                         double tol, double slope, const thx_pick_opts *o, thx_pick_hit *hit)
{
    thx_pick_opts def;
    if (!o) {
        thx_pick_opts_default(&def);
        o = &def;
    }
    hit_clear(hit);
    thx_ray r;
    THX_CHECK(prepare(ctx, &r, origin, dir, o, "pick node"));
    if (!(tol >= 0) || !(slope >= 0) || !isfinite(tol) || !isfinite(slope))
        return thx_error(ctx, THX_EINPUT, "pick node: tolerance %g mm + %g per mm of depth: must be finite and >= 0",
                         tol, slope);
    double best_score = INFINITY;
    for (size_t s = 0; s < idx->n; s++) {
        if (o->skip && o->skip[s]) continue;
        const thx_surface *sf = idx->surf[s];
        for (size_t i = 0; i < sf->n_nodes; i++) {
            const double *p = sf->xyz + 3 * i;
            double v[3] = {p[0] - r.o[0], p[1] - r.o[1], p[2] - r.o[2]};
            double t = v[0] * r.d[0] + v[1] * r.d[1] + v[2] * r.d[2];
            if (!(t >= 0) || t > o->t_max) continue;
            double w[3] = {v[0] - t * r.d[0], v[1] - t * r.d[1], v[2] - t * r.d[2]};
            double dist = sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
            double allowed = tol + slope * t;
            if (dist > allowed) continue;
            double score = allowed > 0 ? dist / allowed : 0;
            /* nodes in order of (score, t, surface, node): the first one kept stays on ties */
            if (score > best_score || (score == best_score && t >= hit->t)) continue;
            if (!clip_keeps(o, p)) continue;
            best_score = score;
            hit->surface = (int)s;
            hit->node = i;
            hit->t = t;
            hit->dist = dist;
            memcpy(hit->point, p, sizeof hit->point);
        }
    }
    if (hit->surface < 0) hit_clear(hit);
    return THX_OK;
}

thx_status thx_pick_index_create(thx_ctx *ctx, const thx_surface *const *surf, size_t n, thx_pick_index **out)
{
    *out = NULL;
    if (n > INT32_MAX) return thx_error(ctx, THX_EINPUT, "pick: %zu surfaces is more than supported", n);
    for (size_t s = 0; s < n; s++) THX_CHECK(thx_surface_validate(ctx, surf[s]));
    thx_pick_index *x = thx_calloc(ctx, 1, sizeof *x);
    if (!x) return THX_ENOMEM;
    x->n = n;
    x->surf = thx_calloc(ctx, n ? n : 1, sizeof *x->surf);
    x->bvh = thx_calloc(ctx, n ? n : 1, sizeof *x->bvh);
    x->lo = thx_malloc(ctx, (n ? 3 * n : 1) * sizeof(double));
    x->hi = thx_malloc(ctx, (n ? 3 * n : 1) * sizeof(double));
    if (!x->surf || !x->bvh || !x->lo || !x->hi) {
        thx_pick_index_destroy(&x);
        return THX_ENOMEM;
    }
    for (size_t s = 0; s < n; s++) {
        const thx_surface *sf = surf[s];
        x->surf[s] = sf;
        thx_status st = thx_bvh_create_triangles(ctx, sf->xyz, sf->n_nodes, sf->tri, sf->n_tris, &x->bvh[s]);
        if (st != THX_OK) {
            thx_pick_index_destroy(&x);
            return st;
        }
        double *lo = x->lo + 3 * s, *hi = x->hi + 3 * s;
        for (int a = 0; a < 3; a++) {
            lo[a] = INFINITY;
            hi[a] = -INFINITY;
        }
        for (size_t k = 0; k < 3 * sf->n_tris; k++) {
            const double *v = sf->xyz + 3 * (size_t)sf->tri[k];
            for (int a = 0; a < 3; a++) {
                lo[a] = fmin(lo[a], v[a]);
                hi[a] = fmax(hi[a], v[a]);
            }
        }
    }
    *out = x;
    return THX_OK;
}

void thx_pick_index_destroy(thx_pick_index **idx)
{
    if (!idx || !*idx) return;
    thx_pick_index *x = *idx;
    if (x->bvh)
        for (size_t s = 0; s < x->n; s++) thx_bvh_destroy(&x->bvh[s]);
    free(x->bvh);
    free(x->surf);
    free(x->lo);
    free(x->hi);
    free(x);
    *idx = NULL;
}
