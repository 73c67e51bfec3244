/* The inverse module on a small ill-posed problem with a known answer, written for thorax: a
 * first-kind Fredholm equation ∫ K(s,t) x(t) dt = b(s) on [0,1] with a Gaussian blurring kernel
 * K(s,t) = exp(-(s-t)²/(2w²)) / (w sqrt(2π)), discretized by the midpoint rule (m = 60 collocation
 * points s, n = 50 quadrature points t), x(t) = two smooth bumps. Every λ rule's λ and the solution
 * error are checked against numpy computing them its own way (explicit normal-equation solves,
 * the influence matrix's trace, finite-difference curvature, root finding, TSVD's truncation from
 * explicit residuals; python below), the
 * error must fall with the noise, the filter factors are checked, and bad input is refused. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/inverse/inverse.h"
#include "thorax/model/series.h"
#include "thorax/model/surface.h"

enum { M = 60, N = 50 };

/* deterministic standard normal numbers (xorshift + Box-Muller) */
static unsigned long long rng_state = 88172645463325252ULL;
static double urand(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return ((double)(rng_state >> 11) + 0.5) / 9007199254740992.0;
}
static double nrand(void) { return sqrt(-2 * log(urand())) * cos(6.283185307179586 * urand()); }

static void problem(thx_ctx *ctx, double noise, int frames, thx_series **A, thx_series **B, double *xt)
{
    const double w = 0.04;
    CHECK_OK(ctx, thx_series_create(ctx, M, N, A));
    CHECK_OK(ctx, thx_series_create(ctx, M, (size_t)frames, B));
    for (int j = 0; j < N; j++) {
        double t = (j + 0.5) / N;
        xt[j] = exp(-pow((t - 0.35) / 0.08, 2)) + 0.6 * exp(-pow((t - 0.7) / 0.12, 2));
        for (int i = 0; i < M; i++) {
            double s = (i + 0.5) / M;
            (*A)->v[(size_t)j * M + i] = exp(-(s - t) * (s - t) / (2 * w * w)) / (w * sqrt(2 * M_PI)) / N;
        }
    }
    double nb = 0;
    for (int i = 0; i < M; i++) {
        double b = 0;
        for (int j = 0; j < N; j++) b += (*A)->v[(size_t)j * M + i] * xt[j];
        for (int f = 0; f < frames; f++) (*B)->v[(size_t)f * M + i] = b;
        nb += b * b;
    }
    /* noise: relative to the exact data's RMS, independent per frame */
    double sigma = noise * sqrt(nb / M);
    for (int f = 0; f < frames; f++)
        for (int i = 0; i < M; i++) (*B)->v[(size_t)f * M + i] += sigma * nrand();
}

static void write_matrix(const char *path, const double *v, size_t rows, size_t cols)
{
    FILE *f = fopen(path, "w");
    if (!f) exit(1);
    for (size_t i = 0; i < rows; i++) {
        for (size_t j = 0; j < cols; j++) fprintf(f, "%.17g ", v[j * rows + i]);
        fputc('\n', f);
    }
    fclose(f);
}

