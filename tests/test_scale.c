/*
 * Tests of the colour scales (src/render/scale.c; thorax/render/image.h; paper 4.2, "Standards"):
 * the names; map3d's lab series as numbers; the lab levels worked out by hand for lab7 and lab13
 * under each mapping (data -37..52 and one-signed ranges), each level exactly on a band boundary;
 * analytic values of every model under every mapping (SEPARATE's -1 -> 0, 0 -> 0.5, 10 -> 1);
 * over every model x mapping x range: monotone, clamped, NaN kept, round trips both ways,
 * thx_scale_apply_n equal to thx_scale_apply, bands between consecutive levels; TRUE equal bit for
 * bit to the scale as it was before mappings (reversed ends too); lo > hi turning any scale
 * around; the range rule; the colour bar of a lab scale and of a SEPARATE mapping.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/render/image.h"

static thx_ctx *ctx;

static thx_scale make(thx_scale_model model, thx_scale_mapping mapping, double lo, double hi)
{
    thx_scale s;
    memset(&s, 0, sizeof s);
    s.model = model, s.mapping = mapping, s.lo = lo, s.hi = hi;
    return s;
}

/* ------------------------------------------------------------- names */

static void test_names(void)
{
    const char *models[] = {"linear", "log", "exp", "lab7", "lab13"};
    const char *mappings[] = {"true", "symmetric", "midpoint", "separate"};
    for (int i = 0; i < 5; i++) {
        thx_scale_model m = THX_SCALE_EXP;
        CHECK(thx_scale_model_parse(models[i], &m) == 0 && (int)m == i && !strcmp(thx_scale_model_name(m), models[i]));
    }
    for (int i = 0; i < 4; i++) {
        thx_scale_mapping m = THX_MAPPING_MIDPOINT;
        CHECK(thx_scale_mapping_parse(mappings[i], &m) == 0 && (int)m == i &&
              !strcmp(thx_scale_mapping_name(m), mappings[i]));
    }
    thx_scale_model m = THX_SCALE_LOG;
    thx_scale_mapping p = THX_MAPPING_SEPARATE;
    CHECK(thx_scale_model_parse("lab", &m) == -1 && m == THX_SCALE_LOG);
    CHECK(thx_scale_model_parse(NULL, &m) == -1 && thx_scale_mapping_parse("Symmetric", &p) == -1 &&
          p == THX_MAPPING_SEPARATE);
    CHECK(!strcmp(thx_scale_model_name((thx_scale_model)9), "unknown") &&
          !strcmp(thx_scale_mapping_name((thx_scale_mapping)-1), "unknown"));
}

/* ------------------------------------------------------------- lab levels */

/* The levels of s (ascending) against want[0..n), each to rel * |value| (0: exactly). */
static int levels_are(const thx_scale *s, const double *want, int n, double rel)
{
    double got[64];
    int count = thx_scale_levels(s, 5, got, 64), ok = count == n && thx_scale_bands(s, 5) == n + 1;
    for (int i = 0; ok && i < n; i++) ok = fabs(got[i] - want[i]) <= rel * fabs(want[i]);
    if (!ok) {
        fprintf(stderr, "%s/%s [%g, %g]: %d levels:", thx_scale_model_name(s->model), thx_scale_mapping_name(s->mapping),
                s->lo, s->hi, count);
        for (int i = 0; i < count && i < 64; i++) fprintf(stderr, " %.17g", got[i]);
        fprintf(stderr, "\n");
    }
    return ok;
}

/* The invariant: level j (1-based, ascending) of a lab scale with n bands is at t = j / n exactly,
   and values just below and above it fall in bands j - 1 and j. */
static int levels_on_boundaries(const thx_scale *s)
{
    double lev[64];
    int count = thx_scale_levels(s, 0, lev, 64), n = thx_scale_bands(s, 0), ok = count == n - 1;
    for (int j = 1; ok && j < n; j++) {
        double v = lev[j - 1], t = thx_scale_apply(s, v), d = 1e-9 * fmax(fabs(v), 1e-3);
        ok = t == (double)j / n && floor(t * n) == j && thx_scale_band(t, n) == (j + 0.5) / n &&
             thx_scale_band(thx_scale_apply(s, v - d), n) == (j - 0.5) / n &&
             thx_scale_band(thx_scale_apply(s, v + d), n) == (j + 0.5) / n && thx_scale_invert(s, t) == v;
        if (!ok) fprintf(stderr, "level %d = %.17g: t = %.17g, n = %d\n", j, v, t, n);
    }
    return ok;
}

