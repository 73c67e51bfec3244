/*
 * Cross-sections of a closed triangle surface with a plane z = z0 (see thorax/geom/slice.h).
 *
 * Every node gets a side: above (z >= z0) or below. A triangle with nodes on
 * both sides crosses the plane along a segment joining the crossing points of
 * its two edges that change side. With the surface closed, every crossing edge
 * belongs to two such triangles, so the segments join into closed loops when
 * walked from crossing edge to crossing edge. Orientation: for a triangle
 * counterclockwise from outside, entering through the edge that goes downward
 * (above -> below, in the triangle's order) and leaving through the one that
 * goes upward keeps the material on the left, so the loop is counterclockwise
 * seen from above.
 */
#include "thorax/geom/slice.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct {
    int32_t a, b;    /* crossing edge, a < b */
    int32_t tri;     /* triangle */
    int out;         /* 1: the walk leaves the triangle through this edge */
} xedge;

static int cmp_xedge(const void *x, const void *y)
{
    const xedge *p = x, *q = y;
    if (p->a != q->a) return p->a < q->a ? -1 : 1;
    if (p->b != q->b) return p->b < q->b ? -1 : 1;
    return p->out - q->out;
}

void thx_slice_free(thx_loop **loops, size_t n_loops)
{
    if (!loops || !*loops) return;
    for (size_t k = 0; k < n_loops; k++) free((*loops)[k].p);
    free(*loops);
    *loops = NULL;
}

static thx_vec2 crossing(const thx_surface *s, int32_t a, int32_t b, double z0)
{
    thx_vec3 p = thx_surface_node(s, (size_t)a), q = thx_surface_node(s, (size_t)b);
    double t = (z0 - p.z) / (q.z - p.z);
    if (p.z == z0) t = 0; /* a node on the plane is the crossing point itself */
    if (q.z == z0) t = 1;
    thx_vec2 r = {p.x + t * (q.x - p.x), p.y + t * (q.y - p.y)};
    return r;
}

thx_status thx_surface_slice(thx_ctx *ctx, const thx_surface *s, double z0, thx_loop **loops, size_t *n_loops)
{
    *loops = NULL;
    *n_loops = 0;
    thx_status st = THX_OK;
    size_t nx = 0;
    xedge *x = thx_malloc(ctx, 2 * (s->n_tris ? s->n_tris : 1) * sizeof *x);
    int32_t *next_of = NULL; /* per crossing triangle: index into x of its 'out' edge */
    unsigned char *used = NULL;
    if (!x) return THX_ENOMEM;
    for (size_t t = 0; t < s->n_tris; t++) {
        const int32_t *v = s->tri + 3 * t;
        int up[3];
        for (int k = 0; k < 3; k++) up[k] = s->xyz[3 * (size_t)v[k] + 2] >= z0;
        if (up[0] == up[1] && up[1] == up[2]) continue;
        for (int k = 0; k < 3; k++) {
            int32_t a = v[k], b = v[(k + 1) % 3];
            if (up[k] == up[(k + 1) % 3]) continue;
            /* In triangle order a -> b: an edge going down is where the walk enters the triangle,
               an edge going up is where it leaves (material on the left, seen from above). */
            x[nx].a = a < b ? a : b;
            x[nx].b = a < b ? b : a;
            x[nx].tri = (int32_t)t;
            x[nx].out = up[k] ? 0 : 1;
            nx++;
        }
    }
    if (nx == 0) { free(x); return THX_OK; }
    /* Pair every 'out' crossing of one triangle with the 'in' crossing of its neighbour on the same edge. */
    qsort(x, nx, sizeof *x, cmp_xedge);
    for (size_t k = 0; k < nx; k += 2) { /* records come in pairs */
        int ok = (k + 1 < nx && x[k + 1].a == x[k].a && x[k + 1].b == x[k].b && x[k].out == 0 && x[k + 1].out == 1) &&
                 (k + 2 >= nx || x[k + 2].a != x[k].a || x[k + 2].b != x[k].b) &&
                 (k == 0 || x[k - 1].a != x[k].a || x[k - 1].b != x[k].b);
        if (!ok) {
            st = thx_error(ctx, THX_EGEOM,
                           "surface \"%s\": the plane z=%g crosses edge %d-%d, which is not shared by exactly two "
                           "consistently oriented triangles",
                           s->name, z0, x[k].a + 1, x[k].b + 1);
            goto done;
        }
    }
    /* For each crossing triangle: its 'in' record and its 'out' record; walk out -> neighbour's in -> its out. */
    next_of = thx_malloc(ctx, s->n_tris * sizeof *next_of);
    int32_t *in_of = thx_malloc(ctx, s->n_tris * sizeof *in_of);
    used = thx_calloc(ctx, nx, 1);
    if (!next_of || !in_of || !used) { free(in_of); st = THX_ENOMEM; goto done; }
    for (size_t k = 0; k < nx; k++) {
        if (x[k].out) next_of[x[k].tri] = (int32_t)k;
        else in_of[x[k].tri] = (int32_t)k;
    }
    size_t cap_loops = 0;
    for (size_t k0 = 0; k0 < nx && st == THX_OK; k0++) {
        if (used[k0] || !x[k0].out) continue;
        /* Start at an 'out' crossing; its partner (same edge, 'in') is x[k0 - 1]. */
        thx_loop lp = {0, NULL, 0, NULL};
        size_t cap = 0;
        size_t k = k0;
        while (!used[k]) {
            used[k] = 1;
            thx_vec2 p = crossing(s, x[k].a, x[k].b, z0);
            if (!(lp.n > 0 && lp.p[lp.n - 1].x == p.x && lp.p[lp.n - 1].y == p.y)) {
                st = thx_grow(ctx, (void **)&lp.p, &cap, lp.n + 1, sizeof *lp.p);
                if (st != THX_OK) break;
                lp.p[lp.n++] = p;
            }
            size_t in = k - 1;        /* the neighbour entering through the same edge */
            used[in] = 1;
            k = (size_t)next_of[x[in].tri];
        }
        if (st != THX_OK) { free(lp.p); break; }
        while (lp.n > 1 && lp.p[0].x == lp.p[lp.n - 1].x && lp.p[0].y == lp.p[lp.n - 1].y) lp.n--;
        if (lp.n < 3) { free(lp.p); continue; } /* a touch at a node: no area */
        st = thx_grow(ctx, (void **)loops, &cap_loops, *n_loops + 1, sizeof **loops);
        if (st != THX_OK) { free(lp.p); break; }
        (*loops)[(*n_loops)++] = lp;
    }
    free(in_of);
done:
    free(x);
    free(next_of);
    free(used);
    if (st != THX_OK) thx_slice_free(loops, *n_loops), *n_loops = 0;
    return st;
}

