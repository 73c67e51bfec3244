/*
 * Exact geometric predicates (see thorax/geom/predicates.h for the conventions).
 *
 * Each predicate first evaluates its determinant in plain floating point on
 * coordinate differences, together with a rigorous bound on the rounding
 * error of that evaluation (a "semi-static filter": the bound is a constant
 * times the permanent of the same expression, i.e. the expression with every
 * term replaced by its absolute value). If |det| exceeds the bound the sign
 * is certain and the float value is returned. Otherwise the determinant is
 * recomputed exactly with floating-point expansions (a value represented as
 * an unevaluated sum of doubles whose magnitudes do not overlap, built from
 * the error-free transformations two-sum and two-product), and the sign of
 * the largest component of the exact result is the exact sign.
 *
 * Error bounds. Treating the differences (a - d) as the leaves of the
 * expression tree, every monomial of the computed determinant carries at most
 * k factors (1 + delta_i), |delta_i| <= u = 2^-53, where k counts the
 * roundings on its path (each leaf difference counted as often as it occurs
 * in the monomial). Hence |computed - exact| <= gamma_k * P, where P is the
 * exact permanent, gamma_k = k u / (1 - k u), and the permanent computed in
 * floating point is at least P (1 - u)^k. (k + 1) u * P_computed therefore
 * bounds the error for every k used here (k <= 16): we use that, slightly
 * looser than the tightest published constants, which only costs a few more
 * exact evaluations in near-degenerate cases.
 *   orient2d: k = 4   orient3d: k = 8   incircle: k = 11   insphere: k = 16
 *
 * Exact evaluation: when all coordinate differences are exact in double (the
 * usual case for nearby points, e.g. grids), the determinant of the
 * differences is expanded exactly; otherwise the raw coordinates are used
 * (differences would round): each predicate is a determinant with a column of
 * ones, e.g. orient3d(a,b,c,d) = det[a 1; b 1; c 1; d 1], expanded by
 * cofactors into 2x2 minors x_p y_q - x_q y_p computed exactly.
 *
 * Assumptions: IEEE 754 binary64 with round-to-nearest-even, no extended
 * precision for intermediates (true on x86-64 SSE2 and AArch64), no
 * overflow or underflow (coordinates between about 1e-60 and 1e60 in
 * magnitude, or zero). Contraction of a*b+c into an FMA would break Dekker's
 * splitting, so two-product uses fma() when the compiler reports a fast FMA
 * (the only targets where contraction can happen) and Dekker's split
 * otherwise; GCC in ISO C mode (-std=c11, as this project builds) also sets
 * -ffp-contract=off.
 */
#include "thorax/geom/predicates.h"
#include <math.h>
#include <stddef.h>

#define U_EPS (1.0 / 9007199254740992.0) /* 2^-53, unit roundoff */

static const double orient2d_bound = 5.0 * U_EPS;
static const double orient3d_bound = 9.0 * U_EPS;
static const double incircle_bound = 12.0 * U_EPS;
static const double insphere_bound = 17.0 * U_EPS;

/* ---------------------------------------------------------------------------
 * Error-free transformations.
 * ------------------------------------------------------------------------- */

/* x + y == a + b exactly, x = fl(a + b). Valid for any a, b. */
static inline void two_sum(double a, double b, double *x, double *y)
{
    double s = a + b;
    double bv = s - a;
    double av = s - bv;
    *x = s;
    *y = (a - av) + (b - bv);
}

/* Same, requires |a| >= |b| (or a == 0). */
static inline void fast_two_sum(double a, double b, double *x, double *y)
{
    double s = a + b;
    *x = s;
    *y = b - (s - a);
}

#if defined(FP_FAST_FMA)
static inline void two_prod(double a, double b, double *x, double *y)
{
    double p = a * b;
    *x = p;
    *y = fma(a, b, -p);
}
#else
/* Dekker: splits a into two 26-bit halves so that partial products are exact. */
static inline void split(double a, double *hi, double *lo)
{
    const double splitter = 134217729.0; /* 2^27 + 1 */
    double c = splitter * a;
    double big = c - a;
    *hi = c - big;
    *lo = a - *hi;
}
static inline void two_prod(double a, double b, double *x, double *y)
{
    double p = a * b, ah, al, bh, bl;
    split(a, &ah, &al);
    split(b, &bh, &bl);
    *x = p;
    *y = al * bl - (((p - ah * bh) - al * bh) - ah * bl);
}
#endif

