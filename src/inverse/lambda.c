/* The λ rules on the spectral data of a right-hand side: filter factors, L-curve corner, CRESO,
 * GCV, discrepancy (thorax/inverse/inverse.h; docs/decisions.md "The inverse problem"). */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "inverse/inverse_impl.h"

void thx_inverse_filter(const double *s, size_t k, double lambda, int tsvd, double *f)
{
    double l2 = lambda * lambda;
    for (size_t i = 0; i < k; i++) f[i] = tsvd ? (s[i] > lambda ? 1.0 : 0.0) : s[i] * s[i] / (s[i] * s[i] + l2);
}

void thx_inverse_compare(const double *x, const double *t, size_t n, double *cc, double *re)
{
    double mx = 0, mt = 0;
    for (size_t i = 0; i < n; i++) {
        mx += x[i];
        mt += t[i];
    }
    mx /= (double)n;
    mt /= (double)n;
    double sxy = 0, sxx = 0, syy = 0, d2 = 0, t2 = 0;
    for (size_t i = 0; i < n; i++) {
        double a = x[i] - mx, b = t[i] - mt;
        sxy += a * b;
        sxx += a * a;
        syy += b * b;
        d2 += (x[i] - t[i]) * (x[i] - t[i]);
        t2 += t[i] * t[i];
    }
    *cc = sxx > 0 && syy > 0 ? sxy / sqrt(sxx * syy) : NAN;
    *re = t2 > 0 ? sqrt(d2 / t2) : NAN;
}

/* ρ² = ||A x - b||² and η² = ||L x||² of Tikhonov at λ */
void thx_inv_norms(const double *s, const double *beta2, size_t k, double perp2, double lambda, double *rho2,
                   double *eta2)
{
    double l2 = lambda * lambda, r = perp2, e = 0;
    for (size_t i = 0; i < k; i++) {
        double s2 = s[i] * s[i], f = s2 / (s2 + l2);
        r += (1 - f) * (1 - f) * beta2[i];
        e += f * f * beta2[i] / s2;
    }
    *rho2 = r;
    *eta2 = e;
}

/* One right-hand side's spectral data, with s² and ξ² = β²/s² computed once (the rules evaluate
 * their functions at a few hundred λ). */
typedef struct {
    const double *s2, *b2, *xi2;
    size_t k;
    double perp2, m;
} spec;

/* The signed curvature of the L-curve (x, y) = (log ρ, log η) at λ, positive at the corner:
 * κ = (x' y'' - x'' y') / (x'² + y'²)^(3/2) with the derivatives in λ from the filter factors
 * f = s²/(s²+λ²): f' = -2 f (1-f)/λ, f'' = -f' (3-4f)/λ (docs/decisions.md). */
static double f_kappa(const spec *q, double lambda)
{
    double l2 = lambda * lambda, il = 1.0 / lambda, rho2 = q->perp2, eta2 = 0, a = 0, b = 0, c = 0, d = 0;
    for (size_t i = 0; i < q->k; i++) {
        double f = q->s2[i] / (q->s2[i] + l2), g = 1 - f, f1 = -2 * f * g * il, f2 = -f1 * (3 - 4 * f) * il;
        double xi2 = q->xi2[i], b2 = q->b2[i];
        rho2 += g * g * b2;
        eta2 += f * f * xi2;
        a += f * f1 * xi2;                /* η η' */
        b += (f1 * f1 + f * f2) * xi2;    /* (η η')' */
        c += -g * f1 * b2;                /* ρ ρ' */
        d += (f1 * f1 - g * f2) * b2;     /* (ρ ρ')' */
    }
    if (!(rho2 > 0) || !(eta2 > 0)) return -INFINITY;
    /* x' = ρ'/ρ = c/ρ², x'' = (ρρ')'/ρ² - 2 x'²; likewise y */
    double x1 = c / rho2, y1 = a / eta2;
    double x2 = d / rho2 - 2 * x1 * x1, y2 = b / eta2 - 2 * y1 * y1;
    double den = pow(x1 * x1 + y1 * y1, 1.5);
    if (!(den > 0)) return -INFINITY;
    return (x1 * y2 - x2 * y1) / den;
}

/* CRESO's C(λ) = η² + 2 λ² dη²/d(λ²) = Σ s² β² (s² - 3λ²) / (s² + λ²)³ */
static double f_creso(const spec *q, double lambda)
{
    double l2 = lambda * lambda, c = 0;
    for (size_t i = 0; i < q->k; i++) {
        double s2 = q->s2[i], d = 1.0 / (s2 + l2);
        c += s2 * q->b2[i] * (s2 - 3 * l2) * d * d * d;
    }
    return c;
}

/* minus GCV's G(λ) = ρ² / trace(I - H)², trace(I - H) = dof - Σ f = (dof - k) + Σ (1 - f): the sum of
 * 1 - f = λ²/(s² + λ²) directly, so that the trace keeps its digits where it goes to 0 (m < n, λ
 * small: dof = k there) instead of being the difference of two nearly equal numbers */