static void test_lab(void)
{
    /* map3d's series (client/scalesubs.cc, labvals7 and labvals13), as numbers: one decade of
       levels, going down from just above 10 */
    const float map3d7[7] = {1.0f, 1.5f, 2.2f, 3.3f, 4.7f, 6.8f, 10.f};
    const float map3d13[13] = {1.0f, 1.2f, 1.5f, 1.8f, 2.2f, 2.7f, 3.3f, 3.9f, 4.7f, 5.6f, 6.8f, 8.2f, 10.f};
    double lev[64];
    thx_scale s = make(THX_SCALE_LAB7, THX_MAPPING_SYMMETRIC, -10.5, 10.5);
    int n = thx_scale_levels(&s, 0, lev, 64), same = n == 15 && lev[7] == 0;
    for (int i = 0; same && i < 7; i++) same = (float)lev[8 + i] == map3d7[i] && lev[6 - i] == -lev[8 + i];
    CHECK(same);
    s.model = THX_SCALE_LAB13;
    n = thx_scale_levels(&s, 0, lev, 64), same = n == 27 && lev[13] == 0;
    for (int i = 0; same && i < 13; i++) same = (float)lev[14 + i] == map3d13[i] && lev[12 - i] == -lev[14 + i];
    CHECK(same);

    /* data -37..52 (map3d's ContValsLab gives these values, times its 1.0001) */
    const double sym7[15] = {-47, -33, -22, -15, -10, -6.8, -4.7, 0, 4.7, 6.8, 10, 15, 22, 33, 47};
    const double sep7[15] = {-33, -22, -15, -10, -6.8, -4.7, -3.3, 0, 4.7, 6.8, 10, 15, 22, 33, 47};
    const double sym13[27] = {-47, -39, -33, -27, -22, -18, -15, -12, -10, -8.2, -6.8, -5.6, -4.7, 0,
                              4.7, 5.6, 6.8,  8.2, 10,  12,  15,  18,  22,  27,  33,   39,   47};
    /* MIDPOINT: about c = 7.5 with half width 44.5: 7.5 -+ 33, 22, 15, 10, 6.8, 4.7, 3.3 */
    double mid7[15];
    const double l7[7] = {33, 22, 15, 10, 6.8, 4.7, 3.3};
    for (int i = 0; i < 7; i++) mid7[i] = 7.5 - l7[i], mid7[14 - i] = 7.5 + l7[i];
    mid7[7] = 7.5;
    thx_scale lab7 = make(THX_SCALE_LAB7, THX_MAPPING_SYMMETRIC, -37, 52);
    CHECK(levels_are(&lab7, sym7, 15, 0) && levels_on_boundaries(&lab7));
    lab7.mapping = THX_MAPPING_SEPARATE;
    CHECK(levels_are(&lab7, sep7, 15, 0) && levels_on_boundaries(&lab7));
    lab7.mapping = THX_MAPPING_TRUE; /* over both signs: map3d's, each side its own */
    CHECK(levels_are(&lab7, sep7, 15, 0) && levels_on_boundaries(&lab7));
    lab7.mapping = THX_MAPPING_MIDPOINT;
    CHECK(levels_are(&lab7, mid7, 15, 1e-15) && levels_on_boundaries(&lab7));
    thx_scale lab13 = make(THX_SCALE_LAB13, THX_MAPPING_SYMMETRIC, -37, 52);
    CHECK(levels_are(&lab13, sym13, 27, 0) && levels_on_boundaries(&lab13));
    CHECK(thx_scale_bands(&lab7, 12) == 16 && thx_scale_bands(&lab13, 3) == 28); /* the number asked is ignored */

    /* the ends and between levels: piecewise linear, uniform steps of t (16 bands) */
    thx_scale sep = make(THX_SCALE_LAB7, THX_MAPPING_SEPARATE, -37, 52);
    CHECK(thx_scale_apply(&sep, -37) == 0 && thx_scale_apply(&sep, 52) == 1 && thx_scale_apply(&sep, 0) == 0.5);
    CHECK_NEAR(thx_scale_apply(&sep, 40), 14.5 / 16, 1e-15);  /* midway 33..47 */
    CHECK_NEAR(thx_scale_apply(&sep, 49.5), 15.5 / 16, 1e-15); /* midway 47..52 */
    CHECK_NEAR(thx_scale_apply(&sep, 2.35), 8.5 / 16, 1e-15);  /* midway 0..4.7 */
    CHECK_NEAR(thx_scale_apply(&sep, -35), 0.5 / 16, 1e-15);   /* midway -37..-33 */
    CHECK(thx_scale_apply(&sep, -100) == 0 && thx_scale_apply(&sep, 1e9) == 1 && isnan(thx_scale_apply(&sep, NAN)));
    CHECK_NEAR(thx_scale_invert(&sep, 14.5 / 16), 40, 1e-12);

    /* TRUE over one sign: the levels strictly inside the range, from the end of larger magnitude */
    const double pos[3] = {22, 33, 47}, neg[3] = {-47, -33, -22};
    const double from0[7] = {4.7, 6.8, 10, 15, 22, 33, 47};
    thx_scale one = make(THX_SCALE_LAB7, THX_MAPPING_TRUE, 20, 52);
    CHECK(levels_are(&one, pos, 3, 0) && levels_on_boundaries(&one));
    CHECK(thx_scale_apply(&one, 20) == 0 && thx_scale_apply(&one, 22) == 0.25 && thx_scale_apply(&one, 52) == 1);
    one = make(THX_SCALE_LAB7, THX_MAPPING_TRUE, -52, -20);
    CHECK(levels_are(&one, neg, 3, 0) && levels_on_boundaries(&one));
    one = make(THX_SCALE_LAB7, THX_MAPPING_TRUE, 0, 52);
    CHECK(levels_are(&one, from0, 7, 0) && levels_on_boundaries(&one) && thx_scale_apply(&one, 0) == 0);
    one = make(THX_SCALE_LAB7, THX_MAPPING_TRUE, 50, 52); /* no level inside: one band */
    CHECK(thx_scale_bands(&one, 8) == 1 && thx_scale_levels(&one, 8, lev, 64) == 0 &&
          thx_scale_apply(&one, 51) == 0.5);

    /* strictly below the largest magnitude, decimal values in any decade */
    const double at47[15] = {-33, -22, -15, -10, -6.8, -4.7, -3.3, 0, 3.3, 4.7, 6.8, 10, 15, 22, 33};
    const double at10[15] = {-6.8, -4.7, -3.3, -2.2, -1.5, -1, -0.68, 0, 0.68, 1, 1.5, 2.2, 3.3, 4.7, 6.8};
    const double small[15] = {-0.047, -0.033, -0.022, -0.015, -0.01, -0.0068, -0.0047, 0,
                              0.0047, 0.0068, 0.01,   0.015,  0.022, 0.033,   0.047};
    const double big[15] = {-10000, -6800, -4700, -3300, -2200, -1500, -1000, 0,
                            1000,   1500,  2200,  3300,  4700,  6800,  10000};
    thx_scale t = make(THX_SCALE_LAB7, THX_MAPPING_SYMMETRIC, -47, 47);
    CHECK(levels_are(&t, at47, 15, 0) && levels_on_boundaries(&t));
    t.lo = -10, t.hi = 10;
    CHECK(levels_are(&t, at10, 15, 0) && levels_on_boundaries(&t));
    t.lo = 0, t.hi = 0.052;
    CHECK(levels_are(&t, small, 15, 0) && levels_on_boundaries(&t));
    t.lo = -12600, t.hi = 3;
    CHECK(levels_are(&t, big, 15, 0) && levels_on_boundaries(&t));
    /* lopsided SEPARATE, lab13: each side from its own end */
    thx_scale u = make(THX_SCALE_LAB13, THX_MAPPING_SEPARATE, -1, 10);
    CHECK(levels_on_boundaries(&u) && thx_scale_bands(&u, 0) == 28);
    n = thx_scale_levels(&u, 0, lev, 64);
    CHECK(n == 27 && lev[0] == -0.82 && lev[12] == -0.082 && lev[13] == 0 && lev[14] == 0.82 && lev[26] == 8.2);
    /* degenerate: a step at the centre, one band */
    thx_scale z = make(THX_SCALE_LAB7, THX_MAPPING_SYMMETRIC, 0, 0);
    CHECK(thx_scale_apply(&z, -1) == 0 && thx_scale_apply(&z, 0) == 0.5 && thx_scale_apply(&z, 2) == 1 &&
          thx_scale_bands(&z, 7) == 1 && thx_scale_levels(&z, 7, lev, 64) == 0 && thx_scale_invert(&z, 0.3) == 0);
}

