/* Layers (paper 3.1): smoothing spline fit and arc-length resampling. */
#include <math.h>
#include <stdlib.h>

#include "testlib.h"
#include "thorax/geom/inside.h"
#include "thorax/geom/surfaces.h"
static unsigned long long rng = 88172645463325252ULL;
static double urand(void)
{
    rng ^= rng << 13; rng ^= rng >> 7; rng ^= rng << 17;
    return (double)(rng >> 11) / 9007199254740992.0;
}

/* Circle of radius r digitized with n points at uneven angles, optional jitter, either direction. */
static thx_vec2 *digitize_circle(size_t n, double r, double jitter, int cw)
{
    thx_vec2 *p = malloc(n * sizeof *p);
    for (size_t i = 0; i < n; i++) {
        /* uneven spacing: each angle moved by up to +-40% of the mean step */
        double a = 0.3 + 2 * M_PI * ((double)i + 0.8 * (urand() - 0.5)) / (double)n;
        double rr = r + jitter * (2 * urand() - 1);
        p[cw ? n - 1 - i : i].x = 10 + rr * cos(a);
        p[cw ? n - 1 - i : i].y = -5 + rr * sin(a);
    }
    return p;
}

static void check_resampled(thx_ctx *ctx, const thx_vec2 *p, size_t n, double r, double spacing, double smoothing,
                            double rtol, double start_x, double start_y)
{
    thx_vec2 *q = NULL;
    size_t m = 0;
    thx_vec2 start = {start_x, start_y};
    CHECK_OK(ctx, thx_loop_resample(ctx, p, n, spacing, smoothing, start, &q, &m));
    if (!q) return;
    long expect = lround(2 * M_PI * r / spacing);
    CHECK(labs((long)m - expect) <= 1);
    CHECK(thx_loop_area(q, m) > 0); /* counterclockwise whatever the input direction */
    double dmin = INFINITY, dmax = 0, rerr = 0;
    for (size_t i = 0; i < m; i++) {
        thx_vec2 a = q[i], b = q[(i + 1) % m];
        double d = hypot(b.x - a.x, b.y - a.y);
        dmin = fmin(dmin, d);
        dmax = fmax(dmax, d);
        rerr = fmax(rerr, fabs(hypot(a.x - 10, a.y + 5) - r));
    }
    /* constant arc-length spacing: chords of equal arcs are equal on a circle */
    CHECK(dmax - dmin < 0.02 * spacing + 2 * rtol * spacing / r);
    CHECK(rerr < rtol);
    if (!(rerr < rtol) || labs((long)m - expect) > 1 || !(dmax - dmin < 0.02 * spacing + 2 * rtol * spacing / r))
        fprintf(stderr, "  m=%zu expect=%ld dmin=%g dmax=%g rerr=%g\n", m, expect, dmin, dmax, rerr);
    /* the first node is the curve point nearest the start point */
    double ang = atan2(start_y + 5, start_x - 10);
    CHECK(hypot(q[0].x - (10 + r * cos(ang)), q[0].y - (-5 + r * sin(ang))) < rtol + 0.01 * r);
    free(q);
}


/* Distance from q to the closed polygon p (n points). */
static double polygon_distance(thx_vec2 q, const thx_vec2 *p, size_t n)
{
    double best = INFINITY;
    for (size_t i = 0; i < n; i++) {
        thx_vec2 a = p[i], b = p[(i + 1) % n];
        double ux = b.x - a.x, uy = b.y - a.y, t = ((q.x - a.x) * ux + (q.y - a.y) * uy) / (ux * ux + uy * uy);
        t = t < 0 ? 0 : t > 1 ? 1 : t;
        best = fmin(best, hypot(q.x - a.x - t * ux, q.y - a.y - t * uy));
    }
    return best;
}

/* Sparse polygons (40 mm between points, node spacing 5 mm; issue 11 item 6): the rebuilt nodes
 * lie within half the node spacing of the digitized polygon (the free spline overshot it by
 * 5-12 mm). A plus sign with arms 40 mm wide, digitized at its 12 corners only. */