/* numpy's answers, each computed without the SVD filter formulas thorax uses */
static const char *reference_py =
    "import sys, numpy as np\n"
    "from scipy.optimize import minimize_scalar, brentq\n"
    "A = np.loadtxt(sys.argv[1]); b = np.loadtxt(sys.argv[2]); x_true = np.loadtxt(sys.argv[3]); sigma = float(sys.argv[4])\n"
    "m, n = A.shape\n"
    "AtA = A.T @ A; Atb = A.T @ b; I = np.eye(n)\n"
    "def x_of(l): return np.linalg.lstsq(np.vstack([A, l * I]), np.concatenate([b, np.zeros(n)]), rcond=None)[0]\n"
    "def res(l): return np.linalg.norm(A @ x_of(l) - b)\n"
    "def gcv(lg):\n"
    "    l = np.exp(lg); H = A @ np.linalg.solve(AtA + l * l * I, A.T)\n"
    "    return res(l) ** 2 / (m - np.trace(H)) ** 2\n"
    "def logs(lg): l = np.exp(lg); x = x_of(l); return np.log(np.linalg.norm(A @ x - b)), np.log(np.linalg.norm(x))\n"
    "def kappa(lg, h=1e-3):\n"
    "    p = [logs(lg + k * h) for k in (-2, -1, 0, 1, 2)]\n"
    "    xs = np.array([q[0] for q in p]); ys = np.array([q[1] for q in p])\n"
    "    dx = (xs[3] - xs[1]) / (2 * h); dy = (ys[3] - ys[1]) / (2 * h)\n"
    "    ddx = (xs[3] - 2 * xs[2] + xs[1]) / h ** 2; ddy = (ys[3] - 2 * ys[2] + ys[1]) / h ** 2\n"
    "    return (dx * ddy - ddx * dy) / (dx * dx + dy * dy) ** 1.5\n"
    "def creso(lg, h=1e-4):\n"
    "    t = np.exp(2 * lg); e = lambda tt: np.linalg.norm(x_of(np.sqrt(tt))) ** 2\n"
    "    return e(t) + 2 * t * (e(t * (1 + h)) - e(t * (1 - h))) / (2 * t * h)\n"
    "s = np.linalg.svd(A, compute_uv=False)\n"
    "lo, hi = np.log(max(s[-1], s[0] * 16 * np.finfo(float).eps)), np.log(s[0])\n"
    "grid = np.linspace(lo, hi, 400)\n"
    "def refine(fn, sign, pick):\n"
    "    v = np.nan_to_num(np.array([sign * fn(g) for g in grid]), nan=-np.inf); i = pick(v)\n"
    "    r = minimize_scalar(lambda g: -sign * fn(g), bounds=(grid[max(i - 1, 0)], grid[min(i + 1, len(grid) - 1)]), method='bounded', options={'xatol': 1e-9})\n"
    "    return np.exp(r.x)\n"
    "def first_max_from_top(v):\n"
    "    for i in range(len(v) - 2, 0, -1):\n"
    "        if v[i] > v[i + 1] and v[i] >= v[i - 1]: return i\n"
    "    return int(np.argmax(v))\n"
    "out = {}\n"
    "out['lcurve'] = refine(kappa, 1, lambda v: int(np.argmax(v)))\n"
    "out['gcv'] = refine(lambda g: gcv(g), -1, lambda v: int(np.argmax(v)))\n"
    "out['creso'] = refine(creso, 1, first_max_from_top)\n"
    "out['discrepancy'] = np.exp(brentq(lambda g: res(np.exp(g)) - np.sqrt(m) * sigma, lo, hi, xtol=1e-12))\n"
    "for k in ('lcurve', 'creso', 'gcv', 'discrepancy'):\n"
    "    x = x_of(out[k]); print(k, repr(out[k]), repr(np.linalg.norm(x - x_true) / np.linalg.norm(x_true)))\n"
    "x = x_of(1e-3); print('fixed', repr(1e-3), repr(np.linalg.norm(x - x_true) / np.linalg.norm(x_true)))\n"
    "U, s, Vt = np.linalg.svd(A, full_matrices=False); k = int(np.sum(s > 1e-3))\n"
    "xt = Vt[:k].T @ ((U[:, :k].T @ b) / s[:k]); print('tsvd', k, repr(np.linalg.norm(xt - x_true) / np.linalg.norm(x_true)))\n"
    "kmax = int(np.sum(s > s[0] * 16 * np.finfo(float).eps))\n"
    "rk = [np.linalg.norm(A @ (Vt[:q].T @ ((U[:, :q].T @ b) / s[:q])) - b) for q in range(1, kmax + 1)]\n"
    "g = [rk[q - 1] ** 2 / (m - q) ** 2 for q in range(1, kmax + 1)]\n"
    "ok = [q for q in range(1, kmax + 1) if rk[q - 1] <= np.sqrt(m) * sigma]\n"
    "print('tsvd_rules', int(np.argmin(g)) + 1, ok[0] if ok else kmax)\n"
    "et = [np.linalg.norm(Vt[:q].T @ ((U[:, :q].T @ b) / s[:q]) - x_true) / np.linalg.norm(x_true) for q in range(1, kmax + 1)]\n"
    "print('tsvd_best', int(np.argmin(et)) + 1, repr(min(et)))\n";

