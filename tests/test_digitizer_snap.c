/* Snapping a loop to a plane's edges (thorax/digitizer/snap.h): a circle shifted by 3 px and scaled by
 * 10% converges onto a blurred noisy disc within 1 px, keeping its node count, order and orientation. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/digitizer/snap.h"

static uint64_t rng = 88172645463325252ULL;
static double unif(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return ((double)(rng >> 11) + 0.5) / 9007199254740992.0;
}
static double gauss(void) { return sqrt(-2 * log(unif())) * cos(2 * M_PI * unif()); }

static const double CX = 64.3, CY = 63.7, R = 40;
#define BX (CX + (R + 4) * cos(1.0))
#define BY (CY + (R + 4) * sin(1.0))

static double area_xy(const double *p, size_t n)
{
    double s = 0;
    for (size_t i = 0; i < n; i++) {
        const double *q = p + 3 * ((i + 1) % n);
        s += p[3 * i] * q[1] - q[0] * p[3 * i + 1];
    }
    return 0.5 * s;
}

int main(void)
{
    thx_ctx *ctx;
    thx_ctx_create(&ctx);
    thx_image_slice s;
    const size_t W = 128, H = 128, N = 96;
    memset(&s, 0, sizeof s);
    s.w = W;
    s.h = H;
    s.v = malloc(W * H * sizeof *s.v);
    s.du[0] = s.dv[1] = 1;
    s.origin[2] = 12;
    s.normal[2] = 1;
    for (size_t b = 0; b < H; b++)
        for (size_t a = 0; a < W; a++)
            s.v[a + W * b] = (float)(100 * 0.5 * (1 + erf((R - hypot(a - CX, b - CY)) / (sqrt(2) * 1.5))) + 3 * gauss() +
                                     /* a small bright spot 4 px outside the edge: a stray edge for a node or two */
                                     300 * 0.5 * (1 + erf((1.5 - hypot(a - BX, b - BY)) / (sqrt(2) * 0.7))));
    for (int dir = 1; dir >= -1; dir -= 2) {
        double *in = malloc(3 * N * sizeof *in), *out = malloc(3 * N * sizeof *out);
        for (size_t i = 0; i < N; i++) {
            double t = dir * 2 * M_PI * (double)i / N + 0.1;
            in[3 * i] = CX + 3 + 1.1 * R * cos(t);
            in[3 * i + 1] = CY + 1.1 * R * sin(t);
            in[3 * i + 2] = 7; /* the neighbouring plane's z: projected onto this one */
        }
        CHECK_OK(ctx, thx_snap_loop(ctx, &s, NULL, in, N, out));
        double worst = 0, mean = 0, before = 0, step_max = 0, step_min = 1e9;
        for (size_t i = 0; i < N; i++) {
            double e = fabs(hypot(out[3 * i] - CX, out[3 * i + 1] - CY) - R);
            worst = fmax(worst, e);
            mean += e / N;
            before = fmax(before, fabs(hypot(in[3 * i] - CX, in[3 * i + 1] - CY) - R));
            CHECK(out[3 * i + 2] == 12);
            const double *q = out + 3 * ((i + 1) % N);
            double l = hypot(q[0] - out[3 * i], q[1] - out[3 * i + 1]);
            step_max = fmax(step_max, l);
            step_min = fmin(step_min, l);
        }
        printf("snap (%s): |r - 40| before max %.2f px, after max %.3f mean %.3f px; node steps %.2f..%.2f px\n",
               dir > 0 ? "counterclockwise" : "clockwise", before, worst, mean, step_min, step_max);
        CHECK(before > 6);
        CHECK(worst <= 1.0);
        CHECK(mean <= 0.3);
        CHECK(area_xy(out, N) * dir > 0);          /* orientation kept */
        CHECK(step_max < 3 * step_min);            /* nodes still spread round the loop, in order */
        /* a node stays near its own part of the loop: within 30 degrees of where it started */
        int order = 1;
        for (size_t i = 0; i < N; i++) {
            double t0 = atan2(in[3 * i + 1] - CY, in[3 * i] - CX - 3), t1 = atan2(out[3 * i + 1] - CY, out[3 * i] - CX);
            double dt = fabs(remainder(t1 - t0, 2 * M_PI));
            if (dt > M_PI / 6) order = 0;
        }
        CHECK(order);
        free(in);
        free(out);
    }
    /* bad input */
    double tri[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0}, two[6] = {0}, o9[9], farl[9] = {500, 0, 0, 501, 0, 0, 500, 1, 0};
    CHECK(thx_snap_loop(ctx, &s, NULL, two, 2, o9) == THX_EINPUT && tl_msg_has(ctx, "3 or more"));
    thx_snap_opts o;
    thx_snap_opts_default(&o);
    o.stiffness = 2;
    CHECK(thx_snap_loop(ctx, &s, &o, tri, 3, o9) == THX_EINPUT && tl_msg_has(ctx, "stiffness"));
    CHECK(thx_snap_loop(ctx, &s, NULL, farl, 3, o9) == THX_EINPUT && tl_msg_has(ctx, "outside the plane"));
    free(s.v);
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
