/* The L-curve picture (thorax/picture/lcurve_plot.h) of real inverse solutions: a first-kind
 * Fredholm problem (Gaussian blur, m = 60, n = 50, as in test_inverse.c) with frames of varying
 * amplitude, solved by thx_inverse_solve and drawn by thx_lcurve_plot_write. Checked on the PNG
 * read back:
 *  - its size is the one asked for;
 *  - the plot box found in the pixels (the dark frame lines, their coverage-weighted centres) is
 *    the mapping's box, and the decades at its ends are those this test computes from the report's
 *    points itself (floor and ceil of log10 of the least and greatest);
 *  - the red disc's centroid is the chosen λ's point (||A x - b||, ||L x||) put through the axis
 *    mapping (computed here from the box and the decades), to half a pixel;
 * and on the report: one λ for the series marks the summed solution norms (the L-curve rule: at
 * the corner); a λ per frame marks the frame of largest ||b|| (found here from the data) at its
 * own λ, residual and norm, lying on its own curve between the two grid λ around it, with at most
 * THX_INVERSE_FRAME_CURVES + 1 frame curves including it; TSVD per frame likewise. Refusals: a
 * path that is not .png, a report with no curve. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/inverse/inverse.h"
#include "thorax/picture/lcurve_plot.h"
#include "thorax/render/image.h"

enum { M = 60, N = 50, F = 70 };

static unsigned long long rng_state = 0x9E3779B97F4A7C15ULL;
static double urand(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return ((double)(rng_state >> 11) + 0.5) / 9007199254740992.0;
}
static double nrand(void) { return sqrt(-2 * log(urand())) * cos(6.283185307179586 * urand()); }

/* blur problem; frame f has amplitude 0.2 + sin(pi f / (F - 1))^2 shifted so the peak is frame 41 */
static void problem(thx_ctx *ctx, thx_series **A, thx_series **B)
{
    const double w = 0.04;
    double xt[N];
    CHECK_OK(ctx, thx_series_create(ctx, M, N, A));
    CHECK_OK(ctx, thx_series_create(ctx, M, F, B));
    for (int j = 0; j < N; j++) {
        double t = (j + 0.5) / N;
        xt[j] = exp(-pow((t - 0.35) / 0.08, 2)) + 0.6 * exp(-pow((t - 0.7) / 0.12, 2));
        for (int i = 0; i < M; i++) {
            double s = (i + 0.5) / M;
            (*A)->v[(size_t)j * M + i] = exp(-(s - t) * (s - t) / (2 * w * w)) / (w * sqrt(2 * M_PI)) / N;
        }
    }
    for (int f = 0; f < F; f++) {
        double amp = 0.2 + exp(-pow((f - 40) / 12.0, 2));
        for (int i = 0; i < M; i++) {
            double b = 0;
            for (int j = 0; j < N; j++) b += (*A)->v[(size_t)j * M + i] * xt[j];
            (*B)->v[(size_t)f * M + i] = amp * b + 0.01 * nrand();
        }
    }
}

static double dark(const thx_raster *img, int i, int j)
{
    const unsigned char *p = img->rgba + 4 * ((size_t)j * img->w + i);
    return 255.0 - (p[0] + p[1] + p[2]) / 3.0;
}

/* The centre of the frame line near x = guess (a vertical line: columns guess-3 .. guess+3,
 * darkness summed over rows y0..y1, weighted by each column's centre i + 0.5); likewise rows. */
static double edge(const thx_raster *img, int vertical, double guess, int a0, int a1)
{
    double sw = 0, sx = 0;
    for (int k = (int)guess - 3; k <= (int)guess + 3; k++) {
        double d = 0;
        for (int a = a0; a <= a1; a++) {
            double v = vertical ? dark(img, k, a) : dark(img, a, k);
            d += v > 100 ? v : 0; /* the black frame, not the light grid */
        }
        if (d > 0.5 * 100 * (a1 - a0 + 1) * 0.3) {
            sw += d;
            sx += d * (k + 0.5);
        }
    }
    return sw > 0 ? sx / sw : NAN;
}

/* the centroid of the pixels of exactly the mark's red */
static int red_centroid(const thx_raster *img, double *x, double *y, int x0, int x1)
{
    double n = 0, sx = 0, sy = 0;
    for (int j = 0; j < img->h; j++)
        for (int i = x0; i < x1; i++) {
            const unsigned char *p = img->rgba + 4 * ((size_t)j * img->w + i);
            if (p[0] == 0xd6 && p[1] == 0x27 && p[2] == 0x28) n++, sx += i + 0.5, sy += j + 0.5;
        }
    if (n < 20) return -1;
    *x = sx / n;
    *y = sy / n;
    return 0;
}

