/* Shape-based interpolation of loops (thorax/digitizer/interp.h) and the crossings of a plane's loops
 * (thorax/digitizer/valid.h). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/digitizer/interp.h"
#include "thorax/digitizer/valid.h"

static thx_vec2 *ellipse(double cx, double cy, double a, double b, size_t n, double start, int dir)
{
    thx_vec2 *p = malloc(n * sizeof *p);
    for (size_t i = 0; i < n; i++) {
        double t = start + dir * 2 * M_PI * (double)i / (double)n;
        p[i].x = cx + a * cos(t);
        p[i].y = cy + b * sin(t);
    }
    return p;
}

/* signed distance to the ellipse (positive inside) by a dense polyline: independent of the library */
static double ell_sd(double x, double y, double a, double b)
{
    double best = 1e9;
    for (int k = 0; k < 20000; k++) {
        double t = 2 * M_PI * k / 20000;
        best = fmin(best, hypot(x - a * cos(t), y - b * sin(t)));
    }
    return (x * x) / (a * a) + (y * y) / (b * b) < 1 ? best : -best;
}

static double loop_area(const thx_vec2 *p, size_t n)
{
    double s = 0;
    for (size_t i = 0; i < n; i++) s += p[i].x * p[(i + 1) % n].y - p[(i + 1) % n].x * p[i].y;
    return 0.5 * s;
}

static void test_interp(void)
{
    thx_ctx *ctx;
    thx_ctx_create(&ctx);
    /* circles r = 20 and r = 30 (polygons of 400 points: their radius is exact to 0.001 mm), the second
     * clockwise and started elsewhere: the middle is r = 25 */
    thx_vec2 *A = ellipse(5, -3, 20, 20, 400, 0, 1), *B = ellipse(5, -3, 30, 30, 400, 1.0, -1), *o = NULL;
    size_t n = 0;
    for (int k = 1; k <= 3; k++) {
        double t = 0.25 * k, r0 = 20 + 10 * t, worst = 0;
        CHECK_OK(ctx, thx_loop_interpolate(ctx, A, 400, B, 400, t, 0.5, &o, &n));
        for (size_t i = 0; i < n; i++) worst = fmax(worst, fabs(hypot(o[i].x - 5, o[i].y + 3) - r0));
        printf("circles 20 -> 30 at t = %.2f: %zu points, |r - %.1f| max %.3f\n", t, n, r0, worst);
        CHECK(n > 100);
        CHECK(worst <= (k == 2 ? 0.1 : 0.15));
        CHECK(loop_area(o, n) > 0);
        free(o);
    }
    /* t = 0 gives the first loop back */
    CHECK_OK(ctx, thx_loop_interpolate(ctx, A, 400, B, 400, 0, 0.5, &o, &n));
    double w0 = 0;
    for (size_t i = 0; i < n; i++) w0 = fmax(w0, fabs(hypot(o[i].x - 5, o[i].y + 3) - 20));
    CHECK(w0 <= 0.1);
    free(o);
    /* circle r = 20 and ellipse 30 x 15 (same centre): at t = 1/2 the zero level of the mean of the signed
     * distances, half-axes 25 along x and 17.5 along y */
    thx_vec2 *E = ellipse(0, 0, 30, 15, 600, 0.2, 1), *C = ellipse(0, 0, 20, 20, 400, 0, 1);
    CHECK_OK(ctx, thx_loop_interpolate(ctx, C, 400, E, 600, 0.5, 0.25, &o, &n));
    double xmax = 0, ymax = 0, worst = 0;
    for (size_t i = 0; i < n; i++) {
        xmax = fmax(xmax, fabs(o[i].x));
        ymax = fmax(ymax, fabs(o[i].y));
        if (i % 7 == 0) worst = fmax(worst, fabs(0.5 * (20 - hypot(o[i].x, o[i].y)) + 0.5 * ell_sd(o[i].x, o[i].y, 30, 15)));
    }
    printf("circle 20 / ellipse 30 x 15 at t = 0.5: %zu points, half-axes %.3f %.3f (25, 17.5), |mean signed "
           "distance| max %.3f\n", n, xmax, ymax, worst);
    CHECK_NEAR(xmax, 25, 0.1);
    CHECK_NEAR(ymax, 17.5, 0.1);
    CHECK(worst <= 0.1);
    free(o);
    /* a shifted loop: the middle is shifted half way (shape-based interpolation of a translation) */
    thx_vec2 *S = ellipse(8, 0, 20, 20, 400, 0, 1);
    CHECK_OK(ctx, thx_loop_interpolate(ctx, C, 400, S, 400, 0.5, 0.5, &o, &n));
    double cx = 0;
    for (size_t i = 0; i < n; i++) cx += o[i].x / (double)n;
    double xr = -1e9, xl = 1e9;
    for (size_t i = 0; i < n; i++) {
        xr = fmax(xr, o[i].x);
        xl = fmin(xl, o[i].x);
    }
    printf("circle shifted by 8: middle spans x %.3f .. %.3f (-16 .. 24)\n", xl, xr);
    CHECK_NEAR(xl, -16, 0.15);
    CHECK_NEAR(xr, 24, 0.15);
    free(o);
    /* bad input */
    CHECK(thx_loop_interpolate(ctx, C, 2, S, 400, 0.5, 0.5, &o, &n) == THX_EINPUT);
    CHECK(thx_loop_interpolate(ctx, C, 400, S, 400, 1.5, 0.5, &o, &n) == THX_EINPUT && tl_msg_has(ctx, "t = 1.5"));
    CHECK(thx_loop_interpolate(ctx, C, 400, S, 400, 0.5, 0, &o, &n) == THX_EINPUT && tl_msg_has(ctx, "step"));
    CHECK(thx_loop_interpolate(ctx, C, 400, S, 400, 0.5, 1e-5, &o, &n) == THX_EINPUT && o == NULL && n == 0);
    free(A);
    free(B);
    free(C);
    free(E);
    free(S);
    thx_ctx_destroy(&ctx);
}