static int reference(const char *a, const char *b, const char *x, double sigma, double lam[5], double err[5],
                     int *tk, double *terr, int tr[2], int *kbest, double *ebest)
{
    char cmd[4096];
    snprintf(cmd, sizeof cmd, "/usr/bin/python3 %s %s %s %s %.17g", tl_path("ref.py"), a, b, x, sigma);
    FILE *p = popen(cmd, "r");
    if (!p) return -1;
    char name[32];
    int got = 0;
    const char *names[5] = {"lcurve", "creso", "gcv", "discrepancy", "fixed"};
    for (int k = 0; k < 5; k++)
        if (fscanf(p, "%31s %lf %lf", name, &lam[k], &err[k]) == 3 && !strcmp(name, names[k])) got++;
    if (fscanf(p, "%31s %d %lf", name, tk, terr) == 3 && !strcmp(name, "tsvd")) got++;
    if (fscanf(p, "%31s %d %d", name, &tr[0], &tr[1]) == 3 && !strcmp(name, "tsvd_rules")) got++;
    if (fscanf(p, "%31s %d %lf", name, kbest, ebest) == 3 && !strcmp(name, "tsvd_best")) got++;
    return pclose(p) == 0 && got == 8 ? 0 : -1;
}

static double rel_err(const double *x, const double *t, size_t n)
{
    double d = 0, q = 0;
    for (size_t i = 0; i < n; i++) d += (x[i] - t[i]) * (x[i] - t[i]), q += t[i] * t[i];
    return sqrt(d / q);
}