static void test_sparse_polygon(thx_ctx *ctx)
{
    const thx_vec2 plus[12] = {{40, 0},   {80, 0},   {80, 40},  {120, 40}, {120, 80}, {80, 80},
                               {80, 120}, {40, 120}, {40, 80},  {0, 80},   {0, 40},   {40, 40}};
    for (int sm = 0; sm < 2; sm++) {
        thx_vec2 *q = NULL;
        size_t m = 0;
        thx_vec2 s = {0, 1000};
        CHECK_OK(ctx, thx_loop_resample(ctx, plus, 12, 5, sm ? 2.0 : 0.0, s, &q, &m));
        double worst = 0;
        for (size_t i = 0; i < m; i++) worst = fmax(worst, polygon_distance(q[i], plus, 12));
        printf("plus sign digitized at its corners (40 mm edges), spacing 5, smoothing %g: nodes within %.3f mm of the polygon\n",
               sm ? 2.0 : 0.0, worst);
        CHECK(worst < 2.5);
        CHECK(labs((long)m - 96) <= 2); /* perimeter 480 mm */
        free(q);
    }
}

int main(void)
{
    thx_ctx *ctx = NULL;
    thx_ctx_create(&ctx);
    test_sparse_polygon(ctx);
    /* exact circle samples, interpolating spline: node positions within 0.1% of r */
    for (int cw = 0; cw < 2; cw++) {
        thx_vec2 *p = digitize_circle(40, 50, 0, cw);
        check_resampled(ctx, p, 40, 50, 5, 0, 0.05, 10, 1000);
        check_resampled(ctx, p, 40, 50, 2, 0, 0.05, -500, -5); /* start point to the left */
        free(p);
    }
    /* jittered digitization (+-1 mm): smoothing brings the nodes back toward the true circle */
    {
        thx_vec2 *p = digitize_circle(150, 80, 1.0, 1);
        thx_vec2 *q0 = NULL, *q1 = NULL;
        size_t m0 = 0, m1 = 0;
        thx_vec2 s = {0, 1000};
        CHECK_OK(ctx, thx_loop_resample(ctx, p, 150, 5, 0, s, &q0, &m0));
        CHECK_OK(ctx, thx_loop_resample(ctx, p, 150, 5, 4, s, &q1, &m1));
        double e0 = 0, e1 = 0;
        for (size_t i = 0; i < m0; i++) e0 += pow(hypot(q0[i].x - 10, q0[i].y + 5) - 80, 2);
        for (size_t i = 0; i < m1; i++) e1 += pow(hypot(q1[i].x - 10, q1[i].y + 5) - 80, 2);
        e0 = sqrt(e0 / (double)m0);
        e1 = sqrt(e1 / (double)m1);
        CHECK(e1 < 0.6 * e0);
        CHECK(e1 < 0.5);
        free(q0);
        free(q1);
        free(p);
    }
    /* a concave (kidney) loop keeps its bay after smoothing, and its area */
    {
        size_t n = 90;
        thx_vec2 *p = malloc(n * sizeof *p);
        for (size_t i = 0; i < n; i++) {
            double t = 2 * M_PI * (double)i / (double)n;
            double rr = 60 * (1 - 0.35 * exp(-pow(fmod(t + M_PI, 2 * M_PI) - M_PI, 2) / 0.2));
            p[i].x = rr * cos(t);
            p[i].y = 0.7 * rr * sin(t);
        }
        double a_in = thx_loop_area(p, n);
        thx_vec2 *q = NULL;
        size_t m = 0;
        thx_vec2 s = {0, 1000};
        CHECK_OK(ctx, thx_loop_resample(ctx, p, n, 4, 1.0, s, &q, &m));
        CHECK(fabs(thx_loop_area(q, m) - a_in) < 0.01 * a_in);
        free(q);
        free(p);
    }
    /* tiny loops: 3 points give at least 3 nodes; bad spacing is an input error */
    {
        thx_vec2 tri[3] = {{0, 0}, {10, 0}, {0, 10}};
        thx_vec2 *q = NULL;
        size_t m = 0;
        thx_vec2 s = {0, 1000};
        CHECK_OK(ctx, thx_loop_resample(ctx, tri, 3, 100, 0, s, &q, &m));
        CHECK(m == 3);
        free(q);
        q = NULL;
        CHECK(thx_loop_resample(ctx, tri, 3, 0, 0, s, &q, &m) == THX_EINPUT);
        CHECK(q == NULL);
        thx_vec2 dup[4] = {{0, 0}, {10, 0}, {10, 0}, {0, 10}};
        CHECK(thx_loop_resample(ctx, dup, 4, 1, 0, s, &q, &m) == THX_EINPUT);
    }
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
