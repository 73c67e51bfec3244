/*
 * Tests of activation and recovery times (thorax/leads/activation.h, src/leads/activation.c):
 *  - synthetic downstrokes -A tanh((t - t_a) / tau): t_a anywhere within a sample, tau from half a
 *    sample to 4 samples, time axis not starting at 0 and 2 ms steps: each derivative (least-squares
 *    over 5 and 7 samples, centred over 3, and centred over 5 for the slower steps) finds t_a within
 *    0.1 sample; a faster upstroke elsewhere is ignored;
 *  - recovery: a T-wave step B tanh((t - t_r) / tau) recovered within 0.1 sample, and a Gaussian T
 *    wave whose steepest upstroke is at t_peak - sigma;
 *  - seeded Gaussian noise (1% and 3% of the step): the error stays within the bounds measured below;
 *  - flat rows, NaN rows, a row with its only downstroke in NaN, a downstroke below min_slope: NaN;
 *    a NaN sample away from the downstroke changes nothing;
 *  - the search window (a steeper downstroke outside it is not taken) and the recovery window;
 *  - bad options refused with a message; the result's shape, units and validity;
 *  - the real 490-lead sock recording (map3d, rsm10jan01-cs-0004.mat, its geometry 490sock.pts/.fac):
 *    without a window, the activation times fall inside the QRS window of the recording's own
 *    fiducials; they agree with the recording's own activation fiducials (map3d fiducial type 10,
 *    read here through libmatio); they are spatially smooth over the sock's triangles; recovery
 *    times fall between the end of QRS and the end of T.
 */
#include <math.h>
#include <stdio.h>
#include <matio.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/io/model_dir.h"
#include "thorax/io/series_file.h"
#include "thorax/leads/activation.h"

static thx_ctx *ctx;