/* ---------------------------------------------------------------------------
 * Expansion arithmetic. An expansion is an array of doubles, smallest
 * magnitude first, nonoverlapping, with zero components eliminated; its value
 * is the exact sum. Lengths are ints; every buffer size below is the proven
 * maximum output length of the operation producing it.
 * ------------------------------------------------------------------------- */

/* h = e + f. h must hold elen + flen components; must not alias e or f.
 * Merge by magnitude, then one pass of two-sums (valid for strongly
 * nonoverlapping inputs, which all expansions produced here are). */
static int exp_sum(int elen, const double *e, int flen, const double *f, double *h)
{
    if (elen == 0) {
        for (int i = 0; i < flen; i++) h[i] = f[i];
        return flen;
    }
    if (flen == 0) {
        for (int i = 0; i < elen; i++) h[i] = e[i];
        return elen;
    }
    int ei = 0, fi = 0, hn = 0;
    double enow = e[0], fnow = f[0], q, qnew, hh;
    if ((fnow > enow) == (fnow > -enow)) { q = enow; enow = (++ei < elen) ? e[ei] : 0; }
    else { q = fnow; fnow = (++fi < flen) ? f[fi] : 0; }
    if (ei < elen && fi < flen) {
        if ((fnow > enow) == (fnow > -enow)) { fast_two_sum(enow, q, &qnew, &hh); enow = (++ei < elen) ? e[ei] : 0; }
        else { fast_two_sum(fnow, q, &qnew, &hh); fnow = (++fi < flen) ? f[fi] : 0; }
        q = qnew;
        if (hh != 0.0) h[hn++] = hh;
        while (ei < elen && fi < flen) {
            if ((fnow > enow) == (fnow > -enow)) { two_sum(q, enow, &qnew, &hh); enow = (++ei < elen) ? e[ei] : 0; }
            else { two_sum(q, fnow, &qnew, &hh); fnow = (++fi < flen) ? f[fi] : 0; }
            q = qnew;
            if (hh != 0.0) h[hn++] = hh;
        }
    }
    while (ei < elen) {
        two_sum(q, enow, &qnew, &hh);
        enow = (++ei < elen) ? e[ei] : 0;
        q = qnew;
        if (hh != 0.0) h[hn++] = hh;
    }
    while (fi < flen) {
        two_sum(q, fnow, &qnew, &hh);
        fnow = (++fi < flen) ? f[fi] : 0;
        q = qnew;
        if (hh != 0.0) h[hn++] = hh;
    }
    if (q != 0.0 || hn == 0) h[hn++] = q;
    if (hn == 1 && h[0] == 0.0) return 0;
    return hn;
}

/* h = b * e. h must hold 2 * elen components; must not alias e. */
static int exp_scale(int elen, const double *e, double b, double *h)
{
    if (elen == 0 || b == 0.0) return 0;
    int hn = 0;
    double q, hh, p1, p0, s;
    two_prod(e[0], b, &q, &hh);
    if (hh != 0.0) h[hn++] = hh;
    for (int i = 1; i < elen; i++) {
        two_prod(e[i], b, &p1, &p0);
        two_sum(q, p0, &s, &hh);
        if (hh != 0.0) h[hn++] = hh;
        fast_two_sum(p1, s, &q, &hh);
        if (hh != 0.0) h[hn++] = hh;
    }
    if (q != 0.0) h[hn++] = q;
    return hn;
}

/* h = e * f. h holds 2 * elen * flen; tmp and acc are scratch of the same size. */
static int exp_mul(int elen, const double *e, int flen, const double *f, double *h, double *tmp, double *acc)
{
    int hn = 0;
    for (int j = 0; j < flen; j++) {
        int tn = exp_scale(elen, e, f[j], tmp);
        int an = exp_sum(hn, h, tn, tmp, acc);
        for (int i = 0; i < an; i++) h[i] = acc[i];
        hn = an;
    }
    return hn;
}

