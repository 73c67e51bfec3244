/* Exact predicates: signs checked against an independent exact evaluation in
 * GMP rationals (mpq), on random, exactly degenerate and one-ulp perturbed
 * inputs. */
#include "testlib.h"
#include "thorax/geom/predicates.h"
#include <gmp.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>

/* ---- reference: exact determinant of an n x n rational matrix (n <= 4) ---- */

static void mpq_det(int n, mpq_t m[4][4], mpq_t out)
{
    if (n == 1) { mpq_set(out, m[0][0]); return; }
    mpq_t acc, sub, t;
    mpq_inits(acc, sub, t, NULL);
    mpq_t minor[4][4];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) mpq_init(minor[i][j]);
    for (int col = 0; col < n; col++) {
        for (int i = 1; i < n; i++)
            for (int j = 0, k = 0; j < n; j++)
                if (j != col) mpq_set(minor[i - 1][k++], m[i][j]);
        mpq_det(n - 1, minor, sub);
        mpq_mul(t, sub, m[0][col]);
        if (col & 1) mpq_sub(acc, acc, t);
        else mpq_add(acc, acc, t);
    }
    mpq_set(out, acc);
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) mpq_clear(minor[i][j]);
    mpq_clears(acc, sub, t, NULL);
}

/* Rows are (p_i - last) for dim coordinates, plus the squared length if lift. */
static int ref_sign(int npts, const double *const *p, int dim, int lift)
{
    int n = npts - 1;
    mpq_t m[4][4], x, y, out;
    mpq_inits(x, y, out, NULL);
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) mpq_init(m[i][j]);
    for (int i = 0; i < n; i++) {
        mpq_t l;
        mpq_init(l);
        for (int k = 0; k < dim; k++) {
            mpq_set_d(x, p[i][k]);
            mpq_set_d(y, p[n][k]);
            mpq_sub(m[i][k], x, y);
            mpq_mul(x, m[i][k], m[i][k]);
            mpq_add(l, l, x);
        }
        if (lift) mpq_set(m[i][dim], l);
        mpq_clear(l);
    }
    mpq_det(n, m, out);
    int s = mpq_sgn(out);
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) mpq_clear(m[i][j]);
    mpq_clears(x, y, out, NULL);
    return s;
}

static int sgn(double v) { return (v > 0) - (v < 0); }

static int ref_orient2d(const double *a, const double *b, const double *c)
{
    const double *p[3] = {a, b, c};
    return ref_sign(3, p, 2, 0);
}
static int ref_orient3d(const double *a, const double *b, const double *c, const double *d)
{
    const double *p[4] = {a, b, c, d};
    return ref_sign(4, p, 3, 0);
}
static int ref_incircle(const double *a, const double *b, const double *c, const double *d)
{
    const double *p[4] = {a, b, c, d};
    return ref_sign(4, p, 2, 1);
}
static int ref_insphere(const double *a, const double *b, const double *c, const double *d, const double *e)
{
    const double *p[5] = {a, b, c, d, e};
    return ref_sign(5, p, 3, 1);
}

/* Deterministic generator (xorshift64*). */
static uint64_t rng = 0x9E3779B97F4A7C15ull;
static double urand(void)
{
    rng ^= rng >> 12; rng ^= rng << 25; rng ^= rng >> 27;
    return (double)((rng * 2685821657736338717ull) >> 11) / 9007199254740992.0;
}

static int mismatches;
#define AGREE(got, ref) do { if (sgn(got) != (ref)) mismatches++; } while (0)

static void test_conventions(void)
{
    double a[3] = {0, 0, 0}, b[3] = {1, 0, 0}, c[3] = {0, 1, 0}, d[3] = {0, 0, -1}, up[3] = {0, 0, 1};
    CHECK(thx_orient2d(a, b, c) > 0);
    CHECK(thx_orient2d(a, c, b) < 0);
    CHECK(thx_orient3d(a, b, c, d) > 0);  /* d below the CCW-from-above triangle */
    CHECK(thx_orient3d(a, b, c, up) < 0);
    double in2[2] = {0.25, 0.25}, out2[2] = {2, 2};
    CHECK(thx_incircle(a, b, c, in2) > 0);
    CHECK(thx_incircle(a, b, c, out2) < 0);
    CHECK(thx_incircle(a, c, b, in2) < 0);
    double cen[3] = {0.5, 0.5, -0.5}, far[3] = {5, 5, 5};
    CHECK(thx_insphere(a, b, c, d, cen) > 0);
    CHECK(thx_insphere(a, b, c, d, far) < 0);
    CHECK(thx_insphere(b, a, c, d, cen) < 0);
}