static void test_rules_against_numpy(thx_ctx *ctx)
{
    const double levels[3] = {1e-2, 1e-3, 1e-4};
    double prev_err[4] = {INFINITY, INFINITY, INFINITY, INFINITY};
    tl_write_text(tl_path("ref.py"), reference_py);
    for (int lv = 0; lv < 3; lv++) {
        thx_series *A = NULL, *B = NULL, *X = NULL;
        double xt[N];
        problem(ctx, levels[lv], 1, &A, &B, xt);
        double nb = 0;
        for (int i = 0; i < M; i++) {
            double b = 0;
            for (int j = 0; j < N; j++) b += A->v[(size_t)j * M + i] * xt[j];
            nb += b * b;
        }
        double sigma = levels[lv] * sqrt(nb / M);
        write_matrix(tl_path("A.txt"), A->v, M, N);
        write_matrix(tl_path("b.txt"), B->v, M, 1);
        write_matrix(tl_path("x.txt"), xt, N, 1);
        double lam[5], err[5], terr;
        int tk, tr[2], kbest = 0;
        double ebest = 0;
        int ok = reference(tl_path("A.txt"), tl_path("b.txt"), tl_path("x.txt"), sigma, lam, err, &tk, &terr, tr, &kbest, &ebest);
        CHECK(ok == 0);
        if (ok) return;
        thx_lambda_rule rules[5] = {THX_LAMBDA_LCURVE, THX_LAMBDA_CRESO, THX_LAMBDA_GCV, THX_LAMBDA_DISCREPANCY,
                                    THX_LAMBDA_FIXED};
        for (int k = 0; k < 5; k++) {
            thx_inverse_opts o;
            thx_inverse_opts_default(&o);
            o.rule = rules[k];
            o.lambda = 1e-3;
            o.noise = sigma;
            thx_inverse_report r;
            CHECK_OK(ctx, thx_inverse_solve(ctx, A, B, NULL, &o, &X, &r));
            if (!X) continue;
            double e = rel_err(X->v, xt, N);
            if (fabs(r.lambda[0] / lam[k] - 1) > 2e-3 || fabs(e - err[k]) > 1e-3 * err[k] + 1e-9)
                fprintf(stderr, "noise %g, %s: thorax λ %.9g error %.9g; numpy λ %.9g error %.9g\n", levels[lv],
                        thx_lambda_rule_name(rules[k]), r.lambda[0], e, lam[k], err[k]);
            CHECK(fabs(r.lambda[0] / lam[k] - 1) <= 2e-3);
            CHECK(fabs(e - err[k]) <= 2e-3 * err[k] + 1e-9);
            /* the reported residual is ||A x - b|| of the solution returned */
            double r2 = 0;
            for (int i = 0; i < M; i++) {
                double v = -B->v[i];
                for (int j = 0; j < N; j++) v += A->v[(size_t)j * M + i] * X->v[j];
                r2 += v * v;
            }
            CHECK_NEAR(r.residual[0], sqrt(r2), 1e-9 * sqrt(r2) + 1e-14);
            if (k < 4 && (k == 2 || k == 3)) { /* GCV and discrepancy: the error falls with the noise */
                CHECK(e < prev_err[k]);
                prev_err[k] = e;
            }
            thx_series_destroy(&X);
            thx_inverse_report_free(&r);
        }
        /* TSVD with λ = 1e-3: the components above it, as numpy truncates */
        thx_inverse_opts o;
        thx_inverse_opts_default(&o);
        o.method = THX_INVERSE_TSVD;
        o.rule = THX_LAMBDA_FIXED;
        o.lambda = 1e-3;
        thx_inverse_report r;
        CHECK_OK(ctx, thx_inverse_solve(ctx, A, B, NULL, &o, &X, &r));
        if (X) {
            CHECK(r.k[0] == tk);
            CHECK_NEAR(rel_err(X->v, xt, N), terr, 1e-6 * terr);
        }
        thx_series_destroy(&X);
        thx_inverse_report_free(&r);
        /* TSVD's GCV and discrepancy pick the truncation numpy picks from explicit residuals */
        for (int q = 0; q < 2; q++) {
            o.rule = q ? THX_LAMBDA_DISCREPANCY : THX_LAMBDA_GCV;
            o.noise = sigma;
            CHECK_OK(ctx, thx_inverse_solve(ctx, A, B, NULL, &o, &X, &r));
            if (X && r.k[0] != tr[q])
                fprintf(stderr, "noise %g, tsvd %s: thorax keeps %d, numpy %d\n", levels[lv], q ? "discrepancy" : "gcv",
                        r.k[0], tr[q]);
            CHECK(X && r.k[0] == tr[q]);
            thx_series_destroy(&X);
            thx_inverse_report_free(&r);
        }
        /* TSVD's L-curve corner: the components above the Tikhonov L-curve's λ, so an error like
         * the Tikhonov L-curve's (numpy's, above); the best truncation (numpy tries every k against
         * the true solution) is printed beside it: the L-curve rule undersmooths this problem */
        o.rule = THX_LAMBDA_LCURVE;
        CHECK_OK(ctx, thx_inverse_solve(ctx, A, B, NULL, &o, &X, &r));
        if (X) {
            double e = rel_err(X->v, xt, N);
            printf("noise %g: tsvd L-curve keeps %d components, error %.4f; the best truncation %d, error %.4f (Tikhonov L-curve %.4f, GCV %.4f)\n",
                   levels[lv], r.k[0], e, kbest, ebest, err[0], err[2]);
            CHECK(e <= 1.2 * err[0]);
            CHECK(e >= ebest);
        }
        thx_series_destroy(&X);
        thx_inverse_report_free(&r);
        thx_series_destroy(&A);
        thx_series_destroy(&B);
    }
}