static inline void negate(int n, double *e)
{
    for (int i = 0; i < n; i++) e[i] = -e[i];
}

/* Exact 2x2 minor p_x q_y - q_x p_y (at most 4 components). */
static int minor2(const double *p, const double *q, double *h)
{
    double x1, y1, x2, y2;
    two_prod(p[0], q[1], &x1, &y1);
    two_prod(q[0], p[1], &x2, &y2);
    /* Drop zero components so that expansions stay zero-free. */
    double e[2], f[2];
    int en = 0, fn = 0;
    if (y1 != 0.0) e[en++] = y1;
    if (x1 != 0.0) e[en++] = x1;
    if (y2 != 0.0) f[fn++] = -y2;
    if (x2 != 0.0) f[fn++] = -x2;
    return exp_sum(en, e, fn, f, h);
}

/* Exact orient2d of raw points: det[p 1; q 1; r 1] = pq + qr + rp with
 * 2x2 minors given (pq, qr, rp each <= 4 components); result <= 12. */
typedef struct { int n; double v[4]; } ex4;
typedef struct { int n; double v[12]; } ex12;

static void ex_minor(const double *p, const double *q, ex4 *out) { out->n = minor2(p, q, out->v); }

/* s1*A + s2*B + s3*C for 4-component minors; signs +-1. */
static void ex_tri(const ex4 *A, int sa, const ex4 *B, int sb, const ex4 *C, int sc, ex12 *out)
{
    double a[4], b[4], c[4], t[8];
    for (int i = 0; i < A->n; i++) a[i] = sa * A->v[i];
    for (int i = 0; i < B->n; i++) b[i] = sb * B->v[i];
    for (int i = 0; i < C->n; i++) c[i] = sc * C->v[i];
    int tn = exp_sum(A->n, a, B->n, b, t);
    out->n = exp_sum(tn, t, C->n, c, out->v);
}

static double ex_estimate(int n, const double *e)
{
    /* The largest component has the sign of the (nonoverlapping) expansion. */
    return n > 0 ? e[n - 1] : 0.0;
}

/* ---------------------------------------------------------------------------
 * orient2d
 * ------------------------------------------------------------------------- */

static double orient2d_exact(const double *a, const double *b, const double *c)
{
    ex4 ab, bc, ca;
    ex12 r;
    ex_minor(a, b, &ab);
    ex_minor(b, c, &bc);
    ex_minor(c, a, &ca);
    ex_tri(&ab, 1, &bc, 1, &ca, 1, &r);
    return ex_estimate(r.n, r.v);
}

double thx_orient2d(const double *a, const double *b, const double *c)
{
    double l = (a[0] - c[0]) * (b[1] - c[1]);
    double r = (a[1] - c[1]) * (b[0] - c[0]);
    double det = l - r, sum;
    if (l > 0.0) {
        if (r <= 0.0) return det;
        sum = l + r;
    } else if (l < 0.0) {
        if (r >= 0.0) return det;
        sum = -l - r;
    } else {
        return det; /* l is exactly 0 (a difference was 0): det = -r has the exact sign */
    }
    double bound = orient2d_bound * sum;
    if (det > bound || -det > bound) return det;
    return orient2d_exact(a, b, c);
}

/* ---------------------------------------------------------------------------
 * orient3d
 * ------------------------------------------------------------------------- */

/* Exact det[p 1; q 1; r 1; s 1] (x, y, z columns) from the six xy minors of
 * p, q, r, s. Result <= 96 components. */
