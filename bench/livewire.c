/* bench/livewire.c — the livewire's speed on a 512 x 512 plane (issue 26 item 8: between two clicks
 * under 50 ms). A synthetic torso-like plane (an ellipse 400 x 300 px, blurred, noisy, with an inner
 * ellipse); prints the median of RUNS runs of: the plane's features (thx_livewire_create: smoothing,
 * derivatives, the 8 link costs per pixel; once per plane shown), seed + path to a click a sixth of
 * the outline away (the usual case), seed + path to the far side of the outline (half of it), seed
 * + path to the far corner (the whole plane finished), and one more path after a seed's first (the
 * mouse moving: the search continues). Usage: livewire_bench [RUNS]  (default 15; LIVEWIRE_WALL=1 for the
 * wall clock rather than the thread's CPU time). Timing only; no check. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "thorax/digitizer/livewire.h"

/* CPU time of this thread by default: the machine may be loaded, and the
 * wall clock then measures the neighbours; LIVEWIRE_WALL=1 times the wall clock instead. */
static double now(void)
{
    static int wall = -1;
    if (wall < 0) wall = getenv("LIVEWIRE_WALL") != NULL;
    struct timespec t;
    clock_gettime(wall ? CLOCK_MONOTONIC : CLOCK_THREAD_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}
static int cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}
static uint64_t rng = 88172645463325252ULL;
static double unif(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return ((double)(rng >> 11) + 0.5) / 9007199254740992.0;
}

int main(int argc, char **argv)
{
    int runs = argc > 1 ? atoi(argv[1]) : 15;
    if (runs < 1) runs = 1;
    const size_t W = 512, H = 512;
    thx_image_slice s;
    memset(&s, 0, sizeof s);
    s.w = W;
    s.h = H;
    s.v = malloc(W * H * sizeof *s.v);
    s.du[0] = s.dv[1] = 0.75;
    s.normal[2] = 1;
    const double cx = 256, cy = 250, A = 200, B = 150;
    for (size_t b = 0; b < H; b++)
        for (size_t a = 0; a < W; a++) {
            double u = (a - cx) / A, v = (b - cy) / B, q = sqrt(u * u + v * v);
            double d = (1 - q) * 170, val = 600 * 0.5 * (1 + erf(d / 2.0));
            if (q < 0.9) val -= 250 * 0.5 * (1 + erf((0.9 - q) * 170 / 2.0));
            s.v[a + W * b] = (float)(val + 30 * (unif() - 0.5));
        }
    thx_ctx *ctx;
    thx_ctx_create(&ctx);
    double *tc = malloc((size_t)runs * sizeof *tc), *t6 = malloc((size_t)runs * sizeof *t6),
           *t2 = malloc((size_t)runs * sizeof *t2), *tw = malloc((size_t)runs * sizeof *tw),
           *tn = malloc((size_t)runs * sizeof *tn);
    double seed[3] = {0.75 * (cx + A), 0.75 * cy, 0};
    double sixth[3] = {0.75 * (cx + A * cos(M_PI / 3)), 0.75 * (cy + B * sin(M_PI / 3)), 0};
    double next[3] = {0.75 * (cx + A * cos(M_PI / 3 + 0.05)), 0.75 * (cy + B * sin(M_PI / 3 + 0.05)), 0};
    double half[3] = {0.75 * (cx - A), 0.75 * cy, 0};
    double corner[3] = {0, 0, 0};
    size_t n6 = 0, n2 = 0;
    for (int r = 0; r < runs; r++) {
        thx_livewire *lw = NULL;
        double *xyz = NULL, t0 = now();
        size_t n = 0;
        if (thx_livewire_create(ctx, &s, NULL, &lw)) return fprintf(stderr, "%s\n", thx_ctx_message(ctx)), 1;
        double t1 = now();
        thx_livewire_seed(ctx, lw, seed);
        if (thx_livewire_path(ctx, lw, sixth, &xyz, &n6)) return fprintf(stderr, "%s\n", thx_ctx_message(ctx)), 1;
        double t2a = now();
        free(xyz);
        if (thx_livewire_path(ctx, lw, next, &xyz, &n)) return 1;
        double t3 = now();
        free(xyz);
        thx_livewire_seed(ctx, lw, seed);
        if (thx_livewire_path(ctx, lw, half, &xyz, &n2)) return 1;
        double t4 = now();
        free(xyz);
        thx_livewire_seed(ctx, lw, seed);
        if (thx_livewire_path(ctx, lw, corner, &xyz, &n)) return 1;
        double t5 = now();
        free(xyz);
        tc[r] = t1 - t0;
        t6[r] = t2a - t1;
        tn[r] = t3 - t2a;
        t2[r] = t4 - t3;
        tw[r] = t5 - t4;
        thx_livewire_destroy(&lw);
    }
    qsort(tc, (size_t)runs, sizeof *tc, cmp);
    qsort(t6, (size_t)runs, sizeof *t6, cmp);
    qsort(tn, (size_t)runs, sizeof *tn, cmp);
    qsort(t2, (size_t)runs, sizeof *t2, cmp);
    qsort(tw, (size_t)runs, sizeof *tw, cmp);
    int m = runs / 2;
    printf("livewire on a 512 x 512 plane, median of %d runs (ms, %s):\n", runs,
           getenv("LIVEWIRE_WALL") ? "wall clock" : "CPU time of the thread");
    printf("  plane features (create, once per plane)  %8.2f\n", 1e3 * tc[m]);
    printf("  seed + path, a sixth of the outline      %8.2f  (%zu points)\n", 1e3 * t6[m], n6);
    printf("  the next path from the same seed         %8.2f\n", 1e3 * tn[m]);
    printf("  seed + path, half the outline            %8.2f  (%zu points)\n", 1e3 * t2[m], n2);
    printf("  seed + path, the far corner (all pixels) %8.2f\n", 1e3 * tw[m]);
    printf("  create + seed + half the outline         %8.2f\n", 1e3 * (tc[m] + t2[m]));
    free(tc);
    free(t6);
    free(tn);
    free(t2);
    free(tw);
    free(s.v);
    thx_ctx_destroy(&ctx);
    return 0;
}
