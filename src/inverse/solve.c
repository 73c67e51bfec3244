/* thx_inverse_solve: standard form, one SVD, λ per frame or per series, the solutions
 * (thorax/inverse/inverse.h; docs/decisions.md "The inverse problem"). */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "inverse/inverse_impl.h"

const char *thx_inverse_method_name(thx_inverse_method m)
{
    static const char *n[] = {"tikhonov0", "tikhonov1", "tikhonov2", "tsvd", "greensite", "tv"};
    return (unsigned)m < 6 ? n[m] : "?";
}

const char *thx_lambda_rule_name(thx_lambda_rule r)
{
    static const char *n[] = {"lcurve", "creso", "gcv", "discrepancy", "fixed"};
    return (unsigned)r < 5 ? n[r] : "?";
}

void thx_inverse_opts_default(thx_inverse_opts *o)
{
    memset(o, 0, sizeof *o);
    o->method = THX_INVERSE_TIKHONOV0;
    o->rule = THX_LAMBDA_LCURVE;
    o->tv_iterations = 10;
    o->n_grid = 100;
    o->matrix_name = "transfer matrix";
    o->data_name = "data";
}

void thx_inverse_report_free(thx_inverse_report *r)
{
    if (!r) return;
    free(r->lambda);
    free(r->k);
    free(r->residual);
    free(r->seminorm);
    free(r->component_lambda);
    free(r->curve_lambda);
    free(r->curve_residual);
    free(r->curve_seminorm);
    free(r->sv);
    free(r->frame_curve_frame);
    free(r->frame_curve_residual);
    free(r->frame_curve_seminorm);
    free(r->flags);
    memset(r, 0, sizeof *r);
}

void thx_inv_gemm(char ta, char tb, size_t m, size_t n, size_t k, const double *a, size_t lda, const double *b,
                  size_t ldb, double beta, double *c, size_t ldc)
{
    int M = (int)m, N = (int)n, K = (int)k, la = (int)lda, lb = (int)ldb, lc = (int)ldc;
    double one = 1.0;
    if (!m || !n) return;
    if (!k) {
        for (size_t j = 0; j < n; j++)
            for (size_t i = 0; i < m; i++) c[j * ldc + i] *= beta;
        return;
    }
    dgemm_(&ta, &tb, &M, &N, &K, &one, a, &la, b, &lb, &beta, c, &lc);
}

static double wtime(void) { return thx_wtime(); }

/* The thin SVD of a (m x n, destroyed): s (min), U (m x min), VT (min x n). */
static thx_status svd(thx_ctx *ctx, double *a, size_t m, size_t n, double *s, double *U, double *VT)
{
    int M = (int)m, N = (int)n, K = (int)(m < n ? m : n), lwork = -1, info = 0;
    double q;
    int *iw = thx_malloc(ctx, 8 * (size_t)K * sizeof *iw);
    if (!iw) return THX_ENOMEM;
    dgesdd_("S", &M, &N, a, &M, s, U, &M, VT, &K, &q, &lwork, iw, &info);
    lwork = (int)q + 1;
    double *w = thx_malloc(ctx, (size_t)lwork * sizeof *w);
    if (!w) {
        free(iw);
        return THX_ENOMEM;
    }
    dgesdd_("S", &M, &N, a, &M, s, U, &M, VT, &K, w, &lwork, iw, &info);
    free(w);
    free(iw);
    if (info) return thx_error(ctx, THX_ESOLVER, "LAPACK dgesdd (SVD of a %zu x %zu matrix) failed: info %d", m, n, info);
    return THX_OK;
}

/* Eldén's standard form for M = L^T L (n x n, destroyed): P = L_A^+ (n x n) and, when L has a null
 * space W (constants), Q = W (AW)^+ (n x m) so that x = P y + Q b. Returns the null space's size. */