static int det4_raw(const double *p, const double *q, const double *r, const double *s, const ex4 *pq,
                    const ex4 *pr, const ex4 *ps, const ex4 *qr, const ex4 *qs, const ex4 *rs, double *out)
{
    /* = z_p M(qrs) - z_q M(prs) + z_r M(pqs) - z_s M(pqr), M = orient2d raw. */
    ex12 m_qrs, m_prs, m_pqs, m_pqr;
    ex_tri(qr, 1, rs, 1, qs, -1, &m_qrs);
    ex_tri(pr, 1, rs, 1, ps, -1, &m_prs);
    ex_tri(pq, 1, qs, 1, ps, -1, &m_pqs);
    ex_tri(pq, 1, qr, 1, pr, -1, &m_pqr);
    double t1[24], t2[24], t3[24], t4[24], u1[48], u2[48];
    int n1 = exp_scale(m_qrs.n, m_qrs.v, p[2], t1);
    int n2 = exp_scale(m_prs.n, m_prs.v, -q[2], t2);
    int n3 = exp_scale(m_pqs.n, m_pqs.v, r[2], t3);
    int n4 = exp_scale(m_pqr.n, m_pqr.v, -s[2], t4);
    int m1 = exp_sum(n1, t1, n2, t2, u1);
    int m2 = exp_sum(n3, t3, n4, t4, u2);
    return exp_sum(m1, u1, m2, u2, out);
}

static double orient3d_exact(const double *a, const double *b, const double *c, const double *d)
{
    ex4 ab, ac, ad, bc, bd, cd;
    ex_minor(a, b, &ab);
    ex_minor(a, c, &ac);
    ex_minor(a, d, &ad);
    ex_minor(b, c, &bc);
    ex_minor(b, d, &bd);
    ex_minor(c, d, &cd);
    double r[96];
    int n = det4_raw(a, b, c, d, &ab, &ac, &ad, &bc, &bd, &cd, r);
    return ex_estimate(n, r);
}

static int orient3d_diff(const double *a, const double *b, const double *c, const double *d, double *r);

double thx_orient3d(const double *a, const double *b, const double *c, const double *d)
{
    double adx = a[0] - d[0], ady = a[1] - d[1], adz = a[2] - d[2];
    double bdx = b[0] - d[0], bdy = b[1] - d[1], bdz = b[2] - d[2];
    double cdx = c[0] - d[0], cdy = c[1] - d[1], cdz = c[2] - d[2];
    double bdxcdy = bdx * cdy, cdxbdy = cdx * bdy;
    double cdxady = cdx * ady, adxcdy = adx * cdy;
    double adxbdy = adx * bdy, bdxady = bdx * ady;
    double det = adz * (bdxcdy - cdxbdy) + bdz * (cdxady - adxcdy) + cdz * (adxbdy - bdxady);
    double perm = (fabs(bdxcdy) + fabs(cdxbdy)) * fabs(adz) + (fabs(cdxady) + fabs(adxcdy)) * fabs(bdz) +
                  (fabs(adxbdy) + fabs(bdxady)) * fabs(cdz);
    double bound = orient3d_bound * perm;
    if (det > bound || -det > bound) return det;
    double r;
    if (orient3d_diff(a, b, c, d, &r)) return r;
    return orient3d_exact(a, b, c, d);
}

/* ---------------------------------------------------------------------------
 * incircle
 * ------------------------------------------------------------------------- */

/* Exact lift x^2 + y^2 (<= 4 components) or x^2 + y^2 + z^2 (<= 6). */
static int lift_exact(const double *p, int dim, double *out)
{
    double h[6], t[6], sq[2];
    int hn = 0;
    for (int k = 0; k < dim; k++) {
        two_prod(p[k], p[k], &sq[1], &sq[0]);
        int sn = (sq[0] != 0.0) ? 2 : (sq[1] != 0.0 ? 1 : 0);
        const double *sp = (sn == 2) ? sq : sq + 1;
        int tn = exp_sum(hn, h, sn, sp, t);
        for (int i = 0; i < tn; i++) h[i] = t[i];
        hn = tn;
    }
    for (int i = 0; i < hn; i++) out[i] = h[i];
    return hn;
}

/* ---------------------------------------------------------------------------
 * Shortcut for the common degenerate case of nearby points (grids): when
 * every coordinate difference to the last point is exact in double, the
 * determinant of the differences is evaluated exactly directly, with much
 * shorter expansions than the raw-coordinate form.
 * ------------------------------------------------------------------------- */