/* ------------------------------------------------------------- analytic values */

static void test_values(void)
{
    /* SEPARATE: zero in the middle whatever the two ends */
    for (int m = 0; m < 5; m++) {
        thx_scale s = make((thx_scale_model)m, THX_MAPPING_SEPARATE, -1, 10);
        CHECK(thx_scale_apply(&s, -1) == 0 && thx_scale_apply(&s, 0) == 0.5 && thx_scale_apply(&s, 10) == 1);
        CHECK_NEAR(thx_scale_invert(&s, 0), -1, 1e-15); /* log: expm1(log1p(10)) / 10 is 1 + 2^-52 */
        CHECK_NEAR(thx_scale_invert(&s, 1), 10, 1e-14);
        CHECK(thx_scale_invert(&s, 0.5) == 0);
    }
    thx_scale s = make(THX_SCALE_LINEAR, THX_MAPPING_SEPARATE, -1, 10);
    CHECK(thx_scale_apply(&s, -0.5) == 0.25 && thx_scale_apply(&s, 5) == 0.75);
    s.model = THX_SCALE_LOG; /* each side by its own magnitude: t(-0.5) mirrors t(5) */
    CHECK_NEAR(thx_scale_apply(&s, 5), 0.5 * (1 + log(1 + 10 * 0.5) / log(11)), 1e-15);
    CHECK_NEAR(thx_scale_apply(&s, -0.5), 1 - thx_scale_apply(&s, 5), 1e-15);
    s.model = THX_SCALE_EXP;
    CHECK_NEAR(thx_scale_apply(&s, 5), 0.5 * (1 + (exp(1.5) - 1) / (exp(3) - 1)), 1e-15);
    /* a side without a range takes the other's; none at all: a step at zero */
    s = make(THX_SCALE_LINEAR, THX_MAPPING_SEPARATE, 2, 10);
    CHECK(thx_scale_apply(&s, 5) == 0.75 && thx_scale_apply(&s, -5) == 0.25);
    s.lo = s.hi = 0;
    CHECK(thx_scale_apply(&s, -3) == 0 && thx_scale_apply(&s, 0) == 0.5 && thx_scale_apply(&s, 1e-300) == 1);

    /* data -2..6 under the other mappings */
    thx_scale a = make(THX_SCALE_LINEAR, THX_MAPPING_TRUE, -2, 6);
    CHECK(thx_scale_apply(&a, 0) == 0.25 && thx_scale_apply(&a, -2) == 0 && thx_scale_apply(&a, 6) == 1);
    a.mapping = THX_MAPPING_MIDPOINT; /* the same map: linear, log and exp are odd about the middle */
    CHECK(thx_scale_apply(&a, 0) == 0.25 && thx_scale_apply(&a, 2) == 0.5);
    a.mapping = THX_MAPPING_SYMMETRIC; /* -6..6 */
    CHECK(thx_scale_apply(&a, 0) == 0.5 && thx_scale_apply(&a, -6) == 0 && thx_scale_apply(&a, 3) == 0.75);
    CHECK_NEAR(thx_scale_apply(&a, -2), 1.0 / 3, 1e-15);
    a.model = THX_SCALE_LOG;
    CHECK_NEAR(thx_scale_apply(&a, 3), 0.5 * (1 + log(1 + 10 * 0.5) / log(11)), 1e-15);
    a.mapping = THX_MAPPING_MIDPOINT; /* about 2, half width 4 */
    CHECK_NEAR(thx_scale_apply(&a, 4), 0.5 * (1 + log(1 + 10 * 0.5) / log(11)), 1e-15);
    a.model = THX_SCALE_EXP, a.k = 2;
    CHECK_NEAR(thx_scale_apply(&a, 0), 0.5 * (1 - (exp(2 * 0.5) - 1) / (exp(2) - 1)), 1e-15);
    /* lab7 over -2..6: SYMMETRIC levels +-4.7 .. 0.47 */
    thx_scale l = make(THX_SCALE_LAB7, THX_MAPPING_SYMMETRIC, -2, 6);
    CHECK(thx_scale_apply(&l, 4.7) == 15.0 / 16 && thx_scale_apply(&l, -0.47) == 7.0 / 16 &&
          thx_scale_apply(&l, -6) == 0);
    CHECK_NEAR(thx_scale_apply(&l, 5.35), 15.5 / 16, 1e-15);
}