static void test_filter_factors(void)
{
    double s[4] = {3, 1, 0.1, 1e-3}, f[4];
    thx_inverse_filter(s, 4, 0.1, 0, f);
    CHECK_NEAR(f[0], 9 / 9.01, 1e-15);
    CHECK_NEAR(f[2], 0.5, 1e-15);
    CHECK_NEAR(f[3], 1e-6 / (1e-6 + 1e-2), 1e-15);
    thx_inverse_filter(s, 4, 0.1, 1, f);
    CHECK(f[0] == 1 && f[1] == 1 && f[2] == 0 && f[3] == 0);
    thx_inverse_filter(s, 4, 0.0, 0, f);
    CHECK(f[0] == 1 && f[3] == 1);
}

/* an octahedron (closed, 6 nodes): the gradient operator is exact for linear potentials */
static thx_surface *octahedron(thx_ctx *ctx)
{
    thx_surface *h = NULL;
    static const double p[18] = {1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1};
    static const int32_t t[24] = {0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5};
    if (thx_surface_create(ctx, "heart", THX_ROLE_HEART, &h) != THX_OK) return NULL;
    h->xyz = malloc(sizeof p);
    h->tri = malloc(sizeof t);
    memcpy(h->xyz, p, sizeof p);
    memcpy(h->tri, t, sizeof t);
    h->n_nodes = 6;
    h->n_tris = 8;
    return h;
}