static void test_random(void)
{
    mismatches = 0;
    for (int it = 0; it < 20000; it++) {
        double p[5][3];
        for (int i = 0; i < 5; i++)
            for (int k = 0; k < 3; k++) p[i][k] = urand() * 200.0 - 100.0;
        AGREE(thx_orient2d(p[0], p[1], p[2]), ref_orient2d(p[0], p[1], p[2]));
        AGREE(thx_orient3d(p[0], p[1], p[2], p[3]), ref_orient3d(p[0], p[1], p[2], p[3]));
        AGREE(thx_incircle(p[0], p[1], p[2], p[3]), ref_incircle(p[0], p[1], p[2], p[3]));
        if (it % 4 == 0) AGREE(thx_insphere(p[0], p[1], p[2], p[3], p[4]), ref_insphere(p[0], p[1], p[2], p[3], p[4]));
    }
    CHECK(mismatches == 0);

    /* Nearly degenerate: the last point is an affine combination of the
     * others (rounded), so the filter usually fails and the exact path runs. */
    mismatches = 0;
    int zeros = 0;
    for (int it = 0; it < 20000; it++) {
        double p[5][3];
        for (int i = 0; i < 4; i++)
            for (int k = 0; k < 3; k++) p[i][k] = urand() * 20.0 - 10.0 + 1000.0 * (it & 1);
        double s = urand(), t = urand();
        for (int k = 0; k < 3; k++) p[4][k] = p[0][k] + s * (p[1][k] - p[0][k]) + t * (p[2][k] - p[0][k]);
        double o2 = thx_orient2d(p[0], p[1], p[4]);
        int r2 = ref_orient2d(p[0], p[1], p[4]);
        AGREE(o2, r2);
        zeros += (r2 == 0);
        AGREE(thx_orient3d(p[0], p[1], p[2], p[4]), ref_orient3d(p[0], p[1], p[2], p[4]));
        /* near-cocircular: rotate a point of the circle by a tiny angle */
        double cx = p[3][0], cy = p[3][1], r = 1.0 + urand();
        double q[4][2];
        for (int i = 0; i < 4; i++) {
            double ang = (i < 3) ? urand() * 6.283185307179586 : urand() * 6.283185307179586;
            q[i][0] = cx + r * cos(ang);
            q[i][1] = cy + r * sin(ang);
        }
        AGREE(thx_incircle(q[0], q[1], q[2], q[3]), ref_incircle(q[0], q[1], q[2], q[3]));
        if (it % 8 == 0) {
            double sp[5][3], rr = 1.0 + urand();
            for (int i = 0; i < 5; i++) {
                double th = urand() * 3.14159, ph = urand() * 6.28318;
                sp[i][0] = p[3][0] + rr * sin(th) * cos(ph);
                sp[i][1] = p[3][1] + rr * sin(th) * sin(ph);
                sp[i][2] = p[3][2] + rr * cos(th);
            }
            AGREE(thx_insphere(sp[0], sp[1], sp[2], sp[3], sp[4]), ref_insphere(sp[0], sp[1], sp[2], sp[3], sp[4]));
        }
    }
    CHECK(mismatches == 0);
    (void)zeros;
}

/* Points exactly collinear in double although the slope and coordinates look
 * inexact: x = x0 + 3k 2^-40, y = y0 + 7k 2^-40 with x0 = 0.1, y0 = 0.4 (each
 * sum is exact because it stays in the binade of x0 / y0 and needs no bit
 * below their last bit). */