static double f_mgcv(const spec *q, double lambda)
{
    double l2 = lambda * lambda, rho2 = q->perp2, tr = q->m - (double)q->k;
    for (size_t i = 0; i < q->k; i++) {
        double g = l2 / (q->s2[i] + l2);
        rho2 += g * g * q->b2[i];
        tr += g;
    }
    return tr > 0 ? -rho2 / (tr * tr) : -INFINITY;
}

typedef double (*fn1)(const spec *q, double lambda);

/* The maximum of g in log λ between a and c (a < c), golden section. */
static double golden_max(fn1 g, const spec *q, double a, double c)
{
    double la = log(a), lc = log(c), r = (sqrt(5.0) - 1) / 2;
    double x1 = lc - r * (lc - la), x2 = la + r * (lc - la);
    double g1 = g(q, exp(x1)), g2 = g(q, exp(x2));
    for (int it = 0; it < 60 && lc - la > 1e-8; it++) {
        if (g1 >= g2) {
            lc = x2;
            x2 = x1;
            g2 = g1;
            x1 = lc - r * (lc - la);
            g1 = g(q, exp(x1));
        } else {
            la = x1;
            x1 = x2;
            g1 = g2;
            x2 = la + r * (lc - la);
            g2 = g(q, exp(x2));
        }
    }
    return exp(0.5 * (la + lc));
}

size_t thx_inv_grid(const double *s, size_t k, int n_grid, double *grid)
{
    /* from the largest singular value down to the smallest (or s_1 · 16 eps), log-spaced */
    double hi = s[0], lo = s[k - 1];
    if (lo < hi * 16 * DBL_EPSILON) lo = hi * 16 * DBL_EPSILON;
    if (n_grid < 3) n_grid = 3;
    for (int i = 0; i < n_grid; i++) grid[i] = exp(log(lo) + (log(hi) - log(lo)) * i / (n_grid - 1));
    return (size_t)n_grid;
}


static double pick_tsvd(const double *s, const double *beta2, size_t k, double perp2, double m, thx_lambda_rule rule,
                        double fixed, double target, int n_grid, int *kept, int *flags)
{
    size_t kmax = 0;
    while (kmax < k && s[kmax] > s[0] * 16 * DBL_EPSILON) kmax++;
    size_t best = kmax;
    /* ρ_k² and η_k² for every k at once: suffix and prefix sums (O(k), no cancellation) */
    double *R2 = malloc(2 * (k + 1) * sizeof *R2), *E2 = R2 ? R2 + k + 1 : NULL;
    if (!R2) return NAN;
    E2[0] = 0;
    for (size_t q = 1; q <= k; q++) E2[q] = E2[q - 1] + beta2[q - 1] / (s[q - 1] * s[q - 1]);
    R2[k] = perp2;
    for (size_t q = k; q-- > 0;) R2[q] = R2[q + 1] + beta2[q];
    if (rule == THX_LAMBDA_FIXED) {
        best = 0;
        while (best < k && s[best] > fixed) best++;
    } else if (rule == THX_LAMBDA_GCV) {
        double bg = INFINITY;
        for (size_t kk = 1; kk <= kmax; kk++) {
            double r2 = R2[kk];
            double d = m - (double)kk, g = d > 0 ? r2 / (d * d) : INFINITY;
            if (g < bg) {
                bg = g;
                best = kk;
            }
        }
    } else if (rule == THX_LAMBDA_DISCREPANCY) {
        best = kmax;
        int met = 0;
        for (size_t kk = 1; kk <= kmax; kk++) {
            if (sqrt(R2[kk]) <= target) {
                best = kk;
                met = 1;
                break;
            }
        }
        if (!met) *flags |= THX_LAMBDA_AT_LOW; /* the target below every residual: all components kept */
    } else {
        /* L-curve: the corner of the continuous Tikhonov L-curve of the same data, λ*, and the
         * components above it (Hansen: the TSVD and Tikhonov L-curves turn at the same place,
         * λ ~ s_k). The discrete polyline's own corner was tried twice and is not robust: its
         * three-point curvature is largest where points crowd together (34 components kept, error
         * 0.36, where the Tikhonov L-curve's is 0.16, on tests/test_inverse.c's problem at 0.1%
         * noise), and the point farthest from its chord follows the last, noise-dominated
         * components; this keeps 25, 32, 36 components there (errors 0.11, 0.16, 0.05 at 1, 0.1,
         * 0.01% noise, the Tikhonov L-curve's 0.10, 0.16, 0.13) */
        double lam = thx_inverse_pick(s, beta2, k, perp2, m, THX_LAMBDA_LCURVE, fixed, target, 0, n_grid, NULL, flags);
        *flags &= ~(THX_LAMBDA_AT_LOW | THX_LAMBDA_AT_HIGH);
        best = 0;
        while (best < kmax && s[best] > lam) best++;
        if (best == 0) best = 1;
    }
    free(R2);
    if (rule != THX_LAMBDA_FIXED && kmax > 0) {
        if (best >= kmax) *flags |= THX_LAMBDA_AT_LOW;
        if (best <= 1) *flags |= THX_LAMBDA_AT_HIGH;
    }
    if (kept) *kept = (int)best;
    if (best == 0) return s[0];
    return s[best - 1];
}