static void test_operators(thx_ctx *ctx)
{
    thx_surface *h = octahedron(ctx);
    CHECK(h != NULL);
    if (!h) return;
    double *M1 = NULL, *M2 = NULL;
    CHECK_OK(ctx, thx_inverse_operator(ctx, h, 1, &M1));
    CHECK_OK(ctx, thx_inverse_operator(ctx, h, 2, &M2));
    if (!M1 || !M2) return;
    /* constants are in the null space of both */
    for (int i = 0; i < 6; i++) {
        double a = 0, b = 0;
        for (int j = 0; j < 6; j++) a += M1[j * 6 + i], b += M2[j * 6 + i];
        CHECK_NEAR(a, 0, 1e-12);
        CHECK_NEAR(b, 0, 1e-12);
    }
    /* x = z: x^T M1 x = Σ area |tangential part of e_z|², by hand: 8 faces of area sqrt(3)/2, normal
     * (±1,±1,±1)/sqrt(3), |P e_z|² = 1 - 1/3 = 2/3: total 8 (sqrt(3)/2)(2/3) = 8/sqrt(3) */
    double x[6] = {0, 0, 0, 0, 1, -1}, q = 0;
    for (int i = 0; i < 6; i++)
        for (int j = 0; j < 6; j++) q += x[i] * M1[j * 6 + i] * x[j];
    CHECK_NEAR(q, 8 / sqrt(3.0), 1e-12);
    free(M1);
    free(M2);

    /* Tikhonov order 1 through the standard form = the normal equations solved directly */
    thx_series *A = NULL, *B = NULL, *X = NULL;
    CHECK_OK(ctx, thx_series_create(ctx, 9, 6, &A));
    CHECK_OK(ctx, thx_series_create(ctx, 9, 2, &B));
    for (size_t i = 0; i < 9 * 6; i++) A->v[i] = 1.0 / (1.0 + (double)((i * 7) % 11)) + 0.1 * (double)(i % 3);
    for (size_t i = 0; i < 18; i++) B->v[i] = sin(0.7 * (double)i);
    for (int order = 1; order <= 2; order++) {
        thx_inverse_opts o;
        thx_inverse_opts_default(&o);
        o.method = order == 1 ? THX_INVERSE_TIKHONOV1 : THX_INVERSE_TIKHONOV2;
        o.rule = THX_LAMBDA_FIXED;
        o.lambda = 0.3;
        thx_inverse_report r;
        double *Mo = NULL;
        CHECK_OK(ctx, thx_inverse_operator(ctx, h, order, &Mo));
        CHECK_OK(ctx, thx_inverse_solve(ctx, A, B, h, &o, &X, &r));
        if (!X || !Mo) return;
        for (int f = 0; f < 2; f++) {
            /* (A^T A + λ² M) x = A^T b by Gaussian elimination */
            double S[6][7];
            for (int i = 0; i < 6; i++) {
                for (int j = 0; j < 6; j++) {
                    double v = 0;
                    for (int k = 0; k < 9; k++) v += A->v[i * 9 + k] * A->v[j * 9 + k];
                    S[i][j] = v + 0.09 * Mo[j * 6 + i];
                }
                double v = 0;
                for (int k = 0; k < 9; k++) v += A->v[i * 9 + k] * B->v[f * 9 + k];
                S[i][6] = v;
            }
            for (int c = 0; c < 6; c++)
                for (int i = c + 1; i < 6; i++) {
                    double l = S[i][c] / S[c][c];
                    for (int j = c; j < 7; j++) S[i][j] -= l * S[c][j];
                }
            double xs[6];
            for (int i = 5; i >= 0; i--) {
                double v = S[i][6];
                for (int j = i + 1; j < 6; j++) v -= S[i][j] * xs[j];
                xs[i] = v / S[i][i];
            }
            for (int i = 0; i < 6; i++) CHECK_NEAR(X->v[f * 6 + i], xs[i], 1e-9 * (1 + fabs(xs[i])));
            /* the reported seminorm is sqrt(x^T M x) */
            double q2 = 0;
            for (int i = 0; i < 6; i++)
                for (int j = 0; j < 6; j++) q2 += X->v[f * 6 + i] * Mo[j * 6 + i] * X->v[f * 6 + j];
            CHECK_NEAR(r.seminorm[f], sqrt(q2), 1e-9 * (1 + sqrt(q2)));
        }
        free(Mo);
        thx_series_destroy(&X);
        thx_inverse_report_free(&r);
    }
    /* total variation runs and does not increase the TV against order 1 at the same λ */
    {
        thx_inverse_opts o;
        thx_inverse_opts_default(&o);
        o.method = THX_INVERSE_TV;
        o.rule = THX_LAMBDA_FIXED;
        o.lambda = 0.3;
        thx_inverse_report r;
        CHECK_OK(ctx, thx_inverse_solve(ctx, A, B, h, &o, &X, &r));
        CHECK(X != NULL && isfinite(r.seminorm[0]) && isfinite(r.residual[0]));
        thx_series_destroy(&X);
        thx_inverse_report_free(&r);
    }
    thx_series_destroy(&A);
    thx_series_destroy(&B);
    thx_surface_destroy(&h);
}