void thx_slice_opts_default(thx_slice_opts *o)
{
    o->spacing = 5.0;
    o->margin = -1;
    o->densify = -1;
    o->node_spacing = 0;
    o->axis = 2;
}

/* Where axis a of the model goes when the model is turned so that `axis` becomes z:
 * (x, y, z) -> (y, z, x) for x, (z, x, y) for y (rotations). */
static int turned(int a, int axis) { return (a - axis - 1 + 6) % 3; }

/* Appends loop p to surface k of c at height z, with points inserted along long segments
 * and points closer than 1 micrometre to their predecessor dropped. */
static thx_status add_dense(thx_ctx *ctx, thx_contours *c, size_t k, double z, const thx_loop *lp, double maxlen)
{
    size_t cap = 0, n = 0;
    thx_vec2 *q = NULL;
    for (size_t i = 0; i < lp->n; i++) {
        thx_vec2 a = lp->p[i], b = lp->p[(i + 1) % lp->n];
        double len = hypot(b.x - a.x, b.y - a.y);
        size_t parts = maxlen > 0 ? (size_t)ceil(len / maxlen) : 1;
        if (parts < 1) parts = 1;
        THX_CHECK(thx_grow(ctx, (void **)&q, &cap, n + parts, sizeof *q));
        for (size_t s = 0; s < parts; s++) {
            thx_vec2 r = {a.x + (b.x - a.x) * (double)s / (double)parts, a.y + (b.y - a.y) * (double)s / (double)parts};
            /* Crossings closer than a micrometre are one point (the text format keeps 6 decimals). */
            if (n > 0 && hypot(r.x - q[n - 1].x, r.y - q[n - 1].y) < 1e-3) continue;
            q[n++] = r;
        }
    }
    while (n > 1 && hypot(q[0].x - q[n - 1].x, q[0].y - q[n - 1].y) < 1e-3) n--;
    thx_status st = thx_contours_add_loop(ctx, c, k, z, q, n);
    free(q);
    return st;
}

static thx_status model_slice(thx_ctx *ctx, const thx_model *m, const thx_slice_opts *o, thx_contours **out);