double thx_inverse_pick(const double *s, const double *beta2, size_t k, double perp2, double m, thx_lambda_rule rule,
                        double fixed, double target, int tsvd, int n_grid, int *kept, int *flags)
{
    int dummy = 0;
    if (!flags) flags = &dummy;
    *flags = 0;
    if (!(k > 0 && s[0] > 0)) {
        if (kept) *kept = 0;
        return rule == THX_LAMBDA_FIXED ? fixed : 0;
    }
    if (tsvd) return pick_tsvd(s, beta2, k, perp2, m, rule, fixed, target, n_grid, kept, flags);
    if (kept) *kept = 0;
    if (rule == THX_LAMBDA_FIXED) return fixed;
    if (n_grid < 3) n_grid = 200;
    double *grid = malloc((size_t)n_grid * sizeof *grid);
    if (!grid) return NAN;
    size_t n = thx_inv_grid(s, k, n_grid, grid);
    double lam = grid[n / 2];
    if (rule == THX_LAMBDA_DISCREPANCY) {
        /* ρ(λ) increases with λ: bisection in log λ */
        double r2, e2, lo = log(grid[0]), hi = log(grid[n - 1]);
        /* a target below the residual outside the matrix's range (the noise underestimated): the
         * in-range part of the residual is set to its expected share instead, k/m of target² */
        if (perp2 >= target * target && m > 0) target = sqrt(perp2 + target * target * (double)k / m);
        thx_inv_norms(s, beta2, k, perp2, grid[0], &r2, &e2);
        if (sqrt(r2) >= target) {
            lam = grid[0];
            *flags |= THX_LAMBDA_AT_LOW;
        } else {
            thx_inv_norms(s, beta2, k, perp2, grid[n - 1], &r2, &e2);
            if (sqrt(r2) <= target) {
                lam = grid[n - 1];
                *flags |= THX_LAMBDA_AT_HIGH;
            } else {
                for (int it = 0; it < 200 && hi - lo > 1e-12; it++) {
                    double mid = 0.5 * (lo + hi);
                    thx_inv_norms(s, beta2, k, perp2, exp(mid), &r2, &e2);
                    if (sqrt(r2) < target) lo = mid;
                    else hi = mid;
                }
                lam = exp(0.5 * (lo + hi));
            }
        }
        free(grid);
        return lam;
    }
    fn1 g = rule == THX_LAMBDA_LCURVE ? f_kappa : rule == THX_LAMBDA_CRESO ? f_creso : f_mgcv;
    double *v = malloc((n + 2 * k) * sizeof *v);
    if (!v) {
        free(grid);
        return NAN;
    }
    double *s2 = v + n, *xi2 = v + n + k;
    for (size_t i = 0; i < k; i++) {
        s2[i] = s[i] * s[i];
        xi2[i] = beta2[i] / s2[i];
    }
    spec q = {s2, beta2, xi2, k, perp2, m};
    for (size_t i = 0; i < n; i++) v[i] = g(&q, grid[i]);
    size_t at = 0;
    if (rule == THX_LAMBDA_CRESO) {
        /* the first local maximum met coming down from λ = s_1 (the largest-λ one): with a discrete
         * spectrum C also peaks near every small, noise-dominated singular value (docs/decisions.md);
         * the global maximum if C has none inside the grid */
        at = n;
        for (size_t i = n - 2; i >= 1; i--)
            if (v[i] > v[i + 1] && v[i] >= v[i - 1]) {
                at = i;
                break;
            }
        if (at == n) {
            *flags |= THX_LAMBDA_NO_CORNER;
            at = 0;
            for (size_t i = 1; i < n; i++)
                if (v[i] > v[at]) at = i;
        }
    } else {
        for (size_t i = 1; i < n; i++)
            if (v[i] > v[at]) at = i;
        /* the L-curve bends the wrong way everywhere (no corner): the most curved point is not one */
        if (rule == THX_LAMBDA_LCURVE && !(v[at] > 0)) *flags |= THX_LAMBDA_NO_CORNER;
    }
    if (at == 0) *flags |= THX_LAMBDA_AT_LOW;
    if (at + 1 == n) *flags |= THX_LAMBDA_AT_HIGH;
    if (at > 0 && at + 1 < n) lam = golden_max(g, &q, grid[at - 1], grid[at + 1]);
    else lam = grid[at];
    free(v);
    free(grid);
    return lam;
}
