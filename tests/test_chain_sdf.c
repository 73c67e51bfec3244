/*
 * The signed distance to a closed chain (src/geom/chain_sdf.h), whose tree of boxes must give
 * what the plain loop over every edge gives: the winding number's sign exactly, the nearest
 * distance up to rounding (issue 24: the plain loop made lacing, caps and orientation quadratic; a
 * 40,000-point comb took 45 s to build). Chains: random star polygons, a comb with teeth 0.5 mm
 * apart, a chain that winds twice around the origin, a figure of eight; query points at random,
 * on vertices, at the heights of vertices (the half-open crossing rule) and far away.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "testlib.h"
#include "geom/chain_sdf.h"

static uint64_t rng = 88172645463325252ULL;
static double urand(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return (double)(rng >> 11) / 9007199254740992.0;
}

/* The plain loop: every edge, distance and signed crossings of the ray toward +x. */
static double brute(const thx_vec2 *p, size_t n, thx_vec2 q)
{
    double best = INFINITY;
    int wn = 0;
    for (size_t k = 0; k < n; k++) {
        thx_vec2 a = p[k], c = p[(k + 1) % n];
        double ex = c.x - a.x, ey = c.y - a.y, px = q.x - a.x, py = q.y - a.y;
        double l2 = ex * ex + ey * ey;
        double t = l2 > 0 ? (px * ex + py * ey) / l2 : 0;
        t = t < 0 ? 0 : t > 1 ? 1 : t;
        double ddx = px - t * ex, ddy = py - t * ey, d2 = ddx * ddx + ddy * ddy;
        if (d2 < best) best = d2;
        double cr = ex * py - ey * px;
        if (a.y <= q.y) {
            if (c.y > q.y && cr > 0) wn++;
        } else if (c.y <= q.y && cr < 0) wn--;
    }
    double d = sqrt(best);
    return wn != 0 ? -d : d;
}

/* Queries against chain p: returns how many of them disagree with the plain loop. */
static size_t compare(const char *what, const thx_vec2 *p, size_t n, size_t nq)
{
    chain_index ci;
    if (chain_index_init(&ci, p, n) != 0) return nq;
    double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
    for (size_t k = 0; k < n; k++) {
        x0 = fmin(x0, p[k].x); x1 = fmax(x1, p[k].x);
        y0 = fmin(y0, p[k].y); y1 = fmax(y1, p[k].y);
    }
    size_t bad = 0, inside = 0;
    for (size_t i = 0; i < nq; i++) {
        thx_vec2 q;
        switch (i % 4) {
        case 0: q = (thx_vec2){x0 - 5 + (x1 - x0 + 10) * urand(), y0 - 5 + (y1 - y0 + 10) * urand()}; break;
        case 1: q = p[(size_t)(urand() * (double)n) % n]; break;                       /* on a vertex */
        case 2: q = (thx_vec2){x0 - 5 + (x1 - x0 + 10) * urand(), p[(size_t)(urand() * (double)n) % n].y}; break;
        default: q = (thx_vec2){x0 + (x1 - x0) * urand(), y0 + (y1 - y0) * urand()}; break;
        }
        if (i == 7) q = (thx_vec2){x1 + 1e6, y0 - 3e5}; /* far away */
        double a = chain_index_sdf(&ci, q), b = brute(p, n, q);
        /* the same side, the same distance up to rounding (edges at a shared vertex tie, and the
           tree may meet the tie's other edge first) */
        if (!((a < 0) == (b < 0) && fabs(a - b) <= 1e-12 * fmax(1.0, fabs(b)))) {
            if (bad < 3) fprintf(stderr, "%s: query (%.17g, %.17g): tree %.17g, plain loop %.17g\n", what, q.x, q.y, a, b);
            bad++;
        }
        inside += b < 0;
    }
    printf("%s: %zu points, %zu queries (%zu inside): %zu differ\n", what, n, nq, inside, bad);
    chain_index_free(&ci);
    return bad;
}

int main(void)
{
    /* random star polygons of 3 .. 2000 points */
    for (int r = 0; r < 40; r++) {
        size_t n = 3 + (size_t)(urand() * (r < 20 ? 30 : 2000));
        thx_vec2 *p = malloc(n * sizeof *p);
        for (size_t k = 0; k < n; k++) {
            double t = 2 * M_PI * (double)k / (double)n, rad = 20 + 30 * urand();
            p[k] = (thx_vec2){rad * cos(t), rad * sin(t)};
        }
        char name[64];
        snprintf(name, sizeof name, "star %d", r);
        CHECK(compare(name, p, n, 400) == 0);
        free(p);
    }
    /* a comb: 500 teeth 10 mm tall, 0.5 mm wide, 0.5 mm apart, points 0.5 mm apart, closed by a base */
    {
        size_t cap = 30000, n = 0;
        thx_vec2 *p = malloc(cap * sizeof *p);
        double x = 0;
        for (int t = 0; t < 500; t++, x += 1.0) {
            for (int k = 0; k < 20; k++) p[n++] = (thx_vec2){x, 0.5 * k};
            for (int k = 0; k < 20; k++) p[n++] = (thx_vec2){x + 0.5, 0.5 * (20 - k)};
        }
        for (double b = x; b >= -0.5; b -= 0.5) p[n++] = (thx_vec2){b - 0.5, -0.5};
        CHECK(compare("comb", p, n, 20000) == 0);
        free(p);
    }
    /* a chain around the origin twice (winding number 2 inside the inner circle) */
    {
        size_t n = 1001;
        thx_vec2 *p = malloc(n * sizeof *p);
        for (size_t k = 0; k < n; k++) {
            double t = 4 * M_PI * (double)k / (double)n, rad = 30 + 10 * (double)k / (double)n;
            p[k] = (thx_vec2){rad * cos(t), rad * sin(t)};
        }
        CHECK(compare("twice around", p, n, 4000) == 0);
        free(p);
    }
    /* a figure of eight (winding +1 and -1) with integer coordinates (many equal heights) */
    {
        size_t n = 0;
        thx_vec2 p[400];
        for (int k = 0; k < 100; k++) p[n++] = (thx_vec2){k, (k * 7) % 5};
        for (int k = 0; k < 100; k++) p[n++] = (thx_vec2){100 - k, 40 + (k * 3) % 4};
        for (int k = 0; k < 100; k++) p[n++] = (thx_vec2){-k, 80 + (k * 5) % 3};
        for (int k = 0; k < 100; k++) p[n++] = (thx_vec2){-100 + k, 40 - (k % 2)};
        CHECK(compare("figure of eight", p, n, 8000) == 0);
    }
    return tl_finish();
}