/* ------------------------------------------------------------- every model x mapping */

static void test_properties(void)
{
    const double ranges[][2] = {{-37, 52}, {-1, 10}, {2, 10}, {-10, -2}, {0, 52}, {-5, 5}, {10, 10.5}, {-0.3, 1e4}};
    const int n_ranges = (int)(sizeof ranges / sizeof ranges[0]);
    int mono = 1, inside = 1, nan_kept = 1, round = 1, back = 1, same_n = 1, bands = 1, at_levels = 1;
    for (int m = 0; m < 5; m++)
        for (int p = 0; p < 4; p++)
            for (int r = 0; r < n_ranges; r++) {
                thx_scale s = make((thx_scale_model)m, (thx_scale_mapping)p, ranges[r][0], ranges[r][1]);
                double v0 = thx_scale_invert(&s, 0), v1 = thx_scale_invert(&s, 1), span = v1 - v0;
                enum { K = 4001 };
                static double v[K];
                static float tf[K];
                double prev = -1;
                for (int i = 0; i < K; i++) v[i] = v0 - 0.1 * span + 1.2 * span * i / (K - 1);
                thx_scale_apply_n(&s, v, K, tf);
                for (int i = 0; i < K; i++) {
                    double t = thx_scale_apply(&s, v[i]);
                    if (!(t >= prev)) mono = 0;
                    if (!(t >= 0 && t <= 1)) inside = 0;
                    if (tf[i] != (float)t) same_n = 0;
                    prev = t;
                    if (v[i] >= v0 && v[i] <= v1) {
                        double b = thx_scale_invert(&s, t);
                        if (!(fabs(b - v[i]) <= 1e-9 * fmax(1, fabs(v[i])))) {
                            if (round) fprintf(stderr, "%s/%s [%g, %g]: %.17g -> %.17g -> %.17g\n",
                                               thx_scale_model_name(s.model), thx_scale_mapping_name(s.mapping),
                                               s.lo, s.hi, v[i], t, b);
                            round = 0;
                        }
                    }
                }
                for (int i = 0; i <= 1000; i++) {
                    double t = i / 1000.0, tt = thx_scale_apply(&s, thx_scale_invert(&s, t));
                    if (!(fabs(tt - t) <= 1e-9)) back = 0;
                }
                nan_kept &= isnan(thx_scale_apply(&s, NAN)) && isnan(thx_scale_invert(&s, NAN));
                double nanv = NAN;
                float nant = 0;
                thx_scale_apply_n(&s, &nanv, 1, &nant);
                nan_kept &= isnan(nant);
                /* the values between two consecutive levels fill exactly one band, in order */
                double lev[64];
                int nb = thx_scale_bands(&s, 6), nl = thx_scale_levels(&s, 6, lev, 64);
                if (nl != nb - 1) bands = 0;
                for (int j = 0; j <= nl && bands; j++) {
                    double a = j == 0 ? v0 : lev[j - 1], b = j == nl ? v1 : lev[j];
                    if (!(b > a)) { bands = 0; break; }
                    for (int q = 1; q < 10; q++)
                        if (thx_scale_band(thx_scale_apply(&s, a + (b - a) * q / 10), nb) != (j + 0.5) / nb) bands = 0;
                    if (j < nl && fabs(thx_scale_apply(&s, b) - (double)(j + 1) / nb) > 1e-12) at_levels = 0;
                }
                if (!bands) {
                    fprintf(stderr, "bands: %s/%s [%g, %g]\n", thx_scale_model_name(s.model),
                            thx_scale_mapping_name(s.mapping), s.lo, s.hi);
                    bands = 1, at_levels = 0;
                }
            }
    CHECK(mono);
    CHECK(inside);
    CHECK(nan_kept);
    CHECK(round);
    CHECK(back);
    CHECK(same_n);
    CHECK(at_levels);
}