static void check_picture(thx_ctx *ctx, const thx_inverse_report *r, const char *name, const char *rule, int w, int h)
{
    thx_lcurve_plot_opts o;
    thx_lcurve_plot_opts_default(&o);
    o.width = w;
    o.height = h;
    o.title = name;
    o.rule = rule;
    const char *path = tl_path(name);
    CHECK_OK(ctx, thx_lcurve_plot_write(ctx, r, &o, path));
    thx_raster *img = NULL;
    CHECK_OK(ctx, thx_raster_read_png(ctx, path, &img));
    if (!img) return;
    CHECK(img->w == w && img->h == h);
    thx_lcurve_axes ax;
    CHECK_OK(ctx, thx_lcurve_plot_axes(ctx, r, &o, &ax));
    /* the decades, from the report's points by this test */
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    const double *res = r->curve_residual, *sem = r->curve_seminorm;
    size_t nc = r->n_curve, ncur = 1;
    if (r->mark_frame >= 0) {
        res = r->frame_curve_residual;
        sem = r->frame_curve_seminorm;
        ncur = r->n_frame_curves;
    }
    for (size_t i = 0; i < nc * ncur; i++)
        if (res[i] > 0 && sem[i] > 0) {
            lo[0] = fmin(lo[0], log10(res[i])), hi[0] = fmax(hi[0], log10(res[i]));
            lo[1] = fmin(lo[1], log10(sem[i])), hi[1] = fmax(hi[1], log10(sem[i]));
        }
    double pts[2][2] = {{r->mark_residual, r->mark_seminorm}, {r->mark_corner_residual, r->mark_corner_seminorm}};
    for (int k = 0; k < 2; k++) {
        lo[0] = fmin(lo[0], log10(pts[k][0])), hi[0] = fmax(hi[0], log10(pts[k][0]));
        lo[1] = fmin(lo[1], log10(pts[k][1])), hi[1] = fmax(hi[1], log10(pts[k][1]));
    }
    CHECK(ax.lx0 == floor(lo[0]) && ax.lx1 == ceil(hi[0]) && ax.ly0 == floor(lo[1]) && ax.ly1 == ceil(hi[1]));
    /* the box, from the pixels */
    int ym = (int)((ax.top + ax.bottom) / 2), xm = (int)((ax.left + ax.right) / 2);
    CHECK_NEAR(edge(img, 1, ax.left, ym - 60, ym + 60), ax.left, 0.3);
    CHECK_NEAR(edge(img, 1, ax.right, ym - 60, ym + 60), ax.right, 0.3);
    CHECK_NEAR(edge(img, 0, ax.top, xm - 60, xm + 60), ax.top, 0.3);
    CHECK_NEAR(edge(img, 0, ax.bottom, xm + 100, xm + 200), ax.bottom, 0.3); /* right of the legend */
    /* the mark: its point through the mapping */
    double ex = ax.left + (log10(r->mark_residual) - floor(lo[0])) / (ceil(hi[0]) - floor(lo[0])) * (ax.right - ax.left);
    double ey = ax.bottom - (log10(r->mark_seminorm) - floor(lo[1])) / (ceil(hi[1]) - floor(lo[1])) * (ax.bottom - ax.top);
    double cx = NAN, cy = NAN;
    /* the legend's red disc sits at the box's bottom left: look only where the mark can be */
    int x0 = ex > ax.left + 60 ? (int)ax.left + 40 : (int)ax.left + 1;
    CHECK(red_centroid(img, &cx, &cy, x0, (int)ax.right) == 0);
    CHECK_NEAR(cx, ex, 0.5);
    CHECK_NEAR(cy, ey, 0.5);
    printf("%s: %dx%d, decades 1e%g..1e%g x 1e%g..1e%g, mark λ %.4g at (%.2f, %.2f) px, expected (%.2f, %.2f)\n", name,
           img->w, img->h, ax.lx0, ax.lx1, ax.ly0, ax.ly1, r->mark_lambda, cx, cy, ex, ey);
    thx_raster_destroy(&img);
}

