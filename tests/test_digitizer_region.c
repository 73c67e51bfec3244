/* The threshold tool (thorax/digitizer/region.h): a blurred noisy disc's loop lies on its circle within
 * 0.5 px with its area within 1%; 4- and 8-connectivity; holes filled; bad input refused. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/digitizer/region.h"

static uint64_t rng = 88172645463325252ULL;
static double unif(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return ((double)(rng >> 11) + 0.5) / 9007199254740992.0;
}
static double gauss(void) { return sqrt(-2 * log(unif())) * cos(2 * M_PI * unif()); }

/* a coronal plane (u = RAS x, v = RAS z) with 0.8 x 1.2 mm pixels: the tools must work in mm */
static void geometry(thx_image_slice *s, size_t w, size_t h)
{
    memset(s, 0, sizeof *s);
    s->w = w;
    s->h = h;
    s->v = calloc(w * h, sizeof *s->v);
    s->origin[0] = 10;
    s->origin[1] = -4;
    s->origin[2] = 20;
    s->du[0] = 0.8;
    s->dv[2] = 1.2;
    s->normal[1] = 1;
}

static const double CX = 50, CY = 40, R = 32; /* mm, in the plane's (u, v) from its first pixel */

int main(void)
{
    thx_ctx *ctx;
    thx_ctx_create(&ctx);
    thx_image_slice s;
    const size_t W = 128, H = 80;
    geometry(&s, W, H);
    for (size_t b = 0; b < H; b++)
        for (size_t a = 0; a < W; a++) {
            double x = 0.8 * (double)a, y = 1.2 * (double)b, d = R - hypot(x - CX, y - CY);
            s.v[a + W * b] = (float)(200 + 100 * 0.5 * (1 + erf(d / (sqrt(2) * 1.5))) + 2.0 * gauss());
        }
    double seed[3] = {10 + CX, -4, 20 + CY}, *xyz = NULL;
    size_t n = 0;
    thx_region_info info;
    CHECK_OK(ctx, thx_region_loop(ctx, &s, 250, 1000, seed, 1, &xyz, &n, &info));
    double worst = 0, area = 0;
    for (size_t i = 0; i < n; i++) {
        double x = xyz[3 * i] - 10, y = xyz[3 * i + 2] - 20, *q = xyz + 3 * ((i + 1) % n);
        CHECK(xyz[3 * i + 1] == -4);
        worst = fmax(worst, fabs(hypot(x - CX, y - CY) - R));
        area += 0.5 * (x * (q[2] - 20) - (q[0] - 10) * y);
    }
    double px = fmin(0.8, 1.2), a0 = M_PI * R * R;
    printf("disc r=32 mm (pixels 0.8 x 1.2 mm, blur 1.5 mm, noise 2%%): %zu points, |r - R| max %.3f mm = %.3f px; "
           "area %.1f mm^2 (%.1f; info %.1f), %zu pixels\n",
           n, worst, worst / px, area, a0, info.area, info.n_pixels);
    CHECK(n > 100);
    CHECK(worst <= 0.5 * px);
    CHECK(area > 0); /* counterclockwise in (u, v) */
    CHECK(fabs(area - a0) <= 0.01 * a0);
    CHECK(fabs(info.area - area) <= 1e-6 * area);
    CHECK(fabs(info.n_pixels * 0.8 * 1.2 - a0) <= 0.03 * a0);
    CHECK(info.n_holes == 0);
    free(xyz);

    /* 4 and 8 connectivity: two squares meeting at a corner; a ring's hole filled */
    memset(s.v, 0, W * H * sizeof *s.v);
    for (size_t b = 10; b < 20; b++)
        for (size_t a = 10; a < 20; a++) s.v[a + W * b] = s.v[(a + 10) + W * (b + 10)] = 1;
    double s1[3] = {10 + 0.8 * 15, -4, 20 + 1.2 * 15};
    CHECK_OK(ctx, thx_region_loop(ctx, &s, 0.5, 1.5, s1, 0, &xyz, &n, &info));
    CHECK(info.n_pixels == 100);
    /* the boundary halfway between the pixels, each corner cut by marching squares' triangle of 1/8 pixel */
    CHECK_NEAR(info.area, (100 - 0.5) * 0.96, 1e-9);
    free(xyz);
    CHECK_OK(ctx, thx_region_loop(ctx, &s, 0.5, 1.5, s1, 1, &xyz, &n, &info));
    CHECK(info.n_pixels == 200);
    CHECK_NEAR(info.area, (200 - 1 + 0.5) * 0.96, 1e-9); /* the saddle cell joined: 3/4 of it inside, not 1/4 */
    free(xyz);
    memset(s.v, 0, W * H * sizeof *s.v);
    for (size_t b = 10; b < 40; b++)
        for (size_t a = 10; a < 40; a++) s.v[a + W * b] = (a < 15 || a >= 35 || b < 15 || b >= 35) ? 1 : 0;
    double s2[3] = {10 + 0.8 * 12, -4, 20 + 1.2 * 12};
    CHECK_OK(ctx, thx_region_loop(ctx, &s, 0.5, 1.5, s2, 1, &xyz, &n, &info));
    CHECK(info.n_pixels == 900 - 400 && info.n_holes == 1);
    CHECK_NEAR(info.area, (900 - 0.5) * 0.96, 1e-9);
    free(xyz);
    /* bad input */
    double far[3] = {-100, -4, 20};
    CHECK(thx_region_loop(ctx, &s, 0.5, 1.5, far, 1, &xyz, &n, NULL) == THX_EINPUT && tl_msg_has(ctx, "outside the plane"));
    CHECK(thx_region_loop(ctx, &s, 2, 1, s1, 1, &xyz, &n, NULL) == THX_EINPUT && tl_msg_has(ctx, "lo <= hi"));
    double hole[3] = {10 + 0.8 * 25, -4, 20 + 1.2 * 25}; /* in the ring's hole */
    CHECK(thx_region_loop(ctx, &s, 0.5, 1.5, hole, 1, &xyz, &n, NULL) == THX_EINPUT && tl_msg_has(ctx, "value 0") &&
          xyz == NULL && n == 0);
    free(s.v);
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