static void test_bad_input(thx_ctx *ctx)
{
    thx_series *A = NULL, *B = NULL, *B2 = NULL, *X = NULL;
    double xt[N];
    problem(ctx, 1e-3, 3, &A, &B, xt);
    thx_inverse_opts o;
    thx_inverse_opts_default(&o);
    o.matrix_name = "T.mat";
    o.data_name = "body.raw";
    thx_inverse_report r;
    CHECK_OK(ctx, thx_series_create(ctx, M - 1, 3, &B2));
    CHECK(thx_inverse_solve(ctx, A, B2, NULL, &o, &X, &r) == THX_EINPUT);
    CHECK(tl_msg_has(ctx, "T.mat has 60 rows") && tl_msg_has(ctx, "body.raw has 59 rows"));
    B->v[2 * M + 7] = NAN;
    CHECK(thx_inverse_solve(ctx, A, B, NULL, &o, &X, &r) == THX_EINPUT);
    CHECK(tl_msg_has(ctx, "body.raw: row 8, frame 3: NaN"));
    B->v[2 * M + 7] = 0;
    A->v[4 * M + 10] = INFINITY;
    CHECK(thx_inverse_solve(ctx, A, B, NULL, &o, &X, &r) == THX_EINPUT);
    CHECK(tl_msg_has(ctx, "T.mat: row 11, column 5 (heart node): Inf"));
    A->v[4 * M + 10] = 0;
    o.method = THX_INVERSE_TIKHONOV1;
    CHECK(thx_inverse_solve(ctx, A, B, NULL, &o, &X, &r) == THX_EINPUT);
    CHECK(tl_msg_has(ctx, "needs the heart surface"));
    o.method = THX_INVERSE_TSVD;
    o.rule = THX_LAMBDA_CRESO;
    CHECK(thx_inverse_solve(ctx, A, B, NULL, &o, &X, &r) == THX_EINPUT);
    o.method = THX_INVERSE_TIKHONOV0;
    o.rule = THX_LAMBDA_DISCREPANCY;
    CHECK(thx_inverse_solve(ctx, A, B, NULL, &o, &X, &r) == THX_EINPUT);
    CHECK(tl_msg_has(ctx, "noise level"));
    CHECK(X == NULL);
    thx_series_destroy(&A);
    thx_series_destroy(&B);
    thx_series_destroy(&B2);
}

/* one λ for the series = the rule on the frames stacked into one vector */
static void test_series_lambda(thx_ctx *ctx)
{
    thx_series *A = NULL, *B = NULL, *X = NULL;
    double xt[N];
    problem(ctx, 1e-3, 5, &A, &B, xt);
    thx_inverse_opts o;
    thx_inverse_opts_default(&o);
    o.rule = THX_LAMBDA_GCV;
    o.per_series = 1;
    thx_inverse_report r;
    CHECK_OK(ctx, thx_inverse_solve(ctx, A, B, NULL, &o, &X, &r));
    if (!X) return;
    for (int f = 1; f < 5; f++) CHECK(r.lambda[f] == r.lambda[0]);
    CHECK(r.n_curve > 10 && r.corner_lambda > 0);
    /* GCV of the stacked problem at the chosen λ is not beaten on a fine grid around it */
    double best = INFINITY, at = 0;
    for (int q = -200; q <= 200; q++) {
        double l = r.lambda[0] * exp(q * 0.005), rho2 = 0, tr = 0;
        thx_inverse_opts fo = o;
        fo.rule = THX_LAMBDA_FIXED;
        fo.lambda = l;
        fo.per_series = 0;
        thx_series *Y = NULL;
        thx_inverse_report rr;
        if (thx_inverse_solve(ctx, A, B, NULL, &fo, &Y, &rr) != THX_OK) break;
        for (int f = 0; f < 5; f++) rho2 += rr.residual[f] * rr.residual[f];
        for (size_t i = 0; i < rr.rank; i++) tr += rr.sv[i] * rr.sv[i] / (rr.sv[i] * rr.sv[i] + l * l);
        double g = rho2 / pow(5.0 * M - 5 * tr, 2);
        if (g < best) best = g, at = l;
        thx_series_destroy(&Y);
        thx_inverse_report_free(&rr);
    }
    CHECK(fabs(log(at / r.lambda[0])) <= 0.006);
    /* the SVG picture is written and names the corner */
    CHECK_OK(ctx, thx_inverse_write_svg(ctx, &r, "test <L-curve>", tl_path("l.svg")));
    char *svg = tl_slurp(ctx, tl_path("l.svg"), NULL);
    CHECK(svg && strstr(svg, "id=\"corner\"") && strstr(svg, "test &lt;L-curve>"));
    free(svg);
    thx_series_destroy(&X);
    thx_inverse_report_free(&r);
    thx_series_destroy(&A);
    thx_series_destroy(&B);
}