static void test_valid(void)
{
    thx_ctx *ctx;
    thx_ctx_create(&ctx);
    thx_vec2 *big = ellipse(0, 0, 30, 20, 64, 0, 1), *in = ellipse(2, 0, 10, 10, 32, 0, -1),
             *over = ellipse(35, 0, 10, 10, 32, 0.05, 1);
    thx_vec2 eight[6] = {{0, 0}, {10, 10}, {20, 0}, {20, 10}, {10, 0}, {0, 10}}; /* crosses itself */
    const thx_vec2 *L[4] = {big, in, over, eight};
    size_t n[4] = {64, 32, 32, 6}, m = 0;
    thx_loop_crossing *c = NULL;
    /* nested loops: nothing */
    CHECK_OK(ctx, thx_loops_crossings(ctx, L, n, 2, &c, &m));
    CHECK(m == 0 && c == NULL);
    /* big and over cross; eight crosses itself, and lies inside big without crossing it; in crosses eight */
    CHECK_OK(ctx, thx_loops_crossings(ctx, L, n, 4, &c, &m));
    int self8 = 0, big_over = 0, in_eight = 0, other = 0;
    for (size_t i = 0; i < m; i++) {
        if (c[i].a == 3 && c[i].b == 3) self8 = 1;
        else if (c[i].a == 0 && c[i].b == 2) {
            big_over = 1;
            /* the edges named do touch */
            CHECK(c[i].ea < 64 && c[i].eb < 32);
        } else if (c[i].a == 1 && c[i].b == 3) in_eight = 1;
        else other++;
    }
    CHECK(self8 && big_over && in_eight && other == 0);
    free(c);
    /* a shared point counts */
    thx_vec2 t1[3] = {{0, 0}, {1, 0}, {0, 1}}, t2[3] = {{1, 0}, {2, 0}, {2, 1}};
    const thx_vec2 *T[2] = {t1, t2};
    size_t nt[2] = {3, 3};
    CHECK_OK(ctx, thx_loops_crossings(ctx, T, nt, 2, &c, &m));
    CHECK(m == 1);
    free(c);
    nt[1] = 2;
    CHECK(thx_loops_crossings(ctx, T, nt, 2, &c, &m) == THX_EINPUT && tl_msg_has(ctx, "loop 2 has 2 points"));
    free(big);
    free(in);
    free(over);
    thx_ctx_destroy(&ctx);
}

int main(void)
{
    test_interp();
    test_valid();
    return tl_finish();
}
