/* Point location against a closed surface (see locate.h). */
#include "mesh/locate.h"

#include <math.h>
#include <stdlib.h>

#include "thorax/predicates.h"

thx_status locator_init(thx_ctx *ctx, locator *l, const thx_surface *s)
{
    l->s = s;
    l->bvh = NULL;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < s->n_nodes; i++)
        for (int d = 0; d < 3; d++) {
            lo[d] = fmin(lo[d], s->xyz[3 * i + d]);
            hi[d] = fmax(hi[d], s->xyz[3 * i + d]);
        }
    l->reach = 2.0 * (fabs(hi[0] - lo[0]) + fabs(hi[1] - lo[1]) + fabs(hi[2] - lo[2])) + 1.0;
    return thx_bvh_create_triangles(ctx, s->xyz, s->n_nodes, s->tri, s->n_tris, &l->bvh);
}

void locator_free(locator *l) { thx_bvh_destroy(&l->bvh); }

typedef struct {
    const thx_surface *s;
    const double *p, *q;
    int crossings;
    int degenerate;
} ray_state;

static int ray_visit(void *user, size_t t)
{
    ray_state *r = user;
    const thx_surface *s = r->s;
    const double *a = s->xyz + 3 * (size_t)s->tri[3 * t], *b = s->xyz + 3 * (size_t)s->tri[3 * t + 1],
                 *c = s->xyz + 3 * (size_t)s->tri[3 * t + 2];
    double sp = thx_orient3d(a, b, c, r->p), sq = thx_orient3d(a, b, c, r->q);
    if ((sp > 0 && sq > 0) || (sp < 0 && sq < 0)) return 0;
    if (sq == 0) { r->degenerate = 1; return 1; } /* the far end never lies on a triangle; be safe */
    if (sp == 0) return 0;                          /* the point itself on the triangle's plane: not a crossing of the open ray */
    double e0 = thx_orient3d(r->p, r->q, a, b), e1 = thx_orient3d(r->p, r->q, b, c), e2 = thx_orient3d(r->p, r->q, c, a);
    if ((e0 > 0 && e1 > 0 && e2 > 0) || (e0 < 0 && e1 < 0 && e2 < 0)) { r->crossings++; return 0; }
    if ((e0 >= 0 && e1 >= 0 && e2 >= 0) || (e0 <= 0 && e1 <= 0 && e2 <= 0)) { r->degenerate = 1; return 1; }
    return 0;
}

int locator_inside(const locator *l, thx_vec3 p)
{
    /* Fixed, irrational-looking directions: grazing an edge is a measure-zero event; retry if it happens. */
    static const double dir[6][3] = {{0.1327, 0.2461, 0.9601},  {-0.5817, 0.3923, 0.7126}, {0.7713, -0.4172, 0.4806},
                                     {-0.2203, -0.8314, 0.5101}, {0.6151, 0.6612, -0.4295}, {-0.3391, 0.1783, -0.9237}};
    double pp[3] = {p.x, p.y, p.z};
    for (int k = 0; k < 6; k++) {
        double q[3] = {p.x + l->reach * dir[k][0], p.y + l->reach * dir[k][1], p.z + l->reach * dir[k][2]};
        ray_state r = {l->s, pp, q, 0, 0};
        thx_bvh_query_segment(l->bvh, pp, q, ray_visit, &r);
        if (!r.degenerate) return r.crossings & 1;
    }
    return 0;
}

typedef struct {
    const thx_surface *s;
    thx_vec3 p;
    double r2;
} near_state;

/* Squared distance from p to triangle abc (closest-point by regions). */
static double tri_dist2(thx_vec3 p, thx_vec3 a, thx_vec3 b, thx_vec3 c)
{
    thx_vec3 ab = thx_v3_sub(b, a), ac = thx_v3_sub(c, a), ap = thx_v3_sub(p, a);
    double d1 = thx_v3_dot(ab, ap), d2 = thx_v3_dot(ac, ap);
    thx_vec3 q;
    if (d1 <= 0 && d2 <= 0) q = a;
    else {
        thx_vec3 bp = thx_v3_sub(p, b);
        double d3 = thx_v3_dot(ab, bp), d4 = thx_v3_dot(ac, bp);
        thx_vec3 cp = thx_v3_sub(p, c);
        double d5 = thx_v3_dot(ab, cp), d6 = thx_v3_dot(ac, cp);
        double vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
        if (d3 >= 0 && d4 <= d3) q = b;
        else if (d6 >= 0 && d5 <= d6) q = c;
        else if (vc <= 0 && d1 >= 0 && d3 <= 0) q = thx_v3_add(a, thx_v3_scale(ab, d1 / (d1 - d3)));
        else if (vb <= 0 && d2 >= 0 && d6 <= 0) q = thx_v3_add(a, thx_v3_scale(ac, d2 / (d2 - d6)));
        else if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0)
            q = thx_v3_add(b, thx_v3_scale(thx_v3_sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6))));
        else {
            double den = 1.0 / (va + vb + vc);
            q = thx_v3_add(a, thx_v3_add(thx_v3_scale(ab, vb * den), thx_v3_scale(ac, vc * den)));
        }
    }
    thx_vec3 d = thx_v3_sub(p, q);
    return thx_v3_dot(d, d);
}

static int near_visit(void *user, size_t t)
{
    near_state *n = user;
    const thx_surface *s = n->s;
    thx_vec3 a = thx_surface_node(s, (size_t)s->tri[3 * t]), b = thx_surface_node(s, (size_t)s->tri[3 * t + 1]),
             c = thx_surface_node(s, (size_t)s->tri[3 * t + 2]);
    return tri_dist2(n->p, a, b, c) < n->r2;
}

int locator_near(const locator *l, thx_vec3 p, double r)
{
    double lo[3] = {p.x - r, p.y - r, p.z - r}, hi[3] = {p.x + r, p.y + r, p.z + r};
    near_state n = {l->s, p, r * r};
    return thx_bvh_query_box(l->bvh, lo, hi, near_visit, &n) != 0;
}