/* lo > hi: the same scale turned around, under every model and mapping */
static void test_reversed(void)
{
    const double ranges[][2] = {{-37, 52}, {-1, 10}, {2, 10}, {-10, -2}, {0, 52}, {20, 52}};
    int turned = 1, inverse = 1, same_levels = 1;
    for (int m = 0; m < 5; m++)
        for (int p = 0; p < 4; p++)
            for (int r = 0; r < 6; r++) {
                thx_scale s = make((thx_scale_model)m, (thx_scale_mapping)p, ranges[r][0], ranges[r][1]);
                thx_scale b = make((thx_scale_model)m, (thx_scale_mapping)p, ranges[r][1], ranges[r][0]);
                double v0 = thx_scale_invert(&s, 0), v1 = thx_scale_invert(&s, 1);
                for (int i = -50; i <= 1050; i++) {
                    double v = v0 + (v1 - v0) * i / 1000.0, t = i / 1000.0;
                    if (fabs(thx_scale_apply(&b, v) - (1 - thx_scale_apply(&s, v))) > 1e-15) turned = 0;
                    if (i >= 0 && i <= 1000 &&
                        fabs(thx_scale_invert(&b, t) - thx_scale_invert(&s, 1 - t)) > 1e-12 * fmax(1, fabs(v)))
                        inverse = 0;
                }
                double la[64], lb[64];
                int na = thx_scale_levels(&s, 6, la, 64), nb = thx_scale_levels(&b, 6, lb, 64);
                if (na != nb || thx_scale_bands(&s, 6) != thx_scale_bands(&b, 6)) same_levels = 0;
                for (int j = 0; j < na && j < nb; j++)
                    if (fabs(la[j] - lb[j]) > 1e-12 * fmax(1, fabs(la[j]))) same_levels = 0;
                if (!turned || !inverse || !same_levels) {
                    fprintf(stderr, "reversed %s/%s [%g, %g]\n", thx_scale_model_name(s.model),
                            thx_scale_mapping_name(s.mapping), s.lo, s.hi);
                    turned = inverse = same_levels = 1;
                    CHECK(0);
                }
            }
    CHECK(turned && inverse && same_levels);
    /* a reversed lab scale: its levels at 1 - j / n */
    thx_scale s = make(THX_SCALE_LAB7, THX_MAPPING_SEPARATE, 52, -37);
    CHECK(thx_scale_apply(&s, 47) == 1.0 / 16 && thx_scale_apply(&s, -33) == 15.0 / 16 &&
          thx_scale_apply(&s, 0) == 0.5);
}