/* d[k] = p[k] - q[k] for k < dim; returns 1 iff all are exact. */
static int exact_diffs(const double *p, const double *q, int dim, double *d)
{
    for (int k = 0; k < dim; k++) {
        double x, y;
        two_sum(p[k], -q[k], &x, &y);
        if (y != 0.0) return 0;
        d[k] = x;
    }
    return 1;
}

/* Exact det[A; B; C] of single-double 3-vectors (<= 24 components). */
static int det3_single(const double *A, const double *B, const double *C, double *out)
{
    double bc[4], ca[4], ab[4], t1[8], t2[8], t3[8], u[16];
    int nbc = minor2(B, C, bc), nca = minor2(C, A, ca), nab = minor2(A, B, ab);
    int n1 = exp_scale(nbc, bc, A[2], t1), n2 = exp_scale(nca, ca, B[2], t2), n3 = exp_scale(nab, ab, C[2], t3);
    int nu = exp_sum(n1, t1, n2, t2, u);
    return exp_sum(nu, u, n3, t3, out);
}

/* Returns 1 and the exact sign estimate in *r if the shortcut applies. */
static int orient3d_diff(const double *a, const double *b, const double *c, const double *d, double *r)
{
    double A[3], B[3], C[3], out[24];
    if (!exact_diffs(a, d, 3, A) || !exact_diffs(b, d, 3, B) || !exact_diffs(c, d, 3, C)) return 0;
    int n = det3_single(A, B, C, out);
    *r = ex_estimate(n, out);
    return 1;
}

static int incircle_diff(const double *a, const double *b, const double *c, const double *d, double *r)
{
    double A[2], B[2], C[2];
    if (!exact_diffs(a, d, 2, A) || !exact_diffs(b, d, 2, B) || !exact_diffs(c, d, 2, C)) return 0;
    /* alift (B x C) + blift (C x A) + clift (A x B) */
    const double *P[3] = {A, B, C};
    double acc[96], acc2[96], term[32], tmp[32], scratch[32];
    int an = 0;
    for (int i = 0; i < 3; i++) {
        double mn[4], lift[4];
        int mnn = minor2(P[(i + 1) % 3], P[(i + 2) % 3], mn);
        int ln = lift_exact(P[i], 2, lift);
        int tn = exp_mul(mnn, mn, ln, lift, term, tmp, scratch);
        int n2 = exp_sum(an, acc, tn, term, acc2);
        for (int k = 0; k < n2; k++) acc[k] = acc2[k];
        an = n2;
    }
    *r = ex_estimate(an, acc);
    return 1;
}

static int insphere_diff(const double *a, const double *b, const double *c, const double *d, const double *e,
                         double *r)
{
    double A[3], B[3], C[3], D[3];
    if (!exact_diffs(a, e, 3, A) || !exact_diffs(b, e, 3, B) || !exact_diffs(c, e, 3, C) ||
        !exact_diffs(d, e, 3, D))
        return 0;
    /* -alift det[B;C;D] + blift det[A;C;D] - clift det[A;B;D] + dlift det[A;B;C] */
    const double *P[4] = {A, B, C, D};
    double acc[1152], acc2[1152], m3[24], term[288], tmp[48], scratch[288];
    int an = 0;
    for (int skip = 0; skip < 4; skip++) {
        const double *q[3];
        for (int i = 0, k = 0; i < 4; i++)
            if (i != skip) q[k++] = P[i];
        int mn = det3_single(q[0], q[1], q[2], m3);
        double lift[6];
        int ln = lift_exact(P[skip], 3, lift);
        if (skip == 0 || skip == 2) negate(ln, lift);
        int tn = exp_mul(mn, m3, ln, lift, term, tmp, scratch);
        int n2 = exp_sum(an, acc, tn, term, acc2);
        for (int k = 0; k < n2; k++) acc[k] = acc2[k];
        an = n2;
    }
    *r = ex_estimate(an, acc);
    return 1;
}