static void test_collinear_exact(void)
{
    const double h = ldexp(1.0, -40);
    double pts[64][2];
    for (int k = 0; k < 64; k++) {
        pts[k][0] = 0.1 + 3.0 * k * h;
        pts[k][1] = 0.4 + 7.0 * k * h;
    }
    mismatches = 0;
    int nz = 0;
    for (int i = 0; i < 64; i += 3)
        for (int j = i + 1; j < 64; j += 5)
            for (int k = j + 1; k < 64; k += 7) {
                CHECK(ref_orient2d(pts[i], pts[j], pts[k]) == 0); /* really collinear */
                nz += thx_orient2d(pts[i], pts[j], pts[k]) != 0.0;
                /* one ulp off the line in each direction and coordinate */
                double q[2] = {pts[k][0], pts[k][1]};
                double dirs[4][2] = {{INFINITY, 0}, {-INFINITY, 0}, {0, INFINITY}, {0, -INFINITY}};
                for (int d = 0; d < 4; d++) {
                    q[0] = dirs[d][0] != 0 ? nextafter(pts[k][0], dirs[d][0]) : pts[k][0];
                    q[1] = dirs[d][1] != 0 ? nextafter(pts[k][1], dirs[d][1]) : pts[k][1];
                    double o = thx_orient2d(pts[i], pts[j], q);
                    int r = ref_orient2d(pts[i], pts[j], q);
                    CHECK(r != 0);
                    AGREE(o, r);
                }
            }
    CHECK(nz == 0);
    CHECK(mismatches == 0);

    /* The classic failure of naive orient2d: a grid of ulp-perturbations of
     * (0.5, 0.5) against the line through (12, 12) and (24, 24). */
    mismatches = 0;
    double b[2] = {12, 12}, c[2] = {24, 24};
    int naive_wrong = 0;
    for (int i = 0; i < 64; i++)
        for (int j = 0; j < 64; j++) {
            double a[2] = {0.5 + i * ldexp(1.0, -53), 0.5 + j * ldexp(1.0, -53)};
            int r = ref_orient2d(a, b, c);
            AGREE(thx_orient2d(a, b, c), r);
            double naive = (a[0] - c[0]) * (b[1] - c[1]) - (a[1] - c[1]) * (b[0] - c[0]);
            naive_wrong += sgn(naive) != r;
        }
    CHECK(mismatches == 0);
    CHECK(naive_wrong > 0); /* the test really exercises the exact path */

    /* The same at a small scale (coordinates below 1 mm: both products of the determinant below
     * 1), where a filter that trusted small terms would give the float's wrong sign. */
    mismatches = 0;
    naive_wrong = 0;
    double bs[2] = {0.012, 0.012}, cs[2] = {0.024, 0.024};
    for (int i = 0; i < 64; i++)
        for (int j = 0; j < 64; j++) {
            double a[2] = {0.0005 + i * ldexp(1.0, -63), 0.0005 + j * ldexp(1.0, -63)};
            int r = ref_orient2d(a, bs, cs);
            AGREE(thx_orient2d(a, bs, cs), r);
            double naive = (a[0] - cs[0]) * (bs[1] - cs[1]) - (a[1] - cs[1]) * (bs[0] - cs[0]);
            naive_wrong += sgn(naive) != r;
        }
    CHECK(mismatches == 0);
    CHECK(naive_wrong > 0);

    /* Coplanar points in 3D: z = z0 + (3x + 5y) exactly on dyadic offsets. */
    mismatches = 0;
    nz = 0;
    int flipped = 0, tried = 0;
    double P[32][3];
    for (int k = 0; k < 32; k++) {
        double u = (double)((k * 7) % 32) * h, v = (double)((k * 13) % 32) * h;
        P[k][0] = 0.1 + u;
        P[k][1] = 0.3 + v;
        P[k][2] = 0.7 + 3.0 * u + 5.0 * v;
    }
    for (int i = 0; i < 32; i += 2)
        for (int j = i + 1; j < 32; j += 3)
            for (int k = j + 1; k < 32; k += 4)
                for (int l = k + 1; l < 32; l += 5) {
                    CHECK(ref_orient3d(P[i], P[j], P[k], P[l]) == 0);
                    nz += thx_orient3d(P[i], P[j], P[k], P[l]) != 0.0;
                    double q[3] = {P[l][0], P[l][1], nextafter(P[l][2], 1.0)};
                    tried++;
                    AGREE(thx_orient3d(P[i], P[j], P[k], q), ref_orient3d(P[i], P[j], P[k], q));
                    flipped += thx_orient3d(P[i], P[j], P[k], q) != 0.0; /* 0 only if i, j, k collinear */
                    q[2] = nextafter(P[l][2], -1.0);
                    AGREE(thx_orient3d(P[i], P[j], P[k], q), ref_orient3d(P[i], P[j], P[k], q));
                }
    CHECK(nz == 0);
    CHECK(mismatches == 0);
    CHECK(flipped > tried / 2);
}