/* The scale before mappings existed (thorax 98c5f55, src/render/colormap.c), kept here to show
   that TRUE gives exactly the same t. */
static double old_apply(const thx_scale *s, double v)
{
    if (isnan(v)) return v;
    double c = 0.5 * (s->lo + s->hi), h = 0.5 * (s->hi - s->lo);
    if (h == 0 || !isfinite(h)) return v < c ? 0 : v > c ? 1 : 0.5;
    double u = (v - c) / h;
    u = u < -1 ? -1 : u > 1 ? 1 : u;
    double k = s->k > 0 && isfinite(s->k) ? s->k : s->model == THX_SCALE_LOG ? 10 : s->model == THX_SCALE_EXP ? 3 : 0;
    double a = fabs(u), w = a;
    if (s->model == THX_SCALE_LOG) w = log1p(k * a) / log1p(k);
    else if (s->model == THX_SCALE_EXP) w = expm1(k * a) / expm1(k);
    return 0.5 * (copysign(w, u) + 1);
}

static double old_invert(const thx_scale *s, double t)
{
    if (isnan(t)) return t;
    double c = 0.5 * (s->lo + s->hi), h = 0.5 * (s->hi - s->lo);
    double w = 2 * (t < 0 ? 0 : t > 1 ? 1 : t) - 1, a = fabs(w), u = a;
    double k = s->k > 0 && isfinite(s->k) ? s->k : s->model == THX_SCALE_LOG ? 10 : s->model == THX_SCALE_EXP ? 3 : 0;
    if (s->model == THX_SCALE_LOG) u = expm1(a * log1p(k)) / k;
    else if (s->model == THX_SCALE_EXP) u = log1p(a * expm1(k)) / k;
    return c + h * copysign(u, w);
}

static void test_unchanged(void)
{
    const double ranges[][2] = {{-2, 6}, {-5, 5}, {10, 10.5}, {-12600, 12600}, {3, 3}, {-1e-7, 3e-7}};
    const double ks[] = {0, 1, 5, 25};
    int same = 1;
    for (int m = 0; m < 3; m++)
        for (int r = 0; r < 6; r++)
            for (int q = 0; q < 4; q++)
                for (int sym = 0; sym < 4; sym++) {
                    thx_scale s;
                    if (sym & 1) thx_scale_from_range(&s, (thx_scale_model)m, ranges[r][0], ranges[r][1], 1);
                    else s = make((thx_scale_model)m, THX_MAPPING_TRUE, ranges[r][0], ranges[r][1]);
                    s.k = ks[q];
                    if (sym & 2) { /* the picture module's reversed colours: the ends swapped */
                        double x = s.lo;
                        s.lo = s.hi, s.hi = x;
                    }
                    thx_scale old = s; /* the old code saw lo = -M, hi = M for a symmetric range */
                    for (int i = -100; i <= 1100; i++) {
                        double v = s.lo + (s.hi - s.lo) * i / 1000.0 + (i == 500 ? 0 : 1e-3 * i), t = i / 1000.0;
                        if (thx_scale_apply(&s, v) != old_apply(&old, v) || thx_scale_invert(&s, t) != old_invert(&old, t))
                            same = 0;
                    }
                }
    CHECK(same);
}

