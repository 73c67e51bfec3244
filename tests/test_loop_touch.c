/*
 * Tests of thx_loop_touch (src/geom/loop_touch.c), the O(n log n) sweep that finds two edges of a
 * closed loop that touch:
 *  - against the brute force over every pair of non-adjacent edges (thx_segments_touch), on
 *    200,000 random loops of 4-14 points on a 5 x 5 integer grid and 200,000 of 4-8 points on a
 *    9 x 9 grid: repeated points, collinear edges, touching and overlapping everywhere (the
 *    sweep's hard cases), and on 50,000 random loops in general position;
 *  - the reported pair touches and is not two neighbours;
 *  - loops of 40,000 points whose edges all overlap in x (a tall comb: the case that took the old
 *    test, pairs of edges overlapping in x, over 300 s), with no touch and with one planted;
 *  - a digitized-like circle with a figure-of-eight twist.
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "testlib.h"
#include "thorax/geom/predicates.h"
static int brute(const double *p, size_t n)
{
    for (size_t i = 0; i < n; i++)
        for (size_t j = i + 1; j < n; j++) {
            if (j == i + 1 || (i == 0 && j == n - 1)) continue;
            if (thx_segments_touch(p + 2 * i, p + 2 * ((i + 1) % n), p + 2 * j, p + 2 * ((j + 1) % n))) return 1;
        }
    return 0;
}

static uint64_t rng = 88172645463325252ull;
static uint64_t next_u(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return rng;
}

static int pair_ok(const double *p, size_t n, size_t i, size_t j)
{
    if (!(i < j && j < n) || j == i + 1 || (i == 0 && j == n - 1)) return 0;
    return thx_segments_touch(p + 2 * i, p + 2 * ((i + 1) % n), p + 2 * j, p + 2 * ((j + 1) % n));
}

int main(void)
{
    double p[2 * 16];
    /* degenerate: a small grid */
    size_t agree = 0, touching = 0, cases = 200000;
    for (size_t c = 0; c < cases; c++) {
        size_t n = 4 + next_u() % 11;
        for (size_t i = 0; i < n; i++) {
            p[2 * i] = (double)(next_u() % 5);
            p[2 * i + 1] = (double)(next_u() % 5);
        }
        size_t a = 0, b = 0;
        int got = thx_loop_touch(p, n, &a, &b), want = brute(p, n);
        if (got == want && (!got || pair_ok(p, n, a, b))) agree++;
        else if (tl_fail < 5) {
            fprintf(stderr, "disagree (sweep %d, brute force %d) on:", got, want);
            for (size_t i = 0; i < n; i++) fprintf(stderr, " (%g,%g)", p[2 * i], p[2 * i + 1]);
            fprintf(stderr, "\n");
            tl_fail++;
        }
        touching += (size_t)want;
    }
    printf("grid loops: %zu of %zu agree with the brute force (%zu touch themselves)\n", agree, cases, touching);
    CHECK(agree == cases);
    CHECK(touching > cases / 4 && touching < cases);
    /* a finer grid, fewer points: more loops that do not touch, still degenerate */
    agree = touching = 0;
    for (size_t c = 0; c < 200000; c++) {
        size_t n = 4 + next_u() % 5;
        for (size_t i = 0; i < 2 * n; i++) p[i] = (double)(next_u() % 9);
        size_t a = 0, b = 0;
        int got = thx_loop_touch(p, n, &a, &b), want = brute(p, n);
        agree += got == want && (!got || pair_ok(p, n, a, b));
        touching += (size_t)want;
    }
    printf("9 x 9 grid loops: %zu of 200000 agree (%zu touch themselves)\n", agree, touching);
    CHECK(agree == 200000);
    CHECK(touching < 190000); /* at least 10,000 that do not touch */
    /* general position */
    agree = touching = 0;
    for (size_t c = 0; c < 50000; c++) {
        size_t n = 4 + next_u() % 11;
        for (size_t i = 0; i < 2 * n; i++) p[i] = (double)(next_u() >> 11) / 9007199254740992.0;
        size_t a = 0, b = 0;
        int got = thx_loop_touch(p, n, &a, &b), want = brute(p, n);
        agree += got == want && (!got || pair_ok(p, n, a, b));
        touching += (size_t)want;
    }
    printf("random loops: %zu of 50000 agree (%zu touch themselves)\n", agree, touching);
    CHECK(agree == 50000);
    /* a tall comb of 40,000 points: every edge overlaps every other in x */
    {
        size_t n = 40000, half = n / 2;
        double *q = malloc(2 * n * sizeof *q);
        for (size_t i = 0; i < half; i++) { /* up the left teeth, down the right ones */
            q[2 * i] = (i % 2) ? 1.0 : 0.0;
            q[2 * i + 1] = (double)i;
            q[2 * (n - 1 - i)] = (i % 2) ? 2.0 : 3.0;
            q[2 * (n - 1 - i) + 1] = (double)i;
        }
        size_t a = 0, b = 0;
        clock_t t0 = clock();
        int r = thx_loop_touch(q, n, &a, &b);
        double s = (double)(clock() - t0) / CLOCKS_PER_SEC;
        printf("comb of %zu points, no touch: %d in %.3f s\n", n, r, s);
        CHECK(r == 0);
        /* one tooth of the left side pushed across to the right side */
        q[2 * 10001] = 2.5;
        t0 = clock();
        r = thx_loop_touch(q, n, &a, &b);
        s = (double)(clock() - t0) / CLOCKS_PER_SEC;
        printf("comb with one tooth across: %d (edges %zu and %zu) in %.3f s\n", r, a, b, s);
        CHECK(r == 1 && pair_ok(q, n, a, b));
        CHECK(a == 10000 || a == 10001);
        free(q);
    }
    /* a circle of 1,000 points, then twisted into a figure of eight (two edges cross) */
    {
        size_t n = 1000;
        double *q = malloc(2 * n * sizeof *q);
        for (size_t i = 0; i < n; i++) {
            double t = 2 * M_PI * (double)i / (double)n;
            q[2 * i] = 100 * cos(t);
            q[2 * i + 1] = 60 * sin(t);
        }
        size_t a = 0, b = 0;
        CHECK(thx_loop_touch(q, n, &a, &b) == 0);
        for (size_t i = n / 4; i < 3 * n / 4; i++) q[2 * i + 1] = -q[2 * i + 1];
        CHECK(thx_loop_touch(q, n, &a, &b) == 1 && pair_ok(q, n, a, b));
        free(q);
    }
    return tl_finish();
}