static double incircle_exact(const double *a, const double *b, const double *c, const double *d)
{
    /* det[x y lift 1] over rows a, b, c, d, expanded along the lift column:
     * lift_a M(bcd) - lift_b M(acd) + lift_c M(abd) - lift_d M(abc). */
    ex4 ab, ac, ad, bc, bd, cd;
    ex_minor(a, b, &ab);
    ex_minor(a, c, &ac);
    ex_minor(a, d, &ad);
    ex_minor(b, c, &bc);
    ex_minor(b, d, &bd);
    ex_minor(c, d, &cd);
    ex12 m[4];
    ex_tri(&bc, 1, &cd, 1, &bd, -1, &m[0]); /* M(bcd) */
    ex_tri(&ac, 1, &cd, 1, &ad, -1, &m[1]); /* M(acd) */
    ex_tri(&ab, 1, &bd, 1, &ad, -1, &m[2]); /* M(abd) */
    ex_tri(&ab, 1, &bc, 1, &ac, -1, &m[3]); /* M(abc) */
    const double *pts[4] = {a, b, c, d};
    double acc[384], acc2[384], term[96], tmp[96], scratch[96];
    int an = 0;
    for (int i = 0; i < 4; i++) {
        double lift[4];
        int ln = lift_exact(pts[i], 2, lift);
        if (i & 1) negate(ln, lift);
        int tn = exp_mul(m[i].n, m[i].v, ln, lift, term, tmp, scratch);
        int n2 = exp_sum(an, acc, tn, term, acc2);
        for (int k = 0; k < n2; k++) acc[k] = acc2[k];
        an = n2;
    }
    return ex_estimate(an, acc);
}

double thx_incircle(const double *a, const double *b, const double *c, const double *d)
{
    double adx = a[0] - d[0], ady = a[1] - d[1];
    double bdx = b[0] - d[0], bdy = b[1] - d[1];
    double cdx = c[0] - d[0], cdy = c[1] - d[1];
    double bdxcdy = bdx * cdy, cdxbdy = cdx * bdy;
    double cdxady = cdx * ady, adxcdy = adx * cdy;
    double adxbdy = adx * bdy, bdxady = bdx * ady;
    double alift = adx * adx + ady * ady;
    double blift = bdx * bdx + bdy * bdy;
    double clift = cdx * cdx + cdy * cdy;
    double det = alift * (bdxcdy - cdxbdy) + blift * (cdxady - adxcdy) + clift * (adxbdy - bdxady);
    double perm = (fabs(bdxcdy) + fabs(cdxbdy)) * alift + (fabs(cdxady) + fabs(adxcdy)) * blift +
                  (fabs(adxbdy) + fabs(bdxady)) * clift;
    double bound = incircle_bound * perm;
    if (det > bound || -det > bound) return det;
    double r;
    if (incircle_diff(a, b, c, d, &r)) return r;
    return incircle_exact(a, b, c, d);
}

/* ---------------------------------------------------------------------------
 * insphere
 * ------------------------------------------------------------------------- */

static double insphere_exact(const double *a, const double *b, const double *c, const double *d, const double *e)
{
    /* det[x y z lift 1] over rows a..e, expanded along the lift column:
     * -lift_a O(bcde) + lift_b O(acde) - lift_c O(abde) + lift_d O(abce) - lift_e O(abcd),
     * O = det[x y z 1] of four raw points. */
    const double *P[5] = {a, b, c, d, e};
    ex4 mn[5][5]; /* mn[i][j], i < j: xy minor of P[i], P[j] */
    for (int i = 0; i < 5; i++)
        for (int j = i + 1; j < 5; j++) ex_minor(P[i], P[j], &mn[i][j]);
    static const double sgn[5] = {-1.0, 1.0, -1.0, 1.0, -1.0};
    double acc[5760], acc2[5760], o[96], term[1152], tmp[1152], scratch[1152];
    int an = 0;
    for (int skip = 0; skip < 5; skip++) {
        int q[4], k = 0;
        for (int i = 0; i < 5; i++)
            if (i != skip) q[k++] = i;
        int on = det4_raw(P[q[0]], P[q[1]], P[q[2]], P[q[3]], &mn[q[0]][q[1]], &mn[q[0]][q[2]], &mn[q[0]][q[3]],
                          &mn[q[1]][q[2]], &mn[q[1]][q[3]], &mn[q[2]][q[3]], o);
        double lift[6];
        int ln = lift_exact(P[skip], 3, lift);
        if (sgn[skip] < 0) negate(ln, lift);
        int tn = exp_mul(on, o, ln, lift, term, tmp, scratch);
        int n2 = exp_sum(an, acc, tn, term, acc2);
        for (int i = 0; i < n2; i++) acc[i] = acc2[i];
        an = n2;
    }
    return ex_estimate(an, acc);
}