/* ------------------------------------------------------------- the range rule */

static void test_ranges(void)
{
    thx_scale s;
    thx_scale_from_range_mapped(&s, THX_SCALE_LAB7, THX_MAPPING_SYMMETRIC, -5, 2);
    CHECK(s.model == THX_SCALE_LAB7 && s.mapping == THX_MAPPING_SYMMETRIC && s.lo == -5 && s.hi == 5);
    thx_scale_from_range_mapped(&s, THX_SCALE_LOG, THX_MAPPING_SEPARATE, -1, 10);
    CHECK(s.k == 10 && s.mapping == THX_MAPPING_SEPARATE && s.lo == -1 && s.hi == 10);
    thx_scale_from_range_mapped(&s, THX_SCALE_LINEAR, THX_MAPPING_SEPARATE, 0, 0);
    CHECK(s.lo == -1 && s.hi == 1);
    thx_scale_from_range_mapped(&s, THX_SCALE_LINEAR, THX_MAPPING_SEPARATE, 4, 4); /* its magnitude is the scale */
    CHECK(s.lo == 4 && s.hi == 4 && thx_scale_apply(&s, 4) == 1 && thx_scale_apply(&s, 0) == 0.5);
    thx_scale_from_range_mapped(&s, THX_SCALE_EXP, THX_MAPPING_MIDPOINT, 3, 3);
    CHECK(s.k == 3 && s.lo == 2 && s.hi == 4 && thx_scale_apply(&s, 3) == 0.5);
    thx_scale_from_range_mapped(&s, THX_SCALE_LAB13, THX_MAPPING_TRUE, INFINITY, -INFINITY);
    CHECK(s.lo == -1 && s.hi == 1 && s.k == 0);
    const double v[6] = {-1, 3, NAN, INFINITY, 0.5, -INFINITY};
    thx_scale_from_data_mapped(&s, THX_SCALE_LINEAR, THX_MAPPING_SEPARATE, v, 6);
    CHECK(s.lo == -1 && s.hi == 3 && thx_scale_apply(&s, 0) == 0.5 && thx_scale_apply(&s, -0.5) == 0.25);
    /* the older forms: symmetric = SYMMETRIC, else TRUE */
    thx_scale_from_data(&s, THX_SCALE_LINEAR, v, 6, 1);
    CHECK(s.mapping == THX_MAPPING_SYMMETRIC && s.lo == -3 && s.hi == 3);
    thx_scale_from_range(&s, THX_SCALE_LOG, -5, 2, 0);
    CHECK(s.mapping == THX_MAPPING_TRUE && s.lo == -5 && s.hi == 2 && s.k == 10);
    /* levels of the analytic models: the values at t = j / n */
    thx_scale lin = make(THX_SCALE_LINEAR, THX_MAPPING_TRUE, -2, 6);
    double lev[8] = {0};
    CHECK(thx_scale_bands(&lin, 4) == 4 && thx_scale_levels(&lin, 4, lev, 8) == 3 && lev[0] == 0 && lev[1] == 2 &&
          lev[2] == 4);
    lev[1] = 99;
    CHECK(thx_scale_levels(&lin, 4, lev, 1) == 3 && lev[0] == 0 && lev[1] == 99); /* only max written */
    CHECK(thx_scale_levels(&lin, 0, NULL, 0) == 0 && thx_scale_levels(&lin, 1, NULL, 0) == 0);
}

/* ------------------------------------------------------------- the colour bar */

static const unsigned char *px(const thx_raster *im, int x, int y) { return im->rgba + 4 * ((size_t)y * im->w + x); }