/* GCV on the spectral data of a problem with as many degrees of freedom as nonzero singular values
 * (m < n: every row fitted as λ → 0; dof = m - p0 with the operator's null space taken off): the
 * trace(I - H) = dof - Σ f goes to 0 with the residual, and the minimum is inside the range, no
 * flag; thorax's λ is at least as good as any of 2000 λ on a fine grid, G computed here in long
 * double from the definition. With one degree of freedom too many (the old m - Σ f where the
 * null space must be taken off) G → 0 at the bottom: the λ is there and flagged range_low.
 * The discrepancy's target out of reach either way: flagged at that end. */
static void test_pick_dof_and_flags(void)
{
    enum { K = 40 };
    double s[K], b2[K];
    for (int i = 0; i < K; i++) {
        s[i] = pow(10.0, -0.25 * i);
        double x = 1.0 / (1 + i), e = 1e-4 * nrand();
        b2[i] = (s[i] * x + e) * (s[i] * x + e);
    }
    int fl = -1;
    double lam = thx_inverse_pick(s, b2, K, 0.0, (double)K, THX_LAMBDA_GCV, 0, 0, 0, 100, NULL, &fl);
    CHECK(fl == 0);
    CHECK(lam > s[K - 1] * 1.5 && lam < s[0] / 1.5);
    long double gbest = INFINITY, gl = 0;
    for (int q = -1; q < 2000; q++) {
        long double l = q < 0 ? lam : powl(10.0L, -10.5L + 11.0L * q / 1999), r2 = 0, tr = 0;
        for (int i = 0; i < K; i++) {
            long double g = l * l / ((long double)s[i] * s[i] + l * l);
            r2 += g * g * b2[i];
            tr += g;
        }
        long double G = r2 / (tr * tr);
        if (q < 0) gl = G;
        else if (G < gbest) gbest = G;
    }
    if (!(gl <= gbest * (1 + 1e-6L))) fprintf(stderr, "GCV at thorax's λ %g: %Lg, grid minimum %Lg\n", lam, gl, gbest);
    CHECK(gl <= gbest * (1 + 1e-6L));
    lam = thx_inverse_pick(s, b2, K, 0.0, (double)K + 1, THX_LAMBDA_GCV, 0, 0, 0, 100, NULL, &fl);
    CHECK(fl == THX_LAMBDA_AT_LOW && fabs(lam / s[K - 1] - 1) < 1e-9);
    double n2 = 0;
    for (int i = 0; i < K; i++) n2 += b2[i];
    lam = thx_inverse_pick(s, b2, K, 0.0, K, THX_LAMBDA_DISCREPANCY, 0, 10 * sqrt(n2), 0, 100, NULL, &fl);
    CHECK(fl == THX_LAMBDA_AT_HIGH && fabs(lam / s[0] - 1) < 1e-9);
    lam = thx_inverse_pick(s, b2, K, 0.0, K, THX_LAMBDA_DISCREPANCY, 0, 0.0, 0, 100, NULL, &fl);
    CHECK(fl == THX_LAMBDA_AT_LOW && fabs(lam / s[K - 1] - 1) < 1e-9);
    /* TSVD: GCV's denominator dof - k: with dof = K the last k (K) is never taken */
    int kept = 0;
    thx_inverse_pick(s, b2, K, 0.0, (double)K, THX_LAMBDA_GCV, 0, 0, 1, 100, &kept, &fl);
    CHECK(kept > 1 && kept < K && fl == 0);
}

int main(void)
{
    thx_ctx *ctx = NULL;
    if (thx_ctx_create(&ctx) != THX_OK || tl_scratch_make("inverse")) return 1;
    test_filter_factors();
    test_rules_against_numpy(ctx);
    test_operators(ctx);
    test_bad_input(ctx);
    test_series_lambda(ctx);
    test_pick_dof_and_flags(); /* last: it draws from the noise generator the others use */
    thx_ctx_destroy(&ctx);
    return tl_scratch_finish("inverse");
}