static thx_status standard_form(thx_ctx *ctx, const double *A, size_t m, size_t n, double *M, double **P, double **Q,
                                size_t *null_dim, const char *mname)
{
    thx_status st = THX_OK;
    int N = (int)n, lwork = -1, liwork = -1, info = 0, qi;
    double qw;
    double *w = thx_malloc(ctx, n * sizeof *w), *work = NULL, *Lp = NULL, *AW = NULL, *Nm = NULL, *AWp = NULL,
           *T = NULL, *ALp = NULL;
    int *iwork = NULL;
    *P = *Q = NULL;
    *null_dim = 0;
    if (!w) return THX_ENOMEM;
    dsyevd_("V", "U", &N, M, &N, w, &qw, &lwork, &qi, &liwork, &info);
    lwork = (int)qw + 1;
    liwork = qi + 1;
    work = thx_malloc(ctx, (size_t)lwork * sizeof *work);
    iwork = thx_malloc(ctx, (size_t)liwork * sizeof *iwork);
    if (!work || !iwork) THX_TRY(THX_ENOMEM);
    dsyevd_("V", "U", &N, M, &N, w, work, &lwork, iwork, &liwork, &info);
    if (info) THX_TRY(thx_error(ctx, THX_ESOLVER, "LAPACK dsyevd (regularization operator, %zu x %zu) failed: info %d", n, n, info));
    size_t k0 = 0;
    while (k0 < n && w[k0] <= 1e-10 * w[n - 1]) k0++;
    /* Lp = Σ v v^T / sqrt(w) over the non-null eigenpairs: the pseudo-inverse of L's symmetric root */
    Lp = thx_calloc(ctx, n * n, sizeof *Lp);
    T = thx_malloc(ctx, n * n * sizeof *T);
    if (!Lp || !T) THX_TRY(THX_ENOMEM);
    for (size_t j = 0; j < n; j++)
        for (size_t i = 0; i < n; i++) T[j * n + i] = j >= k0 ? M[j * n + i] / sqrt(w[j]) : 0.0;
    thx_inv_gemm('N', 'T', n, n, n, T, n, M, n, 0.0, Lp, n);
    if (k0 > 0) {
        /* W = the first k0 eigenvectors; (AW)^+ = (W^T A^T A W)^-1 (AW)^T */
        AW = thx_malloc(ctx, m * k0 * sizeof *AW);
        Nm = thx_malloc(ctx, k0 * k0 * sizeof *Nm);
        AWp = thx_malloc(ctx, k0 * m * sizeof *AWp);
        ALp = thx_malloc(ctx, m * n * sizeof *ALp);
        if (!AW || !Nm || !AWp || !ALp) THX_TRY(THX_ENOMEM);
        thx_inv_gemm('N', 'N', m, k0, n, A, m, M, n, 0.0, AW, m);
        thx_inv_gemm('T', 'N', k0, k0, m, AW, m, AW, m, 0.0, Nm, k0);
        for (size_t j = 0; j < m; j++)
            for (size_t i = 0; i < k0; i++) AWp[j * k0 + i] = AW[i * m + j];
        int K0 = (int)k0, Mi = (int)m;
        dposv_("U", &K0, &Mi, Nm, &K0, AWp, &K0, &info);
        if (info)
            THX_TRY(thx_error(ctx, THX_EINPUT, "%s maps the regularization operator's null space (constant "
                                               "potentials) to zero: order 1 and 2 need A 1 != 0", mname));
        /* P = Lp - W (AWp (A Lp)),  Q = W AWp */
        double *S = thx_malloc(ctx, k0 * n * sizeof *S);
        *Q = thx_malloc(ctx, n * m * sizeof **Q);
        if (!S || !*Q) {
            free(S);
            THX_TRY(THX_ENOMEM);
        }
        thx_inv_gemm('N', 'N', m, n, n, A, m, Lp, n, 0.0, ALp, m);
        thx_inv_gemm('N', 'N', k0, n, m, AWp, k0, ALp, m, 0.0, S, k0);
        for (size_t j = 0; j < n; j++)
            for (size_t i = 0; i < n; i++) {
                double v = 0;
                for (size_t c = 0; c < k0; c++) v += M[c * n + i] * S[j * k0 + c];
                Lp[j * n + i] -= v;
            }
        thx_inv_gemm('N', 'N', n, m, k0, M, n, AWp, k0, 0.0, *Q, n);
        free(S);
    }
    *P = Lp;
    Lp = NULL;
    *null_dim = k0;
done:
    free(w);
    free(work);
    free(iwork);
    free(Lp);
    free(AW);
    free(Nm);
    free(AWp);
    free(T);
    free(ALp);
    if (st != THX_OK) {
        free(*Q);
        *Q = NULL;
    }
    return st;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static double median(const double *v, size_t n)
{
    double *c = malloc(n * sizeof *c);
    if (!c || !n) {
        free(c);
        return NAN;
    }
    size_t k = 0;
    for (size_t i = 0; i < n; i++)
        if (!isnan(v[i])) c[k++] = v[i];
    qsort(c, k, sizeof *c, cmp_double);
    double r = k ? (k % 2 ? c[k / 2] : 0.5 * (c[k / 2 - 1] + c[k / 2])) : NAN;
    free(c);
    return r;
}

typedef struct {
    int tsvd;
    thx_lambda_rule rule;
    double fixed;
    int per_series;
    int n_grid;
    const double *target; /* per column (discrepancy) */
    const char *matrix_name;
    double dof;           /* GCV's degrees of freedom: rows minus the operator's null-space dimension */
    int frames;           /* the columns are frames (not Greensite's components): the fallback applies */
    int no_fallback;      /* flag frames below the noise but keep their own λ */
    double noise;         /* σ per row for the fallback (0: estimated from the series' GCV fit) */
} core_opts;

/* ρ and η of one right-hand side (β² b2, perp2 outside range(U)) at Tikhonov λ, or TSVD keeping q
 * components */
static void point_at(const double *s, const double *b2, size_t kk, double perp2, int tsvd, double lambda, size_t q,
                     double *rho, double *eta)
{
    double r2 = perp2, e2 = 0;
    if (tsvd) {
        for (size_t i = 0; i < kk; i++)
            if (i < q) e2 += b2[i] / (s[i] * s[i]);
            else r2 += b2[i];
    } else
        thx_inv_norms(s, b2, kk, perp2, lambda, &r2, &e2);
    *rho = sqrt(r2);
    *eta = sqrt(e2);
}

/* The L-curve picture's data (thx_inverse_report's mark_* and frame curves): the representative
 * curve's corner and chosen point; a λ per frame: the curves of frames spread over the series. */
static thx_status picture_data(thx_ctx *ctx, const double *s, size_t kk, const double *beta, const double *perp,
                               const double *sum2, double perp_sum, size_t F, const core_opts *co, double series_lam,
                               int series_k, const double *lam, const int *kept, const double *rho, const double *eta,
                               thx_inverse_report *r)
{
    size_t nc = r->n_curve;
    double *b2 = thx_malloc(ctx, (kk ? kk : 1) * sizeof *b2);
    if (!b2) return THX_ENOMEM;
    const double *cb2 = sum2;
    double cperp = perp_sum;
    if (co->per_series) {
        double r2 = 0, e2 = 0;
        for (size_t f = 0; f < F; f++) r2 += rho[f] * rho[f], e2 += eta[f] * eta[f];
        r->mark_frame = -1;
        r->mark_lambda = series_lam;
        r->mark_residual = sqrt(r2);
        r->mark_seminorm = sqrt(e2);
        (void)series_k;
    } else {
        /* the representative frame: the largest ||b||² = Σ β² + the part outside range(U) */
        size_t rep = 0;
        double best = -1;
        for (size_t f = 0; f < F; f++) {
            double n2 = perp[f];
            for (size_t i = 0; i < kk; i++) n2 += beta[f * kk + i] * beta[f * kk + i];
            if (n2 > best) best = n2, rep = f;
        }
        for (size_t i = 0; i < kk; i++) b2[i] = beta[rep * kk + i] * beta[rep * kk + i];
        cb2 = b2;
        cperp = perp[rep];
        r->mark_frame = (long)rep;
        r->mark_lambda = lam[rep];
        r->mark_residual = rho[rep];
        r->mark_seminorm = eta[rep];
        (void)kept;
        /* frames spread evenly, the representative one among them */
        size_t want = F < THX_INVERSE_FRAME_CURVES ? F : THX_INVERSE_FRAME_CURVES, n = 0;
        r->frame_curve_frame = thx_malloc(ctx, (want + 1) * sizeof *r->frame_curve_frame);
        r->frame_curve_residual = thx_malloc(ctx, (want + 1) * (nc ? nc : 1) * sizeof(double));
        r->frame_curve_seminorm = thx_malloc(ctx, (want + 1) * (nc ? nc : 1) * sizeof(double));
        double *fb2 = thx_malloc(ctx, (kk ? kk : 1) * sizeof *fb2);
        if (!r->frame_curve_frame || !r->frame_curve_residual || !r->frame_curve_seminorm || !fb2) {
            free(fb2);
            free(b2);
            return THX_ENOMEM;
        }
        int rep_in = 0;
        for (size_t j = 0; j < want; j++) {
            size_t f = want > 1 ? (size_t)llround((double)j * (double)(F - 1) / (double)(want - 1)) : 0;
            if (!rep_in && rep < f) r->frame_curve_frame[n++] = rep, rep_in = 1;
            if (f == rep) rep_in = 1;
            if (n && r->frame_curve_frame[n - 1] == f) continue;
            r->frame_curve_frame[n++] = f;
        }
        if (!rep_in) r->frame_curve_frame[n++] = rep;
        for (size_t j = 0; j < n; j++) {
            size_t f = r->frame_curve_frame[j];
            for (size_t i = 0; i < kk; i++) fb2[i] = beta[f * kk + i] * beta[f * kk + i];
            for (size_t q = 0; q < nc; q++)
                point_at(s, fb2, kk, perp[f], co->tsvd, r->curve_lambda[q], q + 1, &r->frame_curve_residual[j * nc + q],
                         &r->frame_curve_seminorm[j * nc + q]);
        }
        r->n_frame_curves = n;
        free(fb2);
    }
    /* that curve's corner */
    int kc = 0;
    double lc = thx_inverse_pick(s, cb2, kk, cperp, 1.0, THX_LAMBDA_LCURVE, 0, 0, co->tsvd, co->n_grid, &kc, NULL);
    r->mark_corner_lambda = lc;
    point_at(s, cb2, kk, cperp, co->tsvd, lc, (size_t)(kc > 0 ? kc : 0), &r->mark_corner_residual,
             &r->mark_corner_seminorm);
    free(b2);
    return THX_OK;
}

/* The spectral core: Abar (m x n, destroyed) y ≈ Bb (m x F) by Tikhonov order 0 or TSVD with the rule;
 * Y (n x F) out, per column λ, k, ρ, η; the summed L-curve into r (when curve). */

static thx_status spectral(thx_ctx *ctx, double *Abar, size_t m, size_t n, const double *Bb, size_t F,
                           const core_opts *co, double *Y, double *lam, int *kept, double *rho, double *eta,
                           int *flags, thx_inverse_report *r, int curve)
{
    thx_status st = THX_OK;
    size_t kfull = m < n ? m : n, kk = kfull;
    double *s = thx_malloc(ctx, kfull * sizeof *s), *U = thx_malloc(ctx, m * kfull * sizeof *U),
           *VT = thx_malloc(ctx, kfull * n * sizeof *VT), *beta = thx_malloc(ctx, kfull * F * sizeof *beta),
           *perp = thx_malloc(ctx, F * sizeof *perp), *C = thx_calloc(ctx, kfull * F, sizeof *C),
           *sum2 = thx_calloc(ctx, kfull, sizeof *sum2);
    if (!s || !U || !VT || !beta || !perp || !C || !sum2) THX_TRY(THX_ENOMEM);
    double t0 = wtime();
    THX_TRY(svd(ctx, Abar, m, n, s, U, VT));
    if (r) {
        r->t_svd += wtime() - t0;
        free(r->sv);
        r->sv = thx_malloc(ctx, kfull * sizeof *r->sv);
        if (!r->sv) THX_TRY(THX_ENOMEM);
        memcpy(r->sv, s, kfull * sizeof *s);
        r->rank = kfull;
    }
    double t1 = wtime();
    if (!(s[0] > 0)) THX_TRY(thx_error(ctx, THX_EINPUT, "%s: the transfer matrix is zero", co->matrix_name));
    /* the numerical rank (LAPACK's and numpy's tolerance, s_1 max(m, n) ε): the components below it
     * are zero (a rank-deficient matrix; m < n with orders 1 and 2: the operator's null space, whose
     * image is taken off b); they are not solved for, their part of b is residual, and the rules'
     * search ranges end at the smallest nonzero singular value */
    {
        double tol = s[0] * (double)(m > n ? m : n) * DBL_EPSILON;
        kk = 0;
        while (kk < kfull && s[kk] > tol) kk++;
    }
    thx_inv_gemm('T', 'N', kk, F, m, U, m, Bb, m, 0.0, beta, kk);
    /* the part of b outside those components, as a vector (||b||² - ||β||² would cancel digits away) */
    double *Rb = thx_malloc(ctx, m * F * sizeof *Rb);
    if (!Rb) THX_TRY(THX_ENOMEM);
    memcpy(Rb, Bb, m * F * sizeof *Rb);
    {
        int M_ = (int)m, N_ = (int)F, K_ = (int)kk;
        double one = 1, mone = -1;
        dgemm_("N", "N", &M_, &N_, &K_, &mone, U, &M_, beta, &K_, &one, Rb, &M_);
    }
    double perp_sum = 0, target2 = 0;
    for (size_t f = 0; f < F; f++) {
        double p2 = 0;
        for (size_t i = 0; i < m; i++) p2 += Rb[f * m + i] * Rb[f * m + i];
        for (size_t i = 0; i < kk; i++) sum2[i] += beta[f * kk + i] * beta[f * kk + i];
        perp[f] = m > kk ? p2 : 0;
        perp_sum += perp[f];
        if (co->target) target2 += co->target[f] * co->target[f];
    }
    free(Rb);
    double series_lam = NAN;
    int series_k = 0, series_flags = 0;
    /* λ per frame with a rule: the series' λ too (the fallback for frames below the noise) */
    int fallback = co->frames && !co->per_series && co->rule != THX_LAMBDA_FIXED;
    if (co->per_series || fallback)
        /* the stacked problem: ρ² and η² summed over the frames; its GCV denominator is F (dof - Σ f),
         * so the minimizer is that of ρ²_sum / (dof - Σ f)² */
        series_lam = thx_inverse_pick(s, sum2, kk, perp_sum, co->dof, co->rule, co->fixed, sqrt(target2), co->tsvd,
                                      co->n_grid, &series_k, &series_flags);
    /* the noise level that tells a frame below it: given, or the series' GCV estimate
     * σ² = ||A x - b||² / trace(I - H) (per row and frame) at the series' GCV λ (Wahba) */
    double sigma = co->noise;
    if (fallback && !(sigma > 0)) {
        double lg = thx_inverse_pick(s, sum2, kk, perp_sum, co->dof, THX_LAMBDA_GCV, 0, 0, 0, co->n_grid, NULL, NULL);
        double r2, e2, tr = co->dof - (double)kk, l2 = lg * lg;
        thx_inv_norms(s, sum2, kk, perp_sum, lg, &r2, &e2);
        for (size_t i = 0; i < kk; i++) tr += l2 / (s[i] * s[i] + l2);
        sigma = tr > 0 ? sqrt(r2 / (tr * (double)F)) : 0;
        if (r) r->frame_noise_estimated = 1;
    }
    if (r && fallback) {
        r->frame_noise = sigma;
        r->series_lambda = series_lam;
        r->series_flags = series_flags;
    } else if (r && co->per_series)
        r->series_flags = series_flags;
    int fail = 0;
    size_t n_fb = 0;
#pragma omp parallel for schedule(dynamic, 8) reduction(| : fail) reduction(+ : n_fb)
    for (size_t f = 0; f < F; f++) {
        double *b2 = malloc((kk ? kk : 1) * sizeof *b2), *fl = malloc((kk ? kk : 1) * sizeof *fl);
        if (!b2 || !fl) {
            fail = 1;
            free(b2);
            free(fl);
            continue;
        }
        double n2 = perp[f];
        for (size_t i = 0; i < kk; i++) n2 += b2[i] = beta[f * kk + i] * beta[f * kk + i];
        int kf = series_k, ff = series_flags;
        double l = co->per_series ? series_lam
                                  : thx_inverse_pick(s, b2, kk, perp[f], co->dof, co->rule, co->fixed,
                                                     co->target ? co->target[f] : 0, co->tsvd, co->n_grid, &kf, &ff);
        /* a frame whose data is below the noise (its signal's energy ||b||² - dof σ² below the
         * noise's dof σ²): no rule finds anything but noise there; the series' λ */
        if (fallback && sigma > 0 && n2 < 2 * co->dof * sigma * sigma) {
            if (!co->no_fallback) { /* the flags say what the λ used is: the series' */
                l = series_lam;
                kf = series_k;
                ff = series_flags;
                n_fb++;
            }
            ff |= THX_LAMBDA_BELOW_NOISE;
        }
        if (co->tsvd)
            for (size_t i = 0; i < kk; i++) fl[i] = (int)i < kf ? 1.0 : 0.0;
        else
            thx_inverse_filter(s, kk, l, 0, fl);
        double r2 = perp[f], e2 = 0;
        for (size_t i = 0; i < kk; i++) {
            C[f * kk + i] = fl[i] * beta[f * kk + i] / s[i];
            r2 += (1 - fl[i]) * (1 - fl[i]) * b2[i];
            e2 += fl[i] * fl[i] * b2[i] / (s[i] * s[i]);
        }
        lam[f] = l;
        if (kept) kept[f] = co->tsvd ? kf : 0;
        if (flags) flags[f] = ff;
        rho[f] = sqrt(r2);
        eta[f] = sqrt(e2);
        free(b2);
        free(fl);
    }
    if (r) r->n_fallback = n_fb;
    if (fail) THX_TRY(THX_ENOMEM);
    thx_inv_gemm('T', 'N', n, F, kk, VT, kfull, C, kk, 0.0, Y, n);
    if (r && curve) {
        /* the series' L-curve: Tikhonov on the λ grid, or TSVD at each k */
        size_t nc = co->tsvd ? kk : (size_t)(co->n_grid > 2 ? co->n_grid : 200);
        free(r->curve_lambda);
        free(r->curve_residual);
        free(r->curve_seminorm);
        r->curve_lambda = thx_malloc(ctx, nc * sizeof(double));
        r->curve_residual = thx_malloc(ctx, nc * sizeof(double));
        r->curve_seminorm = thx_malloc(ctx, nc * sizeof(double));
        if (!r->curve_lambda || !r->curve_residual || !r->curve_seminorm) THX_TRY(THX_ENOMEM);
        if (co->tsvd) {
            size_t nk = 0;
            for (size_t q = 1; q <= kk && s[q - 1] > s[0] * 16 * DBL_EPSILON; q++) {
                double r2 = perp_sum, e2 = 0;
                for (size_t i = 0; i < kk; i++)
                    if (i < q) e2 += sum2[i] / (s[i] * s[i]);
                    else r2 += sum2[i];
                r->curve_lambda[nk] = s[q - 1];
                r->curve_residual[nk] = sqrt(r2);
                r->curve_seminorm[nk++] = sqrt(e2);
            }
            nc = nk;
            int kc = 0;
            r->corner_lambda = thx_inverse_pick(s, sum2, kk, perp_sum, co->dof, THX_LAMBDA_LCURVE, 0, 0, 1, co->n_grid,
                                                &kc, NULL);
        } else {
            thx_inv_grid(s, kk, (int)nc, r->curve_lambda);
            for (size_t q = 0; q < nc; q++) {
                double r2, e2;
                thx_inv_norms(s, sum2, kk, perp_sum, r->curve_lambda[q], &r2, &e2);
                r->curve_residual[q] = sqrt(r2);
                r->curve_seminorm[q] = sqrt(e2);
            }
            r->corner_lambda = thx_inverse_pick(s, sum2, kk, perp_sum, co->dof, THX_LAMBDA_LCURVE, 0, 0, 0, co->n_grid,
                                                NULL, NULL);
        }
        r->n_curve = nc;
        r->chosen_lambda = co->per_series ? series_lam : median(lam, F);
        THX_TRY(picture_data(ctx, s, kk, beta, perp, sum2, perp_sum, F, co, series_lam, series_k, lam, kept, rho, eta, r));
    }
    if (r) r->t_frames += wtime() - t1;
done:
    free(s);
    free(U);
    free(VT);
    free(beta);
    free(perp);
    free(C);
    free(sum2);
    return st;
}

/* Total variation by IRLS from the order-1 solution X (n x F, updated in place), λ per frame. */
static thx_status tv_refine(thx_ctx *ctx, const double *A, size_t m, size_t n, const double *B, size_t F,
                            const thx_surface *h, const double *lam, int iters, double *X, double *tvnorm,
                            const char *mname)
{
    size_t bad_f = F;
    thx_status st = THX_OK;
    size_t nt = h->n_tris, r3 = 3 * nt;
    double *G = NULL, *sqa = NULL, *AtA = thx_malloc(ctx, n * n * sizeof *AtA), *AtB = thx_malloc(ctx, n * F * sizeof *AtB);
    if (!AtA || !AtB) THX_TRY(THX_ENOMEM);
    THX_TRY(thx_inv_gradient(ctx, h, &G));
    thx_inv_gemm('T', 'N', n, n, m, A, m, A, m, 0.0, AtA, n);
    thx_inv_gemm('T', 'N', n, F, m, A, m, B, m, 0.0, AtB, n);
    /* sqrt(area) per triangle: G's rows are sqrt(area) ∇x, so Σ area |∇x| = Σ sqrt(area) |G_t x| */
    sqa = thx_malloc(ctx, (nt ? nt : 1) * sizeof *sqa);
    if (!sqa) THX_TRY(THX_ENOMEM);
    for (size_t t = 0; t < nt; t++) {
        const double *p0 = h->xyz + 3 * (size_t)h->tri[3 * t], *p1 = h->xyz + 3 * (size_t)h->tri[3 * t + 1],
                     *p2 = h->xyz + 3 * (size_t)h->tri[3 * t + 2];
        double u[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]}, v[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
        double nx = u[1] * v[2] - u[2] * v[1], ny = u[2] * v[0] - u[0] * v[2], nz = u[0] * v[1] - u[1] * v[0];
        sqa[t] = sqrt(0.5 * sqrt(nx * nx + ny * ny + nz * nz));
    }
    int fail = 0;
#pragma omp parallel for schedule(dynamic, 1) reduction(| : fail)
    for (size_t f = 0; f < F; f++) {
        double *S = malloc(n * n * sizeof *S), *g = malloc(r3 * sizeof *g), *w = malloc(nt * sizeof *w),
               *x = malloc(n * sizeof *x);
        if (!S || !g || !w || !x) {
            fail = 1;
            goto next;
        }
        double *xf = X + f * n, l2 = lam[f] * lam[f], c = 0, eps = 0;
        for (int it = 0; it < iters; it++) {
            /* g = G x: per triangle sqrt(area) ∇x */
            for (size_t i = 0; i < r3; i++) g[i] = 0;
            for (size_t j = 0; j < n; j++)
                for (size_t i = 0; i < r3; i++) g[i] += G[j * r3 + i] * xf[j];
            if (it == 0) {
                /* the weights' scale: at the start the reweighted penalty equals the order-1 one */
                double q2 = 0, q1 = 0, gmax = 0;
                for (size_t t = 0; t < nt; t++) {
                    double a2 = g[3 * t] * g[3 * t] + g[3 * t + 1] * g[3 * t + 1] + g[3 * t + 2] * g[3 * t + 2];
                    q2 += a2;
                    q1 += sqa[t] * sqrt(a2);
                    if (sqrt(a2) > gmax) gmax = sqrt(a2);
                }
                c = q1 > 0 ? q2 / q1 : 1;
                eps = 1e-3 * (gmax > 0 ? gmax : 1);
            }
            for (size_t t = 0; t < nt; t++)
                w[t] = c * sqa[t] / sqrt(g[3 * t] * g[3 * t] + g[3 * t + 1] * g[3 * t + 1] + g[3 * t + 2] * g[3 * t + 2] + eps * eps);
            /* S = AtA + λ² G^T W G (only the upper triangle is used by dposv) */
            memcpy(S, AtA, n * n * sizeof *S);
            for (size_t t = 0; t < nt; t++)
                for (int a = 0; a < 3; a++) {
                    size_t I = (size_t)h->tri[3 * t + a];
                    for (int b = 0; b < 3; b++) {
                        size_t J = (size_t)h->tri[3 * t + b];
                        double v = 0;
                        for (int d = 0; d < 3; d++) v += G[I * r3 + 3 * t + d] * G[J * r3 + 3 * t + d];
                        S[J * n + I] += l2 * w[t] * v;
                    }
                }
            memcpy(x, AtB + f * n, n * sizeof *x);
            int N = (int)n, one = 1, info = 0;
            dposv_("U", &N, &one, S, &N, x, &N, &info);
            if (info) {
                fail = 2;
#pragma omp critical(thx_tv_bad)
                if (f < bad_f) bad_f = f;
                break;
            }
            double d2 = 0, x2 = 0;
            for (size_t j = 0; j < n; j++) {
                d2 += (x[j] - xf[j]) * (x[j] - xf[j]);
                x2 += x[j] * x[j];
            }
            memcpy(xf, x, n * sizeof *x);
            if (d2 <= 1e-8 * x2) break;
        }
        {
            for (size_t i = 0; i < r3; i++) g[i] = 0;
            for (size_t j = 0; j < n; j++)
                for (size_t i = 0; i < r3; i++) g[i] += G[j * r3 + i] * xf[j];
            double tv = 0;
            for (size_t t = 0; t < nt; t++) {
                /* Σ area |∇x| = Σ sqrt(area) |g_t| with |g_t| = sqrt(area) |∇x| */
                double gg = sqrt(g[3 * t] * g[3 * t] + g[3 * t + 1] * g[3 * t + 1] + g[3 * t + 2] * g[3 * t + 2]);
                tv += sqa[t] * gg;
            }
            tvnorm[f] = tv;
        }
    next:
        free(S);
        free(g);
        free(w);
        free(x);
    }
    if (fail == 1) THX_TRY(THX_ENOMEM);
    if (fail)
        THX_TRY(thx_error(ctx, THX_ESOLVER, "%s: total variation, frame %zu, λ %.3g: the reweighted system A^T A + λ² "
                          "G^T W G is not positive definite (LAPACK dposv); λ too small for the rows (%zu) and the "
                          "heart nodes (%zu), or the matrix vanishes on constants", mname, bad_f + 1,
                          bad_f < F ? lam[bad_f] : NAN, m, n));
done:
    free(G);
    free(sqa);
    free(AtA);
    free(AtB);
    return st;
}

static thx_status check_inputs(thx_ctx *ctx, const thx_series *A, const thx_series *B, const thx_surface *heart,
                               const thx_inverse_opts *o)
{
    size_t row, col;
    if (A->n_rows != B->n_rows)
        return thx_error(ctx, THX_EINPUT, "%s has %zu rows (body-surface leads) but %s has %zu rows: they must be the same leads",
                         o->matrix_name, A->n_rows, o->data_name, B->n_rows);
    if (thx_series_find_nonfinite(A, &row, &col))
        return thx_error(ctx, THX_EINPUT, "%s: row %zu, column %zu (heart node): %s; the transfer matrix must be finite",
                         o->matrix_name, row + 1, col + 1, isnan(A->v[col * A->n_rows + row]) ? "NaN" : "Inf");
    if (thx_series_find_nonfinite(B, &row, &col))
        return thx_error(ctx, THX_EINPUT, "%s: row %zu, frame %zu: %s; the data must be finite (drop or interpolate the lead)",
                         o->data_name, row + 1, col + 1, isnan(B->v[col * B->n_rows + row]) ? "NaN" : "Inf");
    int needs_heart = o->method == THX_INVERSE_TIKHONOV1 || o->method == THX_INVERSE_TIKHONOV2 || o->method == THX_INVERSE_TV;
    if (needs_heart && !heart)
        return thx_error(ctx, THX_EINPUT, "%s needs the heart surface (its gradient or Laplacian): none given for %s",
                         thx_inverse_method_name(o->method), o->matrix_name);
    /* any method given a heart (the CLI's --heart): its nodes must be the matrix's columns */
    if (heart && heart->n_nodes != A->n_frames)
        return thx_error(ctx, THX_EINPUT, "%s has %zu columns (heart nodes) but the heart surface \"%s\" of %s has %zu "
                         "nodes: the columns must be that surface's nodes", o->matrix_name, A->n_frames, heart->name,
                         o->heart_name ? o->heart_name : "the model", heart->n_nodes);
    if (A->n_rows == 0 || A->n_frames == 0)
        return thx_error(ctx, THX_EINPUT, "%s is empty (%zu x %zu)", o->matrix_name, A->n_rows, A->n_frames);
    if (B->n_frames == 0) return thx_error(ctx, THX_EINPUT, "%s has no frames", o->data_name);
    if (o->method == THX_INVERSE_TSVD && o->rule == THX_LAMBDA_CRESO)
        return thx_error(ctx, THX_EINPUT, "CRESO is a Tikhonov rule (a derivative in λ); with tsvd use lcurve, gcv, "
                                          "discrepancy or a value");
    if (o->rule == THX_LAMBDA_DISCREPANCY && !(o->noise > 0) && !(o->snr_db > 0))
        return thx_error(ctx, THX_EINPUT, "the discrepancy principle needs the noise level (--noise)");
    if (o->rule == THX_LAMBDA_FIXED && !(o->lambda >= 0))
        return thx_error(ctx, THX_EINPUT, "λ must be a number >= 0");
    return THX_OK;
}

/* σ: given, or from the signal-to-noise ratio against the whole series' RMS (noise of one level
 * on every frame, as a recording's is) */
static double series_sigma(const thx_inverse_opts *o, const thx_series *B)
{
    if (o->noise > 0) return o->noise;
    double s2 = 0;
    size_t n = B->n_rows * B->n_frames;
    for (size_t i = 0; i < n; i++) s2 += B->v[i] * B->v[i];
    return sqrt(s2 / (double)n) * pow(10.0, -o->snr_db / 20.0);
}

thx_status thx_inverse_solve(thx_ctx *ctx, const thx_series *A, const thx_series *B, const thx_surface *heart,
                             const thx_inverse_opts *o, thx_series **X, thx_inverse_report *r)
{
    thx_status st = THX_OK;
    *X = NULL;
    memset(r, 0, sizeof *r);
    THX_CHECK(check_inputs(ctx, A, B, heart, o));
    size_t m = A->n_rows, n = A->n_frames, F = B->n_frames;
    double *Abar = NULL, *P = NULL, *Q = NULL, *M = NULL, *Bb = NULL, *Y = NULL, *target = NULL;
    double *Ub = NULL, *sb = NULL, *Vbt = NULL, *D = NULL, *Yr = NULL;
    thx_series *x = NULL;
    core_opts co = {.tsvd = o->method == THX_INVERSE_TSVD, .rule = o->rule, .fixed = o->lambda,
                    .per_series = o->per_series, .n_grid = o->n_grid > 2 ? o->n_grid : 200,
                    .matrix_name = o->matrix_name, .dof = (double)m, .no_fallback = o->no_fallback};
    r->n_frames = F;
    r->series_lambda = NAN;
    r->flags = thx_calloc(ctx, F, sizeof *r->flags);
    r->lambda = thx_malloc(ctx, F * sizeof *r->lambda);
    r->k = thx_calloc(ctx, F, sizeof *r->k);
    r->residual = thx_malloc(ctx, F * sizeof *r->residual);
    r->seminorm = thx_malloc(ctx, F * sizeof *r->seminorm);
    THX_TRY(thx_series_create(ctx, n, F, &x));
    if (!r->lambda || !r->k || !r->residual || !r->seminorm || !r->flags) THX_TRY(THX_ENOMEM);
    memcpy(x->time, B->time, F * sizeof *x->time);
    snprintf(x->unit, sizeof x->unit, "%s", B->unit);
    snprintf(x->time_unit, sizeof x->time_unit, "%s", B->time_unit);
    snprintf(x->label, sizeof x->label, "heart potentials by thorax inverse (%s)", thx_inverse_method_name(o->method));
    double t0 = wtime();
    int order = o->method == THX_INVERSE_TIKHONOV2 ? 2 : (o->method == THX_INVERSE_TIKHONOV1 || o->method == THX_INVERSE_TV) ? 1 : 0;

    if (o->method == THX_INVERSE_GREENSITE) {
        /* the data's temporal SVD: B = Ub diag(sb) Vbt */
        size_t q = m < F ? m : F;
        double *Bc = thx_malloc(ctx, m * F * sizeof *Bc);
        Ub = thx_malloc(ctx, m * q * sizeof *Ub);
        sb = thx_malloc(ctx, q * sizeof *sb);
        Vbt = thx_malloc(ctx, q * F * sizeof *Vbt);
        if (!Bc || !Ub || !sb || !Vbt) {
            free(Bc);
            THX_TRY(THX_ENOMEM);
        }
        memcpy(Bc, B->v, m * F * sizeof *Bc);
        st = svd(ctx, Bc, m, F, sb, Ub, Vbt);
        free(Bc);
        if (st != THX_OK) goto done;
        double sigma = 0;
        if (o->noise > 0 || o->snr_db > 0) {
            double s2 = 0;
            for (size_t i = 0; i < m * F; i++) s2 += B->v[i] * B->v[i];
            sigma = o->noise > 0 ? o->noise : sqrt(s2 / (double)(m * F)) * pow(10.0, -o->snr_db / 20.0);
        }
        size_t rk = 0;
        if (o->greensite_rank > 0) rk = (size_t)o->greensite_rank < q ? (size_t)o->greensite_rank : q;
        else if (sigma > 0) {
            /* components above the noise's largest singular value, about σ (sqrt(m) + sqrt(F)) */
            double thr = sigma * (sqrt((double)m) + sqrt((double)F));
            while (rk < q && sb[rk] > thr) rk++;
        } else {
            double tot = 0, acc = 0;
            for (size_t j = 0; j < q; j++) tot += sb[j] * sb[j];
            while (rk < q && acc < (1 - 1e-4) * tot) acc += sb[rk] * sb[rk], rk++;
        }
        if (rk == 0) rk = 1;
        r->noise_sigma = sigma;
        D = thx_malloc(ctx, m * rk * sizeof *D);
        Yr = thx_malloc(ctx, n * rk * sizeof *Yr);
        Abar = thx_malloc(ctx, m * n * sizeof *Abar);
        target = thx_malloc(ctx, rk * sizeof *target);
        r->component_lambda = thx_malloc(ctx, rk * sizeof *r->component_lambda);
        double *rho = thx_malloc(ctx, rk * sizeof *rho), *eta = thx_malloc(ctx, rk * sizeof *eta);
        if (!D || !Yr || !Abar || !target || !r->component_lambda || !rho || !eta) {
            free(rho);
            free(eta);
            THX_TRY(THX_ENOMEM);
        }
        for (size_t j = 0; j < rk; j++) {
            for (size_t i = 0; i < m; i++) D[j * m + i] = Ub[j * m + i] * sb[j];
            target[j] = sqrt((double)m) * sigma;
        }
        memcpy(Abar, A->v, m * n * sizeof *Abar);
        co.target = target;
        co.tsvd = 0;
        r->t_svd = wtime() - t0;
        st = spectral(ctx, Abar, m, n, D, rk, &co, Yr, r->component_lambda, NULL, rho, eta, NULL, r, 1);
        free(rho);
        free(eta);
        if (st != THX_OK) goto done;
        r->n_components = rk;
        double t1 = wtime();
        thx_inv_gemm('N', 'N', n, F, rk, Yr, n, Vbt, q, 0.0, x->v, n);
        /* per-frame figures of the recombined solution */
        double *res = thx_malloc(ctx, m * F * sizeof *res);
        if (!res) THX_TRY(THX_ENOMEM);
        memcpy(res, B->v, m * F * sizeof *res);
        int M_ = (int)m, N_ = (int)F, K_ = (int)n;
        double one = 1, mone = -1;
        dgemm_("N", "N", &M_, &N_, &K_, &one, A->v, &M_, x->v, &K_, &mone, res, &M_);
        for (size_t f = 0; f < F; f++) {
            double r2 = 0, e2 = 0;
            for (size_t i = 0; i < m; i++) r2 += res[f * m + i] * res[f * m + i];
            for (size_t j = 0; j < n; j++) e2 += x->v[f * n + j] * x->v[f * n + j];
            r->residual[f] = sqrt(r2);
            r->seminorm[f] = sqrt(e2);
        }
        free(res);
        r->chosen_lambda = median(r->component_lambda, rk);
        /* a frame has no λ of its own (each temporal component has one): every frame reports the median
         * of the components' λ, the figure the picture and inverse.json's lambda_used give, never NaN */
        for (size_t f = 0; f < F; f++) r->lambda[f] = r->chosen_lambda;
        r->t_frames += wtime() - t1;
        goto finish;
    }

    Bb = thx_malloc(ctx, m * F * sizeof *Bb);
    Y = thx_malloc(ctx, n * F * sizeof *Y);
    Abar = thx_malloc(ctx, m * n * sizeof *Abar);
    target = thx_malloc(ctx, F * sizeof *target);
    if (!Bb || !Y || !Abar || !target) THX_TRY(THX_ENOMEM);
    memcpy(Bb, B->v, m * F * sizeof *Bb);
    double sig = o->rule == THX_LAMBDA_DISCREPANCY ? series_sigma(o, B) : 0;
    for (size_t f = 0; f < F; f++) target[f] = sqrt((double)m) * sig;
    if (o->rule == THX_LAMBDA_DISCREPANCY) r->noise_sigma = target[0] / sqrt((double)m);
    size_t null_dim = 0;
    if (order > 0) {
        THX_TRY(thx_inverse_operator(ctx, heart, order, &M));
        THX_TRY(standard_form(ctx, A->v, m, n, M, &P, &Q, &null_dim, o->matrix_name));
        thx_inv_gemm('N', 'N', m, n, n, A->v, m, P, n, 0.0, Abar, m);
        if (Q) { /* b̄ = b - A Q b */
            double *QB = thx_malloc(ctx, n * F * sizeof *QB);
            if (!QB) THX_TRY(THX_ENOMEM);
            thx_inv_gemm('N', 'N', n, F, m, Q, n, B->v, m, 0.0, QB, n);
            int M_ = (int)m, N_ = (int)F, K_ = (int)n;
            double one = 1, mone = -1;
            dgemm_("N", "N", &M_, &N_, &K_, &mone, A->v, &M_, QB, &K_, &one, Bb, &M_);
            memcpy(x->v, QB, n * F * sizeof *QB); /* x0, the null-space part */
            free(QB);
        }
    } else {
        memcpy(Abar, A->v, m * n * sizeof *Abar);
    }
    r->t_svd = wtime() - t0;
    co.target = target;
    /* trace(I - H) = m - null_dim - Σ f_i (docs/design/inverse.md): the null space's image is fitted
     * exactly, whatever λ */
    co.dof = (double)m - (double)null_dim;
    r->null_dim = null_dim;
    co.frames = 1;
    if (o->noise > 0 || o->snr_db > 0) co.noise = series_sigma(o, B);
    THX_TRY(spectral(ctx, Abar, m, n, Bb, F, &co, Y, r->lambda, r->k, r->residual, r->seminorm, r->flags, r, 1));
    double t1 = wtime();
    if (order > 0) thx_inv_gemm('N', 'N', n, F, n, P, n, Y, n, Q ? 1.0 : 0.0, x->v, n);
    else memcpy(x->v, Y, n * F * sizeof *Y);
    r->t_frames += wtime() - t1;
    if (o->method == THX_INVERSE_TV) {
        double t2 = wtime();
        THX_TRY(tv_refine(ctx, A->v, m, n, B->v, F, heart, r->lambda, o->tv_iterations > 0 ? o->tv_iterations : 10,
                          x->v, r->seminorm, o->matrix_name));
        /* the residuals of the TV solutions */
        for (size_t f = 0; f < F; f++) {
            double r2 = 0;
            for (size_t i = 0; i < m; i++) {
                double v = -B->v[f * m + i];
                for (size_t j = 0; j < n; j++) v += A->v[j * m + i] * x->v[f * n + j];
                r2 += v * v;
            }
            r->residual[f] = sqrt(r2);
        }
        r->t_frames += wtime() - t2;
    }
finish:
    /* nothing that is not a number leaves here (a rule or a solve gone wrong is an error, not a file of NaN) */
    for (size_t i = 0; i < n * F; i++)
        if (!isfinite(x->v[i]))
            THX_TRY(thx_error(ctx, THX_ESOLVER, "%s with %s: heart node %zu, frame %zu came out %s; nothing written",
                              o->matrix_name, thx_inverse_method_name(o->method), i % n + 1, i / n + 1,
                              isnan(x->v[i]) ? "NaN" : "infinite"));
    for (size_t f = 0; f < F; f++)
        if (!isfinite(r->residual[f]) || !isfinite(r->seminorm[f]) || !isfinite(r->lambda[f]))
            THX_TRY(thx_error(ctx, THX_ESOLVER, "%s with %s: frame %zu's λ, residual or solution norm is not a number; "
                              "nothing written", o->matrix_name, thx_inverse_method_name(o->method), f + 1));
    *X = x;
    x = NULL;
done:
    thx_series_destroy(&x);
    free(Abar);
    free(P);
    free(Q);
    free(M);
    free(Bb);
    free(Y);
    free(target);
    free(Ub);
    free(sb);
    free(Vbt);
    free(D);
    free(Yr);
    if (st != THX_OK) thx_inverse_report_free(r);
    return st;
}