static uint64_t rng_state = 2024;
static double urand(void)
{
    uint64_t z = (rng_state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    return (double)(z >> 11) * (1.0 / 9007199254740992.0);
}
static double grand(void) /* standard normal (Box-Muller) */
{
    double u = urand(), v = urand();
    return sqrt(-2 * log(u + 1e-300)) * cos(2 * M_PI * v);
}

/* A rows x frames series with time t0 + f dt ms, values 0. */
static thx_series *make(size_t rows, size_t frames, double t0, double dt)
{
    thx_series *s = NULL;
    CHECK_OK(ctx, thx_series_create(ctx, rows, frames, &s));
    if (!s) exit(1);
    for (size_t f = 0; f < frames; f++) s->time[f] = t0 + (double)f * dt;
    snprintf(s->unit, sizeof s->unit, "mV");
    return s;
}
#define V(s, r, f) ((s)->v[(size_t)(f) * (s)->n_rows + (r)])

static thx_series *times(const thx_series *s, const thx_activation_opts *o)
{
    thx_series *a = NULL;
    CHECK_OK(ctx, thx_activation_times(ctx, s, o, &a));
    if (!a) exit(1);
    return a;
}

/* ------------------------------------------------------------- synthetic steps */

static void test_steps(void)
{
    const double dt = 2, t0 = 37;
    const double taus[4] = {0.5, 1, 2, 4}; /* samples */
    const int n_off = 11;
    size_t rows = 4 * n_off, frames = 300;
    thx_series *s = make(rows, frames, t0, dt);
    double *ta = malloc(rows * sizeof *ta);
    for (size_t r = 0; r < rows; r++) {
        double tau = taus[r / n_off] * dt, A = 5 + (double)(r % 3);
        ta[r] = t0 + 150 * dt + (double)(r % n_off) / (n_off - 1) * dt;
        for (size_t f = 0; f < frames; f++) {
            double t = s->time[f];
            /* the downstroke, plus a faster upstroke 60 samples before it (an R wave's rise) */
            V(s, r, f) = -A * tanh((t - ta[r]) / tau) + 2 * A * (1 + tanh((t - (ta[r] - 60 * dt)) / (0.3 * tau)));
        }
    }
    struct {
        thx_deriv_method m;
        int h;
        double min_tau; /* slowest step it must resolve */
    } cases[4] = {{THX_DERIV_SAVGOL, 2, 0.5}, {THX_DERIV_SAVGOL, 3, 0.5}, {THX_DERIV_CENTRED, 1, 0.5},
                  {THX_DERIV_CENTRED, 2, 1}};
    for (int c = 0; c < 4; c++) {
        thx_activation_opts o;
        thx_activation_opts_default(&o);
        o.method = cases[c].m;
        o.half_width = cases[c].h;
        thx_series *a = times(s, &o);
        CHECK(a->n_rows == rows && a->n_frames == 1);
        CHECK(strcmp(a->unit, "ms") == 0 && a->time_unit[0] == '\0');
        CHECK_OK(ctx, thx_series_validate(ctx, a, "activation"));
        double worst = 0;
        for (size_t r = 0; r < rows; r++) {
            if (taus[r / n_off] < cases[c].min_tau) continue;
            double e = fabs(a->v[r] - ta[r]) / dt;
            if (!(e <= worst)) worst = e; /* NaN counts as the worst */
        }
        CHECK(worst <= 0.1);
        printf("steps, %s over %d samples: largest error %.3f sample\n",
               cases[c].m == THX_DERIV_SAVGOL ? "least squares" : "centred", 2 * cases[c].h + 1, worst);
        thx_series_destroy(&a);
    }
    /* the default is the least-squares derivative over 5 samples */
    thx_series *a = times(s, NULL);
    for (size_t r = 0; r < rows; r++) CHECK(fabs(a->v[r] - ta[r]) <= 0.1 * dt);
    CHECK(strstr(a->label, "least-squares") != NULL);
    thx_series_destroy(&a);
    free(ta);
    thx_series_destroy(&s);
}

static void test_recovery(void)
{
    const double dt = 1;
    size_t frames = 500;
    thx_series *s = make(3, frames, 0, dt);
    /* row 0: downstroke at 120.3, T-wave step up at 330.7; row 1: a Gaussian T wave peaking at 340,
     * sigma 25 (steepest upstroke at 315), after a downstroke at 110.6; row 2: no downstroke */
    for (size_t f = 0; f < frames; f++) {
        double t = s->time[f];
        V(s, 0, f) = -8 * tanh((t - 120.3) / 2) + 1.5 * tanh((t - 330.7) / 15);
        V(s, 1, f) = -8 * tanh((t - 110.6) / 3) + 3 * exp(-(t - 340) * (t - 340) / (2 * 25.0 * 25.0));
        V(s, 2, f) = 1;
    }
    thx_activation_opts o;
    thx_activation_opts_default(&o);
    o.recovery = 1;
    o.t0 = 50;
    o.t1 = 200; /* the QRS window; recovery searched from its end */
    thx_series *a = times(s, &o);
    CHECK(a->n_frames == 2 && a->time[0] == 0 && a->time[1] == 1);
    CHECK(strstr(a->label, "recovery") != NULL);
    CHECK_NEAR(a->v[0], 120.3, 0.1);
    CHECK_NEAR(a->v[1], 110.6, 0.1);
    CHECK_NEAR(a->v[3], 330.7, 0.1);
    CHECK_NEAR(a->v[4], 315, 0.1);
    CHECK(isnan(a->v[2]) && isnan(a->v[5]));
    printf("recovery: step %.3f (330.7), Gaussian T %.3f (315)\n", a->v[3], a->v[4]);
    thx_series_destroy(&a);
    /* without t1 the recovery is searched right after the activation: the T wave must then be given */
    o.t1 = NAN;
    o.rec_t0 = 250;
    o.rec_t1 = 450;
    a = times(s, &o);
    CHECK_NEAR(a->v[3], 330.7, 0.1);
    CHECK_NEAR(a->v[4], 315, 0.1);
    thx_series_destroy(&a);
    /* a recovery window that ends before the T wave's upstroke: the steepest rise inside it */
    o.rec_t0 = 250;
    o.rec_t1 = 300;
    a = times(s, &o);
    CHECK(a->v[3] >= 250 && a->v[3] <= 300);
    thx_series_destroy(&a);
    /* a recovery window before the activation: nothing after the activation in it */
    o.rec_t0 = 0;
    o.rec_t1 = 100;
    a = times(s, &o);
    CHECK(isnan(a->v[3]) && isnan(a->v[4]));
    CHECK(!isnan(a->v[0]));
    thx_series_destroy(&a);
    thx_series_destroy(&s);
}

/* Noise: 200 rows of one step (tau 2 samples, amplitude 10 mV, t_a random within its sample) with
 * seeded white noise of 1% and 3% of the step (0.2 and 0.6 mV standard deviation). */
static void test_noise(void)
{
    const size_t rows = 200, frames = 200;
    /* measured (error in samples, 200 rows): 1%: rms 0.12 / 0.10, largest 0.36 / 0.35 (5 / 7 samples);
     * 3%: rms 0.34 / 0.32, largest 1.02 / 1.12. The bounds are 1.5 times those. */
    const double sd[2] = {0.2, 0.6}, bound_rms[2] = {0.18, 0.5}, bound_max[2] = {0.55, 1.7};
    for (int k = 0; k < 2; k++) {
        thx_series *s = make(rows, frames, 0, 1);
        double *ta = malloc(rows * sizeof *ta);
        for (size_t r = 0; r < rows; r++) {
            ta[r] = 100 + urand();
            for (size_t f = 0; f < frames; f++)
                V(s, r, f) = -5 * tanh((s->time[f] - ta[r]) / 2) + sd[k] * grand();
        }
        for (int h = 2; h <= 3; h++) {
            thx_activation_opts o;
            thx_activation_opts_default(&o);
            o.half_width = h;
            thx_series *a = times(s, &o);
            double se = 0, worst = 0;
            for (size_t r = 0; r < rows; r++) {
                double e = fabs(a->v[r] - ta[r]);
                se += e * e;
                if (!(e <= worst)) worst = e;
            }
            double rms = sqrt(se / rows);
            CHECK(rms <= bound_rms[k]);
            CHECK(worst <= bound_max[k]);
            printf("noise %.0f%% of the step, least squares over %d samples: rms error %.3f sample, largest %.3f\n",
                   100 * sd[k] / 20, 2 * h + 1, rms, worst);
            thx_series_destroy(&a);
        }
        free(ta);
        thx_series_destroy(&s);
    }
}

static void test_missing(void)
{
    size_t frames = 200;
    thx_series *s = make(6, frames, 0, 1);
    for (size_t f = 0; f < frames; f++) {
        double t = s->time[f], step = -5 * tanh((t - 80.4) / 2);
        V(s, 0, f) = 3;                                     /* flat */
        V(s, 1, f) = NAN;                                   /* lost lead */
        V(s, 2, f) = step;                                  /* a NaN sample far from the downstroke: */
        V(s, 3, f) = (f >= 75 && f <= 86) ? NAN : step;     /* the downstroke lost */
        V(s, 4, f) = 0.01 * step;                           /* a weak downstroke: 0.025 mV/ms */
        V(s, 5, f) = 5 * tanh((t - 80) / 2);                /* only an upstroke */
    }
    V(s, 2, 150) = NAN;
    thx_activation_opts o;
    thx_activation_opts_default(&o);
    thx_series *a = times(s, &o);
    CHECK(isnan(a->v[0]));
    CHECK(isnan(a->v[1]));
    CHECK_NEAR(a->v[2], 80.4, 0.1);
    /* the lost downstroke: whatever slope is left outside it is the tanh's tail, far from 80 */
    CHECK(isnan(a->v[3]) || fabs(a->v[3] - 80.4) > 5);
    CHECK_NEAR(a->v[4], 80.4, 0.1);
    /* an upstroke only: its tails still fall nowhere; min_slope 0 keeps any negative slope */
    thx_series_destroy(&a);
    o.min_slope = 0.1; /* mV/ms */
    a = times(s, &o);
    CHECK(isnan(a->v[0]) && isnan(a->v[1]) && isnan(a->v[4]) && isnan(a->v[5]));
    CHECK_NEAR(a->v[2], 80.4, 0.1);
    thx_series_destroy(&a);
    thx_series_destroy(&s);
}

static void test_window(void)
{
    size_t frames = 400;
    thx_series *s = make(1, frames, 0, 1);
    /* a steep downstroke at 100.2 (a pacing artefact), the activation at 250.6 */
    for (size_t f = 0; f < frames; f++) {
        double t = s->time[f];
        V(s, 0, f) = -20 * tanh((t - 100.2) / 0.7) - 6 * tanh((t - 250.6) / 2);
    }
    thx_series *a = times(s, NULL);
    CHECK_NEAR(a->v[0], 100.2, 0.1);
    thx_series_destroy(&a);
    thx_activation_opts o;
    thx_activation_opts_default(&o);
    o.t0 = 150;
    a = times(s, &o);
    CHECK_NEAR(a->v[0], 250.6, 0.1);
    thx_series_destroy(&a);
    o.t0 = 150;
    o.t1 = 240; /* neither downstroke's centre inside: the steepest slope there, at the window's end */
    a = times(s, &o);
    CHECK(a->v[0] >= 239.5 && a->v[0] <= 240.5);
    thx_series_destroy(&a);
    o.t0 = 500; /* after the last sample: nothing */
    o.t1 = NAN;
    a = times(s, &o);
    CHECK(isnan(a->v[0]));
    thx_series_destroy(&a);
    thx_series_destroy(&s);
}

static void test_bad(void)
{
    thx_series *s = make(2, 10, 0, 1), *a = NULL;
    thx_activation_opts o;
    thx_activation_opts_default(&o);
    o.half_width = 0;
    CHECK(thx_activation_times(ctx, s, &o, &a) == THX_EINPUT && a == NULL);
    CHECK(tl_msg_has(ctx, "0 samples either side"));
    o.half_width = 5; /* 11 samples of 10 */
    CHECK(thx_activation_times(ctx, s, &o, &a) == THX_EINPUT && a == NULL);
    CHECK(tl_msg_has(ctx, "has 10"));
    o.half_width = 4;
    CHECK_OK(ctx, thx_activation_times(ctx, s, &o, &a));
    thx_series_destroy(&a);
    thx_activation_opts_default(&o);
    o.t0 = 5;
    o.t1 = 4;
    CHECK(thx_activation_times(ctx, s, &o, &a) == THX_EINPUT);
    CHECK(tl_msg_has(ctx, "window 5..4"));
    thx_activation_opts_default(&o);
    o.rec_t0 = 5;
    o.rec_t1 = 4;
    CHECK(thx_activation_times(ctx, s, &o, &a) == THX_EINPUT);
    thx_activation_opts_default(&o);
    o.min_slope = -1;
    CHECK(thx_activation_times(ctx, s, &o, &a) == THX_EINPUT);
    o.min_slope = NAN;
    CHECK(thx_activation_times(ctx, s, &o, &a) == THX_EINPUT);
    thx_activation_opts_default(&o);
    o.method = (thx_deriv_method)7;
    CHECK(thx_activation_times(ctx, s, &o, &a) == THX_EINPUT);
    s->time[3] = s->time[2]; /* not increasing */
    CHECK(thx_activation_times(ctx, s, NULL, &a) == THX_EINPUT && a == NULL);
    CHECK(tl_msg_has(ctx, "times must increase"));
    thx_series_destroy(&s);
}

/* ------------------------------------------------------------- the real sock */

static double mat_num(matvar_t *v, size_t k)
{
    if (!v || !v->data) return NAN;
    switch (v->class_type) {
    case MAT_C_DOUBLE: return ((const double *)v->data)[k];
    case MAT_C_SINGLE: return ((const float *)v->data)[k];
    case MAT_C_UINT8: return ((const uint8_t *)v->data)[k];
    case MAT_C_INT8: return ((const int8_t *)v->data)[k];
    case MAT_C_UINT16: return ((const uint16_t *)v->data)[k];
    case MAT_C_INT16: return ((const int16_t *)v->data)[k];
    case MAT_C_INT32: return ((const int32_t *)v->data)[k];
    case MAT_C_UINT32: return ((const uint32_t *)v->data)[k];
    default: return NAN;
    }
}

/* The recording's own fiducials (ts.fids: a struct array of value, type): QRS onset (type 2) and
 * offset (4), T offset (7), and the activation fiducial of each lead (type 10; n values). */
static int read_fids(const char *path, double *qrs_on, double *qrs_off, double *t_off, double *act, size_t n)
{
    mat_t *mat = Mat_Open(path, MAT_ACC_RDONLY);
    if (!mat) return -1;
    matvar_t *ts = Mat_VarRead(mat, "ts");
    int found = 0;
    matvar_t *fids = ts ? Mat_VarGetStructFieldByName(ts, "fids", 0) : NULL;
    if (fids && fids->class_type == MAT_C_STRUCT) {
        size_t nf = 1;
        for (int d = 0; d < fids->rank; d++) nf *= fids->dims[d];
        for (size_t k = 0; k < nf; k++) {
            matvar_t *ty = Mat_VarGetStructFieldByName(fids, "type", k);
            matvar_t *va = Mat_VarGetStructFieldByName(fids, "value", k);
            if (!ty || !va) continue;
            size_t nv = 1;
            for (int d = 0; d < va->rank; d++) nv *= va->dims[d];
            int type = (int)mat_num(ty, 0);
            if (type == 2 && nv == 1) *qrs_on = mat_num(va, 0), found |= 1;
            if (type == 4 && nv == 1) *qrs_off = mat_num(va, 0), found |= 2;
            if (type == 7 && nv == 1) *t_off = mat_num(va, 0), found |= 4;
            if (type == 10 && nv == n) {
                for (size_t i = 0; i < n; i++) act[i] = mat_num(va, i);
                found |= 8;
            }
        }
    }
    Mat_VarFree(ts);
    Mat_Close(mat);
    return found == 15 ? 0 : -1;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static void test_sock(void)
{
    const char *rec = tl_src_path(__FILE__, "../../shared/data/map3d/data/socks/10jan01/rsm10jan01-cs-0004.mat");
    const char *pts = tl_src_path(__FILE__, "../../shared/data/map3d/geom/socks/490sock.pts");
    const char *fac = tl_src_path(__FILE__, "../../shared/data/map3d/geom/socks/490sock.fac");
    /* the data folder is part of the project's setup: its absence is a failure */
    CHECK(tl_exists(rec) && tl_exists(pts) && tl_exists(fac));
    if (!tl_exists(rec) || !tl_exists(pts) || !tl_exists(fac)) return;
    thx_series *s = NULL;
    CHECK_OK(ctx, thx_series_read(ctx, rec, THX_SERIES_AUTO, &s));
    thx_surface *sock = NULL;
    CHECK_OK(ctx, thx_surface_read_ptsfac(ctx, pts, fac, "sock", THX_ROLE_HEART, &sock, NULL));
    if (!s || !sock) return;
    const size_t n = 490;
    CHECK(s->n_rows == n && s->n_frames == 712 && sock->n_nodes == n);
    CHECK(strcmp(s->unit, "mV") == 0 && s->time[1] - s->time[0] == 1); /* 1000 Hz: time[f] = f ms */
    double qrs_on = NAN, qrs_off = NAN, t_off = NAN, *fid = malloc(n * sizeof *fid);
    CHECK(read_fids(rec, &qrs_on, &qrs_off, &t_off, fid, n) == 0);
    /* map3d's fiducials of this recording: QRS 251.8 .. 300.4, end of T 523.9 (frames = ms here) */
    CHECK(qrs_on > 250 && qrs_on < 253 && qrs_off > 299 && qrs_off < 302 && t_off > 520 && t_off < 526);

    /* no window: the steepest downstroke of the whole record, with leads flatter than 0.2 mV/ms
     * dropped. Measured: 489 of 490 in the QRS window; lead 145 (1-based; its steepest downstroke in
     * the QRS is 0.01 mV/ms, against 2.5 mV/ms for the median lead) is NaN. */
    thx_activation_opts o;
    thx_activation_opts_default(&o);
    o.min_slope = 0.2;
    thx_series *a = times(s, &o);
    size_t inside = 0, nan = 0;
    for (size_t i = 0; i < n; i++) {
        if (isnan(a->v[i])) {
            if (nan++ == 0) printf("sock: lead %zu (1-based) has no downstroke steeper than 0.2 mV/ms\n", i + 1);
        } else if (a->v[i] >= qrs_on && a->v[i] <= qrs_off) inside++;
    }
    printf("sock: %zu of %zu activation times in the QRS window %.1f..%.1f ms, %zu NaN (no downstroke steeper than "
           "0.2 mV/ms)\n", inside, n, qrs_on, qrs_off, nan);
    CHECK(inside + nan == n);
    CHECK(nan <= 3);
    thx_series_destroy(&a);

    /* in the QRS window: agreement with the recording's own activation fiducials (values in frames,
     * which are our times in ms). Measured: 486 of 490 (99.2%) within 1 ms, median difference
     * 0.18 ms. */
    o.t0 = qrs_on;
    o.t1 = qrs_off;
    o.min_slope = 0;
    a = times(s, &o);
    double *d = malloc(n * sizeof *d);
    size_t within = 0, m = 0;
    for (size_t i = 0; i < n; i++) {
        if (isnan(a->v[i])) continue;
        d[m++] = a->v[i] - fid[i];
        within += fabs(a->v[i] - fid[i]) <= 1;
    }
    qsort(d, m, sizeof *d, cmp_double);
    double med = m ? d[m / 2] : NAN;
    printf("sock: against map3d's activation fiducials: %zu of %zu within 1 ms, median difference %.2f ms\n", within,
           n, med);
    CHECK(m == n);
    CHECK(within >= 0.97 * n);
    CHECK(fabs(med) < 0.5);

    /* smoothness: neighbours on the sock's triangles differ by much less than the spread over the
     * sock. Measured: spread 26.9 ms (the paced beat spreading from its site), the median difference
     * along the 1,428 edges (median length 5 mm) 1.52 ms and their 95th percentile 5.81 ms, against a
     * median of 4.67 ms between random pairs of nodes. */
    double lo = INFINITY, hi = -INFINITY;
    for (size_t i = 0; i < n; i++) lo = fmin(lo, a->v[i]), hi = fmax(hi, a->v[i]);
    /* the edges of the triangles, each once: pairs (lo, hi) as lo * n + hi, sorted, duplicates dropped */
    size_t ne = 0, nk = 3 * sock->n_tris;
    double *key = malloc(nk * sizeof *key), *de = malloc(nk * sizeof *de);
    for (size_t t = 0; t < sock->n_tris; t++)
        for (int k = 0; k < 3; k++) {
            int32_t p = sock->tri[3 * t + k], q = sock->tri[3 * t + (k + 1) % 3];
            key[3 * t + (size_t)k] = (double)(p < q ? p : q) * (double)n + (double)(p < q ? q : p);
        }
    qsort(key, nk, sizeof *key, cmp_double);
    for (size_t k = 0; k < nk; k++) {
        if (k && key[k] == key[k - 1]) continue;
        size_t p = (size_t)(key[k] / (double)n), q = (size_t)key[k] - p * n;
        de[ne++] = fabs(a->v[p] - a->v[q]);
    }
    free(key);
    qsort(de, ne, sizeof *de, cmp_double);
    double edge_med = de[ne / 2], edge_95 = de[(size_t)(0.95 * (double)ne)];
    double *dr = malloc(20000 * sizeof *dr);
    for (size_t k = 0; k < 20000; k++) {
        size_t p = (size_t)(urand() * n), q = (size_t)(urand() * n);
        dr[k] = fabs(a->v[p] - a->v[q]);
    }
    qsort(dr, 20000, sizeof *dr, cmp_double);
    double rand_med = dr[10000];
    printf("sock: activation spread %.1f ms; along %zu edges median |difference| %.2f ms, 95th percentile %.2f ms; "
           "random pairs median %.2f ms\n", hi - lo, ne, edge_med, edge_95, rand_med);
    CHECK(hi - lo > 15);
    CHECK(edge_med < 0.1 * (hi - lo));
    CHECK(edge_95 < 0.25 * (hi - lo));
    CHECK(ne == 1428);
    CHECK(edge_med < 0.5 * rand_med);
    thx_series_destroy(&a);

    /* recovery in the T wave: between the end of QRS and the end of T, after the activation */
    o.recovery = 1;
    o.rec_t0 = qrs_off;
    o.rec_t1 = t_off;
    a = times(s, &o);
    size_t ok = 0;
    for (size_t i = 0; i < n; i++) ok += a->v[n + i] >= qrs_off && a->v[n + i] <= t_off && a->v[n + i] > a->v[i];
    printf("sock: %zu of %zu recovery times between the end of QRS and the end of T\n", ok, n);
    CHECK(ok == n);
    thx_series_destroy(&a);
    free(de);
    free(dr);
    free(d);
    free(fid);
    thx_surface_destroy(&sock);
    thx_series_destroy(&s);
}

/* The data folder of the project's setup (../shared/data/map3d beside the worktree). */
static void map3d_path(char *out, size_t size, const char *rel)
{
    char r[1024];
    snprintf(r, sizeof r, "../../shared/data/map3d/%s", rel);
    snprintf(out, size, "%s", tl_src_path(__FILE__, r));
}

/*
 * The window an activation map is taken from (thx_activation_window_choose) and the record's own
 * per-lead fiducials as a map (thx_activation_from_fiducials):
 *  - synthetic: three beats (Gaussian QRS on 4 rows) with the record starting inside the first:
 *    the second beat is taken (the first complete one), its window holds its QRS and none of the
 *    other beats; global fiducials qon/soff at fractional frames on a 2 ms axis from 100 ms give
 *    their times; a flat record and a 6-frame one give the whole series;
 *  - the Utah tank run (2 beats, 512 channels): the .mat (no fiducials) gives beat 1 of 2 from the
 *    RMS curve, within 10 ms of the QRS map3d's own .tsdf fiducials mark (qon 155, soff 196), and
 *    the steepest downstrokes of the sock's 128 leads in it span under 40 ms (the whole series gave
 *    88.9-589 ms); the .tsdf gives exactly its fiducials' window (recovery soff .. toff 384);
 *  - the 490-lead sock: its act and rec fiducials as maps equal the file's values read through
 *    libmatio (frames = ms here), and its window is its qon .. soff.
 */
static void test_window_choice(void)
{
    thx_activation_window w;
    /* synthetic: beats at frames 10 (cut by the start), 130, 250; 4 rows, 2 ms from 100 ms */
    thx_series *s = make(4, 300, 100, 2);
    for (size_t f = 0; f < 300; f++)
        for (size_t r = 0; r < 4; r++) {
            double v = 0;
            for (int b = 0; b < 3; b++) {
                double c = 10 + 120.0 * b + 2.0 * (double)r, x = ((double)f - c) / 6;
                v += (r % 2 ? -5 : 5) * exp(-0.5 * x * x);
            }
            V(s, r, f) = v + 0.01 * (double)r;
        }
    CHECK_OK(ctx, thx_activation_window_choose(ctx, s, &w));
    CHECK(w.source == THX_WINDOW_RMS && strstr(w.why, "beat 2 of 3"));
    /* beat 2's QRS (frames 130 +- 3 sigma, rows offset up to 6 frames) inside; beats 1 and 3 outside */
    CHECK(w.t0 >= 100 + 2 * 60.0 && w.t0 <= 100 + 2 * 125.0 && w.t1 >= 100 + 2 * 136.0 && w.t1 <= 100 + 2 * 200.0);
    CHECK(w.rec_t0 == w.t1 && w.rec_t1 > w.t1 && w.rec_t1 < 100 + 2 * 245.0);
    /* global fiducials at fractional frames */
    double q = 110.5, so = 140.25;
    CHECK_OK(ctx, thx_series_add_fiducial(ctx, s, 2, 0, 1, &q));
    CHECK_OK(ctx, thx_series_add_fiducial(ctx, s, 4, 0, 1, &so));
    CHECK_OK(ctx, thx_activation_window_choose(ctx, s, &w));
    CHECK(w.source == THX_WINDOW_FIDUCIALS && fabs(w.t0 - 321) < 1e-9 && fabs(w.t1 - 380.5) < 1e-9);
    CHECK(fabs(w.rec_t0 - 380.5) < 1e-9 && w.rec_t1 == s->time[299]);
    thx_series *none = NULL;
    CHECK_OK(ctx, thx_activation_from_fiducials(ctx, s, 10, &none));
    CHECK(none == NULL);
    thx_series_destroy(&s);
    s = make(4, 50, 0, 1); /* flat */
    CHECK_OK(ctx, thx_activation_window_choose(ctx, s, &w));
    CHECK(w.source == THX_WINDOW_WHOLE && w.t0 == 0 && w.t1 == 49);
    thx_series_destroy(&s);
    s = make(2, 6, 0, 1);
    V(s, 0, 3) = 1;
    CHECK_OK(ctx, thx_activation_window_choose(ctx, s, &w));
    CHECK(w.source == THX_WINDOW_WHOLE && w.t1 == 5);
    thx_series_destroy(&s);

    /* the Utah tank run */
    char mat[2300], tsdf[2300], rec[2300];
    map3d_path(mat, sizeof mat, "data/tank/cool1-atdr-run1.mat");
    map3d_path(tsdf, sizeof tsdf, "data/tank/cool1-atdr-run1.tsdf");
    map3d_path(rec, sizeof rec, "data/socks/10jan01/rsm10jan01-cs-0004.mat");
    CHECK(tl_exists(mat) && tl_exists(tsdf) && tl_exists(rec));
    if (!tl_exists(mat) || !tl_exists(tsdf) || !tl_exists(rec)) return;
    CHECK_OK(ctx, thx_series_read(ctx, mat, THX_SERIES_AUTO, &s));
    if (!s) return;
    CHECK(s->n_rows == 512 && s->n_frames == 608 && s->n_fids == 0);
    CHECK_OK(ctx, thx_activation_window_choose(ctx, s, &w));
    CHECK(w.source == THX_WINDOW_RMS && strstr(w.why, "beat 1 of 2"));
    CHECK(fabs(w.t0 - 155) <= 10 && fabs(w.t1 - 196) <= 10);
    CHECK(w.rec_t0 == w.t1 && w.rec_t1 > 384 && w.rec_t1 < 560);
    /* the sock's leads: channels 193..320 (sock128.channels maps node i to channel 192 + i) */
    thx_series *sock = make(128, 608, 0, 1);
    for (size_t f = 0; f < 608; f++)
        for (size_t r = 0; r < 128; r++) V(sock, r, f) = V(s, 192 + r, f);
    thx_activation_opts ao;
    thx_activation_opts_default(&ao);
    ao.t0 = w.t0;
    ao.t1 = w.t1;
    thx_series *t = times(sock, &ao), *all = times(sock, NULL);
    double lo = INFINITY, hi = -INFINITY, alo = INFINITY, ahi = -INFINITY;
    for (size_t r = 0; t && all && r < 128; r++) {
        if (isfinite(t->v[r])) { lo = fmin(lo, t->v[r]); hi = fmax(hi, t->v[r]); }
        if (isfinite(all->v[r])) { alo = fmin(alo, all->v[r]); ahi = fmax(ahi, all->v[r]); }
    }
    CHECK(hi - lo < 40 && lo >= w.t0 && hi <= w.t1);
    CHECK(ahi - alo > 400); /* the whole series: both beats and the artefacts between */
    printf("tank: window %s; sock activation %.1f-%.1f ms (whole series %.1f-%.1f)\n", w.why, lo, hi, alo, ahi);
    thx_series_destroy(&t);
    thx_series_destroy(&all);
    thx_series_destroy(&sock);
    thx_series_destroy(&s);
    CHECK_OK(ctx, thx_series_read(ctx, tsdf, THX_SERIES_AUTO, &s));
    if (!s) return;
    CHECK_OK(ctx, thx_activation_window_choose(ctx, s, &w));
    CHECK(w.source == THX_WINDOW_FIDUCIALS && w.t0 == 155 && w.t1 == 196 && w.rec_t0 == 196 && w.rec_t1 == 384);
    CHECK(!strcmp(w.why, "fiducials qon-soff") && !strcmp(w.rec_why, "fiducials soff-toff"));
    thx_series_destroy(&s);

    /* the 490-lead sock's own activation and recovery fiducials */
    CHECK_OK(ctx, thx_series_read(ctx, rec, THX_SERIES_AUTO, &s));
    if (!s) return;
    double qrs_on = NAN, qrs_off = NAN, t_off = NAN, *fid = malloc(490 * sizeof *fid);
    CHECK(read_fids(rec, &qrs_on, &qrs_off, &t_off, fid, 490) == 0);
    CHECK_OK(ctx, thx_activation_from_fiducials(ctx, s, 10, &t));
    CHECK(t && t->n_rows == 490 && t->n_frames == 1 && !strcmp(t->unit, "ms"));
    size_t same = 0;
    for (size_t r = 0; t && r < 490; r++) same += fabs(t->v[r] - fid[r]) < 1e-9;
    CHECK(same == 490);
    thx_series_destroy(&t);
    CHECK_OK(ctx, thx_activation_from_fiducials(ctx, s, 13, &t));
    size_t in_t = 0;
    for (size_t r = 0; t && r < 490; r++) in_t += t->v[r] > qrs_off && t->v[r] < t_off;
    CHECK(t && in_t == 490);
    thx_series_destroy(&t);
    CHECK_OK(ctx, thx_activation_window_choose(ctx, s, &w));
    CHECK(w.source == THX_WINDOW_FIDUCIALS && fabs(w.t0 - qrs_on) < 1e-9 && fabs(w.t1 - qrs_off) < 1e-9);
    free(fid);
    thx_series_destroy(&s);
}

int main(void)
{
    if (thx_ctx_create(&ctx) != THX_OK) return 1;
    test_steps();
    test_recovery();
    test_noise();
    test_missing();
    test_window();
    test_bad();
    test_sock();
    test_window_choice();
    int rc = tl_finish();
    thx_ctx_destroy(&ctx);
    return rc;
}