int main(void)
{
    if (tl_scratch_make("lcurve_plot")) return 1;
    thx_ctx *ctx = NULL;
    thx_ctx_create(&ctx);
    thx_series *A = NULL, *B = NULL, *X = NULL;
    problem(ctx, &A, &B);
    thx_inverse_opts o;
    thx_inverse_report r;

    /* one λ for the series, L-curve rule: the mark is the corner and the summed norms */
    thx_inverse_opts_default(&o);
    o.per_series = 1;
    CHECK_OK(ctx, thx_inverse_solve(ctx, A, B, NULL, &o, &X, &r));
    CHECK(r.mark_frame == -1 && r.n_frame_curves == 0);
    CHECK(r.mark_lambda == r.chosen_lambda);
    CHECK_NEAR(r.mark_corner_lambda, r.mark_lambda, 1e-12 * r.mark_lambda);
    {
        double r2 = 0, e2 = 0;
        for (int f = 0; f < F; f++) r2 += r.residual[f] * r.residual[f], e2 += r.seminorm[f] * r.seminorm[f];
        CHECK_NEAR(r.mark_residual, sqrt(r2), 1e-12 * sqrt(r2));
        CHECK_NEAR(r.mark_seminorm, sqrt(e2), 1e-12 * sqrt(e2));
    }
    check_picture(ctx, &r, "series.png", "lcurve", 800, 600);
    thx_inverse_report_free(&r);
    thx_series_destroy(&X);

    /* a λ per frame (GCV, so the mark is not the corner), and TSVD per frame */
    for (int tsvd = 0; tsvd < 2; tsvd++) {
        thx_inverse_opts_default(&o);
        o.rule = THX_LAMBDA_GCV;
        o.method = tsvd ? THX_INVERSE_TSVD : THX_INVERSE_TIKHONOV0;
        CHECK_OK(ctx, thx_inverse_solve(ctx, A, B, NULL, &o, &X, &r));
        size_t rep = 0;
        double best = -1;
        for (size_t f = 0; f < F; f++) {
            double n2 = 0;
            for (size_t i = 0; i < M; i++) n2 += B->v[f * M + i] * B->v[f * M + i];
            if (n2 > best) best = n2, rep = f;
        }
        CHECK(r.mark_frame == (long)rep);
        CHECK(r.mark_lambda == r.lambda[rep] && r.mark_residual == r.residual[rep] && r.mark_seminorm == r.seminorm[rep]);
        CHECK(r.n_frame_curves >= THX_INVERSE_FRAME_CURVES && r.n_frame_curves <= THX_INVERSE_FRAME_CURVES + 1);
        size_t j = r.n_frame_curves;
        for (size_t k = 0; k < r.n_frame_curves; k++) {
            if (r.frame_curve_frame[k] == rep) j = k;
            if (k) CHECK(r.frame_curve_frame[k] > r.frame_curve_frame[k - 1]);
        }
        CHECK(j < r.n_frame_curves && r.frame_curve_frame[0] == 0 && r.frame_curve_frame[r.n_frame_curves - 1] == F - 1);
        /* the mark lies on its frame's curve: between the grid points around its λ (residual grows and
           norm falls with λ), or at one (TSVD: λ is a singular value, a point of the curve) */
        if (j < r.n_frame_curves) {
            const double *res = r.frame_curve_residual + j * r.n_curve, *sem = r.frame_curve_seminorm + j * r.n_curve;
            int on = 0;
            for (size_t q = 0; q < r.n_curve; q++) {
                if (tsvd && fabs(r.curve_lambda[q] - r.mark_lambda) <= 1e-12 * r.mark_lambda)
                    on = fabs(res[q] - r.mark_residual) <= 1e-9 * res[q] && fabs(sem[q] - r.mark_seminorm) <= 1e-9 * sem[q];
                if (!tsvd && q + 1 < r.n_curve) {
                    double l0 = fmin(r.curve_lambda[q], r.curve_lambda[q + 1]), l1 = fmax(r.curve_lambda[q], r.curve_lambda[q + 1]);
                    if (l0 <= r.mark_lambda && r.mark_lambda <= l1)
                        on = fmin(res[q], res[q + 1]) <= r.mark_residual * (1 + 1e-12) &&
                             r.mark_residual <= fmax(res[q], res[q + 1]) * (1 + 1e-12) &&
                             fmin(sem[q], sem[q + 1]) <= r.mark_seminorm * (1 + 1e-12) &&
                             r.mark_seminorm <= fmax(sem[q], sem[q + 1]) * (1 + 1e-12);
                }
            }
            CHECK(on);
        }
        check_picture(ctx, &r, tsvd ? "tsvd_frames.png" : "frames.png", "gcv", tsvd ? 1000 : 800, tsvd ? 700 : 600);
        thx_inverse_report_free(&r);
        thx_series_destroy(&X);
    }

    /* refusals */
    thx_inverse_opts_default(&o);
    CHECK_OK(ctx, thx_inverse_solve(ctx, A, B, NULL, &o, &X, &r));
    CHECK(thx_lcurve_plot_write(ctx, &r, NULL, tl_path("x.svg")) == THX_EINPUT && tl_msg_has(ctx, ".png"));
    CHECK(!tl_exists(tl_path("x.svg")));
    thx_inverse_report empty;
    memset(&empty, 0, sizeof empty);
    CHECK(thx_lcurve_plot_write(ctx, &empty, NULL, tl_path("e.png")) == THX_EINPUT && tl_msg_has(ctx, "no curve"));
    CHECK(!tl_exists(tl_path("e.png")));
    thx_inverse_report_free(&r);
    thx_series_destroy(&X);
    thx_series_destroy(&A);
    thx_series_destroy(&B);
    thx_ctx_destroy(&ctx);
    return tl_scratch_finish("lcurve_plot");
}
