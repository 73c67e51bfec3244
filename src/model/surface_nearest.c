/*
 * The nearest point of a triangle surface (thorax/model/surface.h): the electrodes' projection
 * onto the torso (src/model/electrodes_place.c).
 *
 * Per triangle, the closest point is found by the region test on the triangle's plane (the
 * interior, one of three edges or one of three corners), computed from dot products of the
 * edge vectors only, so a degenerate (zero-area) triangle falls to an edge or a corner instead of
 * dividing by zero. The barycentric weights come out of the same test, clamped to [0, 1] and
 * summing to 1 exactly by construction (w0 = 1 - w1 - w2).
 */
#include "thorax/model/surface.h"

#include <math.h>

static double dot3(const double *a, const double *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/* Closest point of triangle (a, b, c) to p: barycentric weights (wa, wb, wc) in w. */
static void closest_on_triangle(const double *p, const double *a, const double *b, const double *c, double w[3])
{
    double ab[3], ac[3], ap[3], bp[3], cp[3];
    for (int k = 0; k < 3; k++) {
        ab[k] = b[k] - a[k];
        ac[k] = c[k] - a[k];
        ap[k] = p[k] - a[k];
        bp[k] = p[k] - b[k];
        cp[k] = p[k] - c[k];
    }
    double d1 = dot3(ab, ap), d2 = dot3(ac, ap);
    if (d1 <= 0 && d2 <= 0) { w[0] = 1; w[1] = w[2] = 0; return; }              /* corner a */
    double d3 = dot3(ab, bp), d4 = dot3(ac, bp);
    if (d3 >= 0 && d4 <= d3) { w[1] = 1; w[0] = w[2] = 0; return; }             /* corner b */
    double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) {                                         /* edge ab */
        double t = d1 / (d1 - d3);
        w[0] = 1 - t; w[1] = t; w[2] = 0;
        return;
    }
    double d5 = dot3(ab, cp), d6 = dot3(ac, cp);
    if (d6 >= 0 && d5 <= d6) { w[2] = 1; w[0] = w[1] = 0; return; }            /* corner c */
    double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) {                                         /* edge ac */
        double t = d2 / (d2 - d6);
        w[0] = 1 - t; w[2] = t; w[1] = 0;
        return;
    }
    double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {                           /* edge bc */
        double t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        w[1] = 1 - t; w[2] = t; w[0] = 0;
        return;
    }
    double den = va + vb + vc;                                                    /* interior */
    double v = vb / den, u = vc / den;
    if (!(v >= 0)) v = 0;
    if (!(u >= 0)) u = 0;
    if (v + u > 1) { double s = v + u; v /= s; u /= s; }
    w[1] = v; w[2] = u; w[0] = 1 - v - u;
}

double thx_surface_nearest(const thx_surface *s, const double p[3], size_t *tri, double w[3], double q[3])
{
    double best = -1;
    for (size_t t = 0; s && t < s->n_tris; t++) {
        const int32_t *T = s->tri + 3 * t;
        const double *a = s->xyz + 3 * (size_t)T[0], *b = s->xyz + 3 * (size_t)T[1], *c = s->xyz + 3 * (size_t)T[2];
        double wt[3], x[3];
        closest_on_triangle(p, a, b, c, wt);
        for (int k = 0; k < 3; k++) x[k] = wt[0] * a[k] + wt[1] * b[k] + wt[2] * c[k];
        double d = sqrt((x[0] - p[0]) * (x[0] - p[0]) + (x[1] - p[1]) * (x[1] - p[1]) + (x[2] - p[2]) * (x[2] - p[2]));
        if (best < 0 || d < best) {
            best = d;
            if (tri) *tri = t;
            if (w) for (int k = 0; k < 3; k++) w[k] = wt[k];
            if (q) for (int k = 0; k < 3; k++) q[k] = x[k];
        }
    }
    return best;
}