double thx_insphere(const double *a, const double *b, const double *c, const double *d, const double *e)
{
    double aex = a[0] - e[0], aey = a[1] - e[1], aez = a[2] - e[2];
    double bex = b[0] - e[0], bey = b[1] - e[1], bez = b[2] - e[2];
    double cex = c[0] - e[0], cey = c[1] - e[1], cez = c[2] - e[2];
    double dex = d[0] - e[0], dey = d[1] - e[1], dez = d[2] - e[2];
    double aexbey = aex * bey, bexaey = bex * aey;
    double bexcey = bex * cey, cexbey = cex * bey;
    double cexdey = cex * dey, dexcey = dex * cey;
    double dexaey = dex * aey, aexdey = aex * dey;
    double aexcey = aex * cey, cexaey = cex * aey;
    double bexdey = bex * dey, dexbey = dex * bey;
    double ab = aexbey - bexaey, bc = bexcey - cexbey, cd = cexdey - dexcey;
    double da = dexaey - aexdey, ac = aexcey - cexaey, bd = bexdey - dexbey;
    /* 3x3 determinants of the xyz differences: abc = det[ae; be; ce] etc. */
    double abc = aez * bc - bez * ac + cez * ab;
    double bcd = bez * cd - cez * bd + dez * bc;
    double cda = cez * da + dez * ac + aez * cd;
    double dab = dez * ab + aez * bd + bez * da;
    double alift = aex * aex + aey * aey + aez * aez;
    double blift = bex * bex + bey * bey + bez * bez;
    double clift = cex * cex + cey * cey + cez * cez;
    double dlift = dex * dex + dey * dey + dez * dez;
    double det = (dlift * abc - clift * dab) + (blift * cda - alift * bcd);

    double aezp = fabs(aez), bezp = fabs(bez), cezp = fabs(cez), dezp = fabs(dez);
    double abp = fabs(aexbey) + fabs(bexaey), bcp = fabs(bexcey) + fabs(cexbey);
    double cdp = fabs(cexdey) + fabs(dexcey), dap = fabs(dexaey) + fabs(aexdey);
    double acp = fabs(aexcey) + fabs(cexaey), bdp = fabs(bexdey) + fabs(dexbey);
    double perm = (cdp * bezp + bdp * cezp + bcp * dezp) * alift + (dap * cezp + acp * dezp + cdp * aezp) * blift +
                  (abp * dezp + bdp * aezp + dap * bezp) * clift + (bcp * aezp + acp * bezp + abp * cezp) * dlift;
    double bound = insphere_bound * perm;
    if (det > bound || -det > bound) return det;
    double r;
    if (insphere_diff(a, b, c, d, e, &r)) return r;
    return insphere_exact(a, b, c, d, e);
}

/* The segments touch if each one's ends are on opposite sides of (or on) the other's line; a
 * zero orientation puts an end on the other segment's line, where a box test settles it. */
static int on_box(const double *a, const double *b, const double *p)
{
    return fmin(a[0], b[0]) <= p[0] && p[0] <= fmax(a[0], b[0]) && fmin(a[1], b[1]) <= p[1] && p[1] <= fmax(a[1], b[1]);
}

int thx_segments_touch(const double *p0, const double *p1, const double *q0, const double *q1)
{
    double d1 = thx_orient2d(q0, q1, p0), d2 = thx_orient2d(q0, q1, p1);
    double d3 = thx_orient2d(p0, p1, q0), d4 = thx_orient2d(p0, p1, q1);
    if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0))) return 1;
    return (d1 == 0 && on_box(q0, q1, p0)) || (d2 == 0 && on_box(q0, q1, p1)) || (d3 == 0 && on_box(p0, p1, q0)) ||
           (d4 == 0 && on_box(p0, p1, q1));
}