static void test_colorbar(void)
{
    thx_font *f = NULL;
    CHECK_OK(ctx, thx_font_open(ctx, NULL, 12, &f));
    const int bx = 20, by = 20, bw = 16, bh = 320;
    const unsigned char white[4] = {255, 255, 255, 255};
    thx_raster *img = NULL;
    CHECK_OK(ctx, thx_raster_create(ctx, 120, 360, &img));
    if (!img) return;

    /* lab7, SYMMETRIC over -37..52, 12 shades asked: 16 bands; a tick at each of the 15 levels and
       nowhere else */
    thx_scale s = make(THX_SCALE_LAB7, THX_MAPPING_SYMMETRIC, -37, 52);
    for (int pass = 0; pass < 2; pass++) {
        thx_raster_fill(img, white);
        thx_draw_colorbar(img, pass ? f : NULL, bx, by, bw, bh, THX_CMAP_ECG, &s, 12, 5, "V", "mV");
        int changes = 0;
        for (int p = 1; p < bh; p++) changes += memcmp(px(img, bx + bw / 2, by + p), px(img, bx + bw / 2, by + p - 1), 3) != 0;
        CHECK(changes == 15);
        int ticks = 0, on_levels = 1;
        for (int row = by; row < by + bh; row++)
            if (px(img, bx + bw + 3, row)[0] < 128) {
                ticks++;
                double j = (by + bh - row) / (double)bh * 16;
                if (fabs(j - round(j)) > 0.5 / bh * 16 + 1e-9) on_levels = 0;
            }
        CHECK(ticks == 15 && on_levels);
        /* labels beside them (with the font) */
        int ink = 0;
        for (int j = by; j < by + bh; j++)
            for (int i = bx + bw + 7; i < 120; i++) ink += px(img, i, j)[0] < 128;
        CHECK(pass ? ink > 200 : ink == 0);
    }
    /* reversed: ticks at the same places (the strip is the map in t; the labels run the other way) */
    thx_scale rev = make(THX_SCALE_LAB7, THX_MAPPING_SYMMETRIC, 52, -37);
    thx_raster_fill(img, white);
    thx_draw_colorbar(img, NULL, bx, by, bw, bh, THX_CMAP_ECG, &rev, 12, 5, NULL, NULL);
    int rticks = 0, ron = 1;
    for (int row = by; row < by + bh; row++)
        if (px(img, bx + bw + 3, row)[0] < 128) {
            rticks++;
            double j = (by + bh - row) / (double)bh * 16;
            if (fabs(j - round(j)) > 0.5 / bh * 16 + 1e-9) ron = 0;
        }
    CHECK(rticks == 15 && ron);
    /* lab13 in a short bar: 28 bands, labels on every k-th level only, never touching */
    thx_scale s13 = make(THX_SCALE_LAB13, THX_MAPPING_SYMMETRIC, -37, 52);
    thx_raster_fill(img, white);
    thx_draw_colorbar(img, f, bx, by, bw, 200, THX_CMAP_ECG, &s13, 4, 5, NULL, NULL);
    int groups = 0, in = 0, ticks = 0;
    for (int row = by - 10; row < by + 210; row++) {
        int any = 0;
        for (int i = bx + bw + 7; i < 120; i++) any |= px(img, i, row)[0] < 128;
        groups += any && !in;
        in = any;
        ticks += px(img, bx + bw + 3, row)[0] < 128;
    }
    CHECK(ticks == 27 && groups >= 5 && groups < 27);

    /* SEPARATE, linear, 4 labels (none at the middle): a line across the strip at zero, and a "0" */
    thx_scale sep = make(THX_SCALE_LINEAR, THX_MAPPING_SEPARATE, -1, 10);
    thx_raster_fill(img, white);
    thx_draw_colorbar(img, f, bx, by, bw, bh, THX_CMAP_ECG, &sep, 0, 4, NULL, NULL);
    int zero_row = by + bh - bh / 2, across = 1, ticks4 = 0;
    for (int i = bx; i < bx + bw; i++) across &= px(img, i, zero_row)[0] < 64 && px(img, i, zero_row)[2] < 64;
    for (int row = by; row < by + bh; row++) ticks4 += px(img, bx + bw + 3, row)[0] < 128;
    CHECK(across && ticks4 == 5);
    /* ... which a TRUE mapping does not have */
    sep.mapping = THX_MAPPING_TRUE;
    thx_raster_fill(img, white);
    thx_draw_colorbar(img, f, bx, by, bw, bh, THX_CMAP_ECG, &sep, 0, 4, NULL, NULL);
    int dark = 0;
    for (int i = bx; i < bx + bw; i++) dark += px(img, i, zero_row)[0] < 64 && px(img, i, zero_row)[2] < 64;
    CHECK(dark == 0);
    thx_raster_destroy(&img);
    thx_font_close(&f);
}

int main(void)
{
    if (thx_ctx_create(&ctx) != THX_OK) return 1;
    test_names();
    test_lab();
    test_values();
    test_properties();
    test_reversed();
    test_unchanged();
    test_ranges();
    test_colorbar();
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