thx_status thx_model_slice(thx_ctx *ctx, const thx_model *m, const thx_slice_opts *o, thx_contours **out)
{
    *out = NULL;
    if (o->axis < 0 || o->axis > 2) return thx_error(ctx, THX_EINPUT, "slice: axis %d is not 0, 1 or 2 (x, y, z)", o->axis);
    if (o->axis == 2) return model_slice(ctx, m, o, out);
    /* the model turned: shallow copies of the surfaces with turned coordinates */
    thx_model t = *m;
    thx_surface *ts = thx_calloc(ctx, m->n_surfaces ? m->n_surfaces : 1, sizeof *ts);
    thx_surface **tp = thx_calloc(ctx, m->n_surfaces ? m->n_surfaces : 1, sizeof *tp);
    thx_status st = ts && tp ? THX_OK : THX_ENOMEM;
    size_t made = 0;
    for (size_t k = 0; k < m->n_surfaces && st == THX_OK; k++) {
        ts[k] = *m->surf[k];
        double *xyz = thx_malloc(ctx, (m->surf[k]->n_nodes ? m->surf[k]->n_nodes : 1) * 3 * sizeof *xyz);
        if (!xyz) { st = THX_ENOMEM; break; }
        for (size_t i = 0; i < m->surf[k]->n_nodes; i++)
            for (int a = 0; a < 3; a++) xyz[3 * i + (size_t)turned(a, o->axis)] = m->surf[k]->xyz[3 * i + (size_t)a];
        ts[k].xyz = xyz;
        tp[k] = &ts[k];
        made++;
    }
    if (st == THX_OK) {
        t.surf = tp;
        if (t.frame.set) {
            t.frame.up.axis = turned(m->frame.up.axis, o->axis);
            t.frame.front.axis = turned(m->frame.front.axis, o->axis);
        }
        thx_slice_opts o2 = *o;
        o2.axis = 2;
        st = model_slice(ctx, &t, &o2, out);
    }
    for (size_t k = 0; k < made; k++) free(ts[k].xyz);
    free(ts);
    free(tp);
    return st;
}

static thx_status model_slice(thx_ctx *ctx, const thx_model *m, const thx_slice_opts *o, thx_contours **out)
{
    *out = NULL;
    if (!(o->spacing > 0)) return thx_error(ctx, THX_EINPUT, "slice: plane spacing must be positive (got %g)", o->spacing);
    double margin = o->margin >= 0 ? o->margin : o->spacing / 10.0;
    double densify = o->densify >= 0 ? o->densify : o->spacing / 2.0;
    double zmin = INFINITY, zmax = -INFINITY;
    for (size_t k = 0; k < m->n_surfaces; k++)
        for (size_t i = 0; i < m->surf[k]->n_nodes; i++) {
            double z = m->surf[k]->xyz[3 * i + 2];
            zmin = fmin(zmin, z);
            zmax = fmax(zmax, z);
        }
    if (!(zmax - zmin > 2 * margin)) return thx_error(ctx, THX_EINPUT, "slice: the model is too flat to slice (z from %g to %g)", zmin, zmax);
    /* Planes evenly from zmin + margin to zmax - margin, at most `spacing` apart. */
    long n_planes = (long)ceil((zmax - zmin - 2 * margin) / o->spacing - 1e-9);
    if (n_planes < 1) n_planes = 1;
    double step = (zmax - zmin - 2 * margin) / (double)n_planes;
    thx_contours *c = NULL;
    thx_status st = thx_contours_create(ctx, &c);
    if (st != THX_OK) return st;
    c->spacing = o->node_spacing > 0 ? o->node_spacing : o->spacing;
    c->frame = m->frame; /* the model's anatomical frame, written as the contour file's 'frame' line */
    for (size_t k = 0; k < m->n_surfaces && st == THX_OK; k++) {
        const thx_surface *s = m->surf[k];
        size_t idx;
        st = thx_contours_add_surface(ctx, c, s->name, s->role, THX_CAP_GRID, 0, &idx);
        int seen = 0, ended = 0;
        double zlo = INFINITY, zhi = -INFINITY;
        for (size_t i = 0; i < s->n_nodes; i++) { zlo = fmin(zlo, s->xyz[3 * i + 2]); zhi = fmax(zhi, s->xyz[3 * i + 2]); }
        for (long p = 0; p <= n_planes && st == THX_OK; p++) {
            double z = p == n_planes ? zmax - margin : zmin + margin + (double)p * step;
            if (z <= zlo || z >= zhi) continue;
            thx_loop *loops = NULL;
            size_t nl = 0;
            st = thx_surface_slice(ctx, s, z, &loops, &nl);
            if (st != THX_OK) break;
            if (nl > 0 && ended) {
                st = thx_error(ctx, THX_EINPUT, "slice: surface \"%s\" has an empty cross-section below z=%g and a "
                               "non-empty one there (a surface must be one stack of layers)", s->name, z);
            }
            for (size_t q = 0; q < nl && st == THX_OK; q++) st = add_dense(ctx, c, idx, z, &loops[q], densify);
            if (nl > 0) seen = 1;
            else if (seen) ended = 1;
            thx_slice_free(&loops, nl);
        }
    }
    if (st == THX_OK) st = thx_contours_validate(ctx, c);
    if (st != THX_OK) thx_contours_destroy(&c);
    *out = c;
    return st;
}