/* Any rectangle is cyclic and any box is inscribed in a sphere: corners with
 * arbitrary double coordinates are exactly cocircular / cospherical. */
static void test_cocircular(void)
{
    mismatches = 0;
    int nz = 0, flips = 0;
    for (int it = 0; it < 2000; it++) {
        double x0 = urand() * 10 - 5, x1 = x0 + 0.1 + urand(), y0 = urand() * 10 - 5 + 1000.0 * (it & 1),
               y1 = y0 + 0.3 * urand() + 1e-3;
        double a[2] = {x0, y0}, b[2] = {x1, y0}, c[2] = {x1, y1}, d[2] = {x0, y1};
        nz += thx_incircle(a, b, c, d) != 0.0;
        nz += thx_incircle(b, c, d, a) != 0.0;
        /* one ulp in or out */
        double dd[2] = {nextafter(x0, x1), y1};
        int r = ref_incircle(a, b, c, dd);
        flips += (r == 0);
        AGREE(thx_incircle(a, b, c, dd), r);
        dd[0] = nextafter(x0, -100.0);
        AGREE(thx_incircle(a, b, c, dd), ref_incircle(a, b, c, dd));
        CHECK(thx_incircle(a, b, c, dd) != 0.0);

        double z0 = urand(), z1 = z0 + 0.5 + urand();
        double box[8][3];
        for (int k = 0; k < 8; k++) {
            box[k][0] = (k & 1) ? x1 : x0;
            box[k][1] = (k & 2) ? y1 : y0;
            box[k][2] = (k & 4) ? z1 : z0;
        }
        /* 0,1,2,4 are not coplanar; every other corner is on their sphere */
        double *t0 = box[0], *t1 = box[1], *t2 = box[2], *t3 = box[4];
        if (thx_orient3d(t0, t1, t2, t3) < 0) { double *s = t1; t1 = t2; t2 = s; }
        for (int k = 3; k < 8; k++)
            if (k != 4) nz += thx_insphere(t0, t1, t2, t3, box[k]) != 0.0;
        nz += thx_orient3d(box[0], box[1], box[2], box[3]) != 0.0; /* a face: coplanar */
        double e[3] = {box[7][0], box[7][1], nextafter(box[7][2], 100.0)};
        CHECK(ref_insphere(t0, t1, t2, t3, e) < 0);
        CHECK(thx_insphere(t0, t1, t2, t3, e) < 0);
        e[2] = nextafter(box[7][2], -100.0);
        CHECK(thx_insphere(t0, t1, t2, t3, e) > 0);
    }
    CHECK(nz == 0);
    CHECK(flips == 0);
    CHECK(mismatches == 0);

    /* Integer grid: all 4-point subsets of points on x^2 + y^2 = 25. */
    double circ[12][2] = {{5, 0}, {4, 3}, {3, 4}, {0, 5}, {-3, 4}, {-4, 3}, {-5, 0}, {-4, -3}, {-3, -4}, {0, -5}, {3, -4}, {4, -3}};
    nz = 0;
    for (int i = 0; i < 12; i++)
        for (int j = i + 1; j < 12; j++)
            for (int k = j + 1; k < 12; k++)
                for (int l = 0; l < 12; l++) {
                    double sh = 1024.125; /* translation that keeps coordinates exact */
                    double a[2] = {circ[i][0] + sh, circ[i][1] - sh}, b[2] = {circ[j][0] + sh, circ[j][1] - sh};
                    double c[2] = {circ[k][0] + sh, circ[k][1] - sh}, d[2] = {circ[l][0] + sh, circ[l][1] - sh};
                    nz += thx_incircle(a, b, c, d) != 0.0;
                }
    CHECK(nz == 0);
}

int main(void)
{
    test_conventions();
    test_random();
    test_collinear_exact();
    test_cocircular();
    return tl_finish();
}
