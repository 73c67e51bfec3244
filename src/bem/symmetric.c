/* The symmetric (Galerkin) boundary-element method for dipoles in nested compartments
 * (thorax/bem/bem.h, thx_bem_dipoles with THX_BEM_SYMMETRIC; docs/decisions.md, "Symmetric
 * boundary elements").
 *
 * Unknowns: the potential V on every surface (linear on each triangle, one value a node) and the
 * normal current p = sigma dV/dn on every surface but the outermost (constant on each triangle);
 * outside the outermost surface nothing conducts, so p = 0 there. For a compartment c (the inside
 * of a surface minus the insides of its children) with conductivity sigma_c, s_{c,k} = +1 when
 * surface k is c's outer boundary and -1 when it is an inner one, Green's representation gives
 *     u_c = v_c / sigma_c + sum_{k in dc} s_{c,k} [ S_k p_k / sigma_c - D_k V_k ]
 * (V in c, 0 outside it; v_c the potential of c's sources in a unit-conductivity infinite medium,
 * S_k and D_k the single- and double-layer potentials of surface k, G = 1/(4 pi r)). The jump of
 * u_in - u_out and of sigma_in du_in/dn - sigma_out du_out/dn across surface i vanish; written
 * with the principal values the jump terms cancel, and for every pair of surfaces (i, k) that
 * bound a common compartment c:
 *     Dirichlet row of surface i (tested by each triangle's indicator):
 *       sum_k sum_c s_ci s_ck [ S_ik p_k / sigma_c - D_ik V_k ] = - sum_c s_ci v_c / sigma_c
 *     Neumann row (tested by each node's hat function):
 *       sum_k sum_c s_ci s_ck [ sigma_c N_ik V_k - D*_ik p_k ]  =   sum_c s_ci dv_c/dn
 * with N = d/dn D the hypersingular operator. Tested by Galerkin the matrix is symmetric
 * (<psi, D phi> = <D* psi, phi>); N by Nedelec's integration by parts,
 *     <phi_a, N phi_b> = - int int G(x - y) (n x grad phi_a)(x) . (n x grad phi_b)(y),
 * so that every block comes from two kinds of triangle-pair integrals: the constant single layer
 * SS_TT' = int_T int_T' G and the double layer of the hat functions int_T int_T' dG/dn_y h_j.
 * The inner integral is analytic (thx_bem_triangle) for near pairs, a 7- or 3-point rule for far
 * ones; the outer one a 12- or 7-point rule. The constant potential (V = 1 everywhere, p = 0) is
 * the one null vector; it is deflated by alpha w w^T on the outer surface's block (w the hat
 * functions' integrals), which fixes the area-weighted mean of V on the outer surface to 0. */
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bem/bem_impl.h"

/* pairs nearer than NEAR_ANALYTIC times the larger diameter: analytic inner integral, a 12-point
 * outer rule below NEAR_FINE diameters, 7 points above; numerical 7 x 7 points below FAR, 3 x 3
 * beyond (the thresholds chosen against the analytic 12-point values; each rule's exactness on
 * the polynomials of its degree: tests/test_bem_quadrature.c, over thx_bem_quad_rules) */
#define NEAR_FINE 1.5
#define NEAR_ANALYTIC 2.5
#define FAR 4.0

typedef struct {
    double x[3], w, l[3]; /* point, weight times area, barycentric coordinates */
} qpt;

typedef struct {
    const double *v[3];
    double n[3], area, c[3], diam;
    double curl[3][3]; /* n x grad h_j (constant on the triangle) */
    int surf;
    int32_t node[3]; /* global node indices (unknowns) */
    qpt q3[3], q7[7];
} tri;

/* Dunavant's rules: barycentric coordinates and weights */
static const double R3[3][4] = {{2. / 3, 1. / 6, 1. / 6, 1. / 3}, {1. / 6, 2. / 3, 1. / 6, 1. / 3}, {1. / 6, 1. / 6, 2. / 3, 1. / 3}};
#define A7 0.059715871789770
#define B7 0.470142064105115
#define C7 0.797426985353087
#define D7 0.101286507323456
#define W7A 0.132394152788506
#define W7B 0.125939180544827
static const double R7[7][4] = {{1. / 3, 1. / 3, 1. / 3, 0.225},
                                {A7, B7, B7, W7A}, {B7, A7, B7, W7A}, {B7, B7, A7, W7A},
                                {C7, D7, D7, W7B}, {D7, C7, D7, W7B}, {D7, D7, C7, W7B}};
#define A12 0.873821971016996
#define B12 0.063089014491502
#define C12 0.501426509658179
#define D12 0.249286745170910
#define E12 0.636502499121399
#define F12 0.310352451033785
#define G12 0.053145049844816
#define W12A 0.050844906370207
#define W12B 0.116786275726379
#define W12C 0.082851075618374
static const double R12[12][4] = {
    {A12, B12, B12, W12A}, {B12, A12, B12, W12A}, {B12, B12, A12, W12A},
    {C12, D12, D12, W12B}, {D12, C12, D12, W12B}, {D12, D12, C12, W12B},
    {E12, F12, G12, W12C}, {E12, G12, F12, W12C}, {F12, E12, G12, W12C},
    {F12, G12, E12, W12C}, {G12, E12, F12, W12C}, {G12, F12, E12, W12C}};

const thx_bem_quad_rule thx_bem_quad_rules[] = {
    {"3-point (interior, Strang-Fix)", 3, 2, R3},
    {"7-point (Dunavant)", 7, 5, R7},
    {"12-point (Dunavant)", 12, 6, R12},
    {"3-point (edge midpoints, solve.c)", 3, 2, thx_bem_edge_midpoints},
    {NULL, 0, 0, NULL}};

static void rule(const tri *t, const double (*r)[4], int m, qpt *q)
{
    for (int i = 0; i < m; i++) {
        for (int k = 0; k < 3; k++) {
            q[i].x[k] = r[i][0] * t->v[0][k] + r[i][1] * t->v[1][k] + r[i][2] * t->v[2][k];
            q[i].l[k] = r[i][k];
        }
        q[i].w = r[i][3] * t->area;
    }
}

static double dist(const double *a, const double *b)
{
    double d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
    return sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
}

static void tri_init(tri *t, const double *a, const double *b, const double *c)
{
    t->v[0] = a, t->v[1] = b, t->v[2] = c;
    double e1[3], e2[3], nn[3];
    for (int k = 0; k < 3; k++) e1[k] = b[k] - a[k], e2[k] = c[k] - a[k], t->c[k] = (a[k] + b[k] + c[k]) / 3;
    nn[0] = e1[1] * e2[2] - e1[2] * e2[1];
    nn[1] = e1[2] * e2[0] - e1[0] * e2[2];
    nn[2] = e1[0] * e2[1] - e1[1] * e2[0];
    double l = sqrt(nn[0] * nn[0] + nn[1] * nn[1] + nn[2] * nn[2]);
    t->area = l / 2;
    for (int k = 0; k < 3; k++) t->n[k] = l > 0 ? nn[k] / l : 0;
    t->diam = fmax(dist(a, b), fmax(dist(b, c), dist(c, a)));
    /* n x grad h_j = n x (n x e_j)/(2A) = -e_j/(2A), e_j = v_{j+2} - v_{j+1} (in the plane) */
    for (int j = 0; j < 3; j++)
        for (int k = 0; k < 3; k++)
            t->curl[j][k] = l > 0 ? (t->v[(j + 1) % 3][k] - t->v[(j + 2) % 3][k]) / l : 0;
    rule(t, R3, 3, t->q3);
    rule(t, R7, 7, t->q7);
}

/* Which corner of t node a is (a must be one of its three). */
static int corner(const tri *t, size_t a)
{
    return t->node[0] == (int32_t)a ? 0 : t->node[1] == (int32_t)a ? 1 : 2;
}

/* int_T int_T' G (ss) and int_T int_T' dG(x - y)/dn_y h_j(y) (dd[j]) for the pair (T, T'). */
static void pair_integrals(const tri *T, const qpt *q12, const tri *U, double *ss, double dd[3])
{
    double s = 0, d0 = 0, d1 = 0, d2 = 0;
    double rho = dist(T->c, U->c) / fmax(T->diam, U->diam);
    if (rho < NEAR_ANALYTIC) {
        const qpt *q = rho < NEAR_FINE ? q12 : T->q7;
        int m = rho < NEAR_FINE ? 12 : 7;
        for (int i = 0; i < m; i++) {
            double dl[3], sl[3];
            thx_bem_triangle(q[i].x, U->v[0], U->v[1], U->v[2], dl, sl);
            s += q[i].w * (sl[0] + sl[1] + sl[2]);
            /* dG/dn_y = -n.(y - x)/(4 pi |y - x|^3): the analytic dl carries n.(y - x)/|y - x|^3 */
            d0 -= q[i].w * dl[0];
            d1 -= q[i].w * dl[1];
            d2 -= q[i].w * dl[2];
        }
    } else {
        const qpt *p = rho < FAR ? T->q7 : T->q3, *q = rho < FAR ? U->q7 : U->q3;
        int m = rho < FAR ? 7 : 3;
        const double *n = U->n;
        for (int i = 0; i < m; i++)
            for (int j = 0; j < m; j++) {
                double r[3] = {q[j].x[0] - p[i].x[0], q[j].x[1] - p[i].x[1], q[j].x[2] - p[i].x[2]};
                double inv = 1 / sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
                double w = p[i].w * q[j].w;
                s += w * inv;
                double k = -w * (n[0] * r[0] + n[1] * r[1] + n[2] * r[2]) * inv * inv * inv;
                d0 += k * q[j].l[0];
                d1 += k * q[j].l[1];
                d2 += k * q[j].l[2];
            }
    }
    const double f = 1 / (4 * M_PI);
    *ss = s * f;
    dd[0] = d0 * f, dd[1] = d1 * f, dd[2] = d2 * f;
}

/* The potential v of a unit-conductivity dipole (p, q) and its gradient at x. */
static double dipole_v(const double *x, const double *p, const double *q, double g[3])
{
    double R[3] = {x[0] - p[0], x[1] - p[1], x[2] - p[2]};
    double r2 = R[0] * R[0] + R[1] * R[1] + R[2] * R[2], r = sqrt(r2), r3 = r2 * r;
    double qr = q[0] * R[0] + q[1] * R[1] + q[2] * R[2];
    for (int k = 0; k < 3; k++) g[k] = (q[k] / r3 - 3 * qr * R[k] / (r3 * r2)) / (4 * M_PI);
    return qr / (4 * M_PI * r3);
}

/* int_T v (out[0]) and int_T h_j dv/dn (out[1 + j]) over the sub-triangle with barycentric
 * corners L[0..2] of T, subdivided where the dipole is near (adaptive, 7-point leaves). */
static void source_integrals(const tri *T, const double L[3][3], const double *p, const double *q, int depth, double out[4])
{
    double x[3][3], c[3], h = 0;
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++) x[i][k] = L[i][0] * T->v[0][k] + L[i][1] * T->v[1][k] + L[i][2] * T->v[2][k];
    for (int k = 0; k < 3; k++) c[k] = (x[0][k] + x[1][k] + x[2][k]) / 3;
    for (int i = 0; i < 3; i++) h = fmax(h, dist(x[i], x[(i + 1) % 3]));
    if (depth < 10 && h > 0.3 * dist(c, p)) {
        double M[3][3]; /* edge midpoints 01, 12, 20 */
        for (int i = 0; i < 3; i++)
            for (int k = 0; k < 3; k++) M[i][k] = (L[i][k] + L[(i + 1) % 3][k]) / 2;
        double S[4][3][3];
        for (int k = 0; k < 3; k++) {
            S[0][0][k] = L[0][k], S[0][1][k] = M[0][k], S[0][2][k] = M[2][k];
            S[1][0][k] = M[0][k], S[1][1][k] = L[1][k], S[1][2][k] = M[1][k];
            S[2][0][k] = M[2][k], S[2][1][k] = M[1][k], S[2][2][k] = L[2][k];
            S[3][0][k] = M[0][k], S[3][1][k] = M[1][k], S[3][2][k] = M[2][k];
        }
        for (int s = 0; s < 4; s++) source_integrals(T, (const double(*)[3])S[s], p, q, depth + 1, out);
        return;
    }
    double area = T->area / (double)(1u << (2 * depth));
    for (int i = 0; i < 7; i++) {
        double l[3], y[3], g[3];
        for (int k = 0; k < 3; k++) l[k] = R7[i][0] * L[0][k] + R7[i][1] * L[1][k] + R7[i][2] * L[2][k];
        for (int k = 0; k < 3; k++) y[k] = l[0] * T->v[0][k] + l[1] * T->v[1][k] + l[2] * T->v[2][k];
        double w = R7[i][3] * area;
        double v = dipole_v(y, p, q, g);
        double dn = g[0] * T->n[0] + g[1] * T->n[1] + g[2] * T->n[2];
        out[0] += w * v;
        for (int j = 0; j < 3; j++) out[1 + j] += w * l[j] * dn;
    }
}

/* s_{c,k}: +1 when surface k is compartment c's outer boundary, -1 an inner one, 0 neither
 * (compartment c is the inside of surface c; the outside of the outermost conducts nothing). */
static int side(const thx_bem *b, size_t c, size_t k)
{
    if (c == k) return 1;
    if (b->parent[k] == (int)c) return -1;
    return 0;
}

/* Coefficients of the pair of surfaces (i, k): sum over their common compartments of
 * s_ci s_ck / sigma_c, s_ci s_ck sigma_c, s_ci s_ck. Returns 0 when they bound none together. */
static int pair_coef(const thx_bem *b, size_t i, size_t k, double *cs, double *cn, double *cd)
{
    *cs = *cn = *cd = 0;
    int any = 0;
    int cand[2] = {(int)i, b->parent[i]};
    for (int m = 0; m < 2; m++) {
        if (cand[m] < 0) continue;
        size_t c = (size_t)cand[m];
        int si = side(b, c, i), sk = side(b, c, k);
        if (!si || !sk) continue;
        double sig = b->sig_in[c];
        *cs += si * sk / sig;
        *cn += si * sk * sig;
        *cd += si * sk;
        any = 1;
    }
    return any;
}

/* The discrete problem's layout and coefficients, shared by the serial and the distributed paths. */
typedef struct {
    size_t S, N, nt, np, n; /* surfaces, nodes, triangles, current unknowns, all unknowns */
    tri *T;
    qpt *q12;               /* 12 points a triangle (outer rule of near pairs) */
    long *pidx;             /* each triangle's current unknown, -1 on the outer surface */
    size_t *toff;           /* S + 1: first triangle of each surface */
    unsigned char *share;   /* S x S: the two surfaces bound a common compartment */
    double *cS, *cN, *cD;   /* S x S coefficients (pair_coef) */
    size_t *star_off, *star; /* node -> its triangles (ascending) */
    double alpha;           /* deflation */
} sym;

static void sym_free(sym *s)
{
    free(s->T);
    free(s->q12);
    free(s->pidx);
    free(s->toff);
    free(s->share);
    free(s->cS);
    free(s->cN);
    free(s->cD);
    free(s->star_off);
    free(s->star);
    memset(s, 0, sizeof *s);
}

static thx_status sym_init(thx_ctx *ctx, const thx_bem *b, sym *s)
{
    memset(s, 0, sizeof *s);
    const size_t S = b->n, N = b->off[S];
    size_t nt = 0, np = 0;
    for (size_t k = 0; k < S; k++) {
        nt += b->surf[k]->n_tris;
        if (k != b->outer) np += b->surf[k]->n_tris;
    }
    s->S = S, s->N = N, s->nt = nt, s->np = np, s->n = N + np;
    if (s->n > 46000)
        return thx_error(ctx, THX_EINPUT, "bem: symmetric method: %zu unknowns (%zu nodes, %zu current triangles) would "
                         "need %.0f GB for the dense system; use fewer nodes", s->n, N, np,
                         8.0 * (double)s->n * (double)s->n / 1e9);
    s->T = thx_calloc(ctx, nt ? nt : 1, sizeof *s->T);
    s->q12 = thx_malloc(ctx, 12 * (nt ? nt : 1) * sizeof *s->q12);
    s->pidx = thx_malloc(ctx, (nt ? nt : 1) * sizeof *s->pidx);
    s->toff = thx_malloc(ctx, (S + 1) * sizeof *s->toff);
    s->share = thx_calloc(ctx, S * S, 1);
    s->cS = thx_calloc(ctx, S * S, sizeof *s->cS);
    s->cN = thx_calloc(ctx, S * S, sizeof *s->cN);
    s->cD = thx_calloc(ctx, S * S, sizeof *s->cD);
    s->star_off = thx_calloc(ctx, N + 1, sizeof *s->star_off);
    s->star = thx_malloc(ctx, (3 * nt + 1) * sizeof *s->star);
    size_t *fill = thx_calloc(ctx, N ? N : 1, sizeof *fill);
    if (!s->T || !s->q12 || !s->pidx || !s->toff || !s->share || !s->cS || !s->cN || !s->cD || !s->star_off ||
        !s->star || !fill) {
        free(fill);
        sym_free(s);
        return THX_ENOMEM;
    }
    size_t t = 0, p = 0;
    for (size_t k = 0; k < S; k++) {
        const thx_surface *f = b->surf[k];
        s->toff[k] = t;
        for (size_t j = 0; j < f->n_tris; j++, t++) {
            const int32_t *v = f->tri + 3 * j;
            tri_init(&s->T[t], f->xyz + 3 * v[0], f->xyz + 3 * v[1], f->xyz + 3 * v[2]);
            rule(&s->T[t], R12, 12, s->q12 + 12 * t);
            s->T[t].surf = (int)k;
            for (int m = 0; m < 3; m++) s->T[t].node[m] = (int32_t)(b->off[k] + (size_t)v[m]);
            s->pidx[t] = k == b->outer ? -1 : (long)(N + p++);
        }
    }
    s->toff[S] = t;
    for (size_t i = 0; i < nt; i++)
        for (int m = 0; m < 3; m++) s->star_off[s->T[i].node[m] + 1]++;
    for (size_t a = 0; a < N; a++) s->star_off[a + 1] += s->star_off[a];
    for (size_t i = 0; i < nt; i++)
        for (int m = 0; m < 3; m++) {
            size_t a = (size_t)s->T[i].node[m];
            s->star[s->star_off[a] + fill[a]++] = i;
        }
    free(fill);
    for (size_t i = 0; i < S; i++)
        for (size_t k = 0; k < S; k++)
            s->share[i * S + k] =
                (unsigned char)pair_coef(b, i, k, &s->cS[i * S + k], &s->cN[i * S + k], &s->cD[i * S + k]);
    return THX_OK;
}

/* The symmetric single layer of the pair (the mean of the two outer rules; a + b = b + a exactly,
 * so both paths get the same bits) and the two double layers: dd_tu with t tested, u inner. */
static double pair_sym(const sym *s, size_t t, size_t u, double dd_tu[3], double dd_ut[3])
{
    double a, c, x[3], y[3];
    pair_integrals(&s->T[t], s->q12 + 12 * t, &s->T[u], &a, dd_tu ? dd_tu : x);
    pair_integrals(&s->T[u], s->q12 + 12 * u, &s->T[t], &c, dd_ut ? dd_ut : y);
    return 0.5 * (a + c);
}

/* The deflation weight: the largest hypersingular diagonal entry on the outer surface over the
 * squared mean node weight (the same number however the matrix is assembled). */
static void sym_alpha(sym *s, const thx_bem *b)
{
    size_t oo = b->off[b->outer], on = b->off[b->outer + 1] - oo;
    double dmax = 0, wsum = 0;
    size_t o = (size_t)b->outer;
    for (size_t a = oo; a < oo + on; a++) {
        /* M_aa = sum over T' at a (ascending) of g_T'.r_{T',a}, g_T' = sum over T at a of -cN ss r_{T,a} */
        double v = 0;
        double c = -s->cN[o * s->S + o];
        for (size_t f = s->star_off[a]; f < s->star_off[a + 1]; f++) {
            size_t u = s->star[f];
            const tri *U = &s->T[u];
            double g[3] = {0, 0, 0};
            for (size_t e = s->star_off[a]; e < s->star_off[a + 1]; e++) {
                size_t t = s->star[e];
                const tri *A = &s->T[t];
                int ja = corner(A, a);
                double w = c * pair_sym(s, t, u, NULL, NULL);
                for (int k = 0; k < 3; k++) g[k] += w * A->curl[ja][k];
            }
            int jb = corner(U, a);
            v += g[0] * U->curl[jb][0] + g[1] * U->curl[jb][1] + g[2] * U->curl[jb][2];
        }
        dmax = fmax(dmax, fabs(v));
        wsum += b->area[a];
    }
    double wm = wsum / (double)(on ? on : 1);
    s->alpha = dmax / (wm * wm);
}

/* The right-hand sides (n x nd, column-major): each triangle's integrals, then summed at the
 * nodes in a fixed order (the result does not depend on the threads). */
static thx_status sym_rhs(thx_ctx *ctx, const sym *s, const thx_bem *b, const double *pos, const double *mom,
                          size_t nd, const int *comp, double *rhs)
{
    const size_t nt = s->nt, n = s->n;
    double *tin = thx_malloc(ctx, 4 * (nt ? nt : 1) * sizeof *tin);
    if (!tin) return THX_ENOMEM;
    memset(rhs, 0, n * nd * sizeof *rhs);
    for (size_t d = 0; d < nd; d++) {
        const double *p = pos + 3 * d, *q = mom + 3 * d;
        size_t c = (size_t)comp[d];
        double *r = rhs + d * n;
#pragma omp parallel for schedule(dynamic, 8)
        for (size_t i = 0; i < nt; i++) {
            static const double L[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
            double *out = tin + 4 * i;
            out[0] = out[1] = out[2] = out[3] = 0;
            if (side(b, c, (size_t)s->T[i].surf)) source_integrals(&s->T[i], L, p, q, 0, out);
        }
        for (size_t i = 0; i < nt; i++) {
            int sg = side(b, c, (size_t)s->T[i].surf);
            if (!sg) continue;
            const double *out = tin + 4 * i;
            if (s->pidx[i] >= 0) r[s->pidx[i]] = -sg * out[0] / b->sig_in[c];
            for (int m = 0; m < 3; m++) r[s->T[i].node[m]] += sg * out[1 + m];
        }
    }
    free(tin);
    return THX_OK;
}

thx_status thx_bem_dipoles_symmetric(thx_ctx *ctx, const thx_bem *b, const double *pos, const double *mom, size_t nd,
                                     const int *comp, double *phi, thx_bem_info *info)
{
    sym sy;
    THX_CHECK(sym_init(ctx, b, &sy));
    const size_t S = sy.S, N = sy.N, nt = sy.nt, np = sy.np, n = sy.n;
    const tri *T = sy.T;
    const long *pidx = sy.pidx;
    const size_t *toff = sy.toff, *nt_off = sy.star_off, *nt_idx = sy.star;
    const unsigned char *share = sy.share;
    const double *cS = sy.cS, *cN = sy.cN, *cD = sy.cD;
    thx_status st = THX_OK;
    double *SS = NULL, *M = NULL, *rhs = NULL;
    int *piv = NULL;

    double t0 = thx_wtime();
    SS = thx_calloc(ctx, nt * nt, sizeof *SS);
    M = thx_calloc(ctx, n * n, sizeof *M);
    if (!SS || !M) {
        st = thx_error(ctx, THX_ENOMEM, "bem: symmetric method: %zu unknowns need %.1f GB", n,
                       8.0 * ((double)n * (double)n + (double)nt * (double)nt) / 1e9);
        goto done;
    }
    if (info) info->matrix_bytes = 8.0 * ((double)n * (double)n + (double)nt * (double)nt);
    /* 1. every pair of triangles whose surfaces bound a common compartment: SS, and the double
     *    layer into the current columns (column p_T: written by T's iteration only; column-major,
     *    so each thread writes its own contiguous stretch) */
#pragma omp parallel for schedule(dynamic, 8)
    for (size_t i = 0; i < nt; i++) {
        const tri *A = &T[i];
        for (size_t k = 0; k < S; k++) {
            if (!share[(size_t)A->surf * S + k]) continue;
            double cd = cD[(size_t)A->surf * S + k];
            for (size_t j = toff[k]; j < toff[k + 1]; j++) {
                double ss, dd[3];
                pair_integrals(A, sy.q12 + 12 * i, &T[j], &ss, dd);
                SS[i * nt + j] = ss;
                if (pidx[i] >= 0)
                    for (int m = 0; m < 3; m++) M[(size_t)pidx[i] * n + (size_t)T[j].node[m]] -= cd * dd[m];
            }
        }
    }
    /* 2. SS symmetric (the outer rule makes SS_TT' and SS_T'T differ slightly) */
#pragma omp parallel for schedule(dynamic, 16)
    for (size_t i = 0; i < nt; i++)
        for (size_t j = i + 1; j < nt; j++) {
            double a = 0.5 * (SS[j * nt + i] + SS[i * nt + j]);
            SS[j * nt + i] = SS[i * nt + j] = a;
        }
    /* 3. current-current blocks: sum_c s s / sigma_c SS (column p_T' by its iteration) */
#pragma omp parallel for schedule(dynamic, 16)
    for (size_t j = 0; j < nt; j++) {
        if (pidx[j] < 0) continue;
        for (size_t i = 0; i < nt; i++) {
            if (pidx[i] < 0) continue;
            double c = cS[(size_t)T[i].surf * S + (size_t)T[j].surf];
            if (c != 0) M[(size_t)pidx[j] * n + (size_t)pidx[i]] = c * SS[j * nt + i];
        }
    }
    /* 4. potential-potential blocks: sum_c s s sigma_c N, N by Nedelec (symmetric: column a by its
     *    iteration): g_T' = sum_{T at a} c SS_TT' (n x grad h_a)_T, then column a gets g_T'.(n x
     *    grad h_b)_T' for the three nodes b of each T' */
    thx_status st4 = THX_OK;
#pragma omp parallel
    {
        double *g = malloc(3 * (nt ? nt : 1) * sizeof *g);
        if (!g) {
#pragma omp atomic write
            st4 = THX_ENOMEM;
        }
#pragma omp for schedule(dynamic, 8)
        for (size_t a = 0; a < N; a++) {
            if (!g) continue;
            memset(g, 0, 3 * nt * sizeof *g);
            for (size_t e = nt_off[a]; e < nt_off[a + 1]; e++) {
                const tri *A = &T[nt_idx[e]];
                int ja = corner(A, a);
                const double *ra = A->curl[ja];
                const double *row = SS + nt_idx[e] * nt;
                for (size_t k = 0; k < S; k++) {
                    double c = -cN[(size_t)A->surf * S + k];
                    if (c == 0) continue;
                    for (size_t j = toff[k]; j < toff[k + 1]; j++) {
                        double w = c * row[j];
                        g[3 * j] += w * ra[0];
                        g[3 * j + 1] += w * ra[1];
                        g[3 * j + 2] += w * ra[2];
                    }
                }
            }
            double *col = M + a * n;
            for (size_t j = 0; j < nt; j++) {
                const double *gj = g + 3 * j;
                if (gj[0] == 0 && gj[1] == 0 && gj[2] == 0) continue;
                for (int m = 0; m < 3; m++) {
                    const double *rb = T[j].curl[m];
                    col[T[j].node[m]] += gj[0] * rb[0] + gj[1] * rb[1] + gj[2] * rb[2];
                }
            }
        }
        free(g);
    }
    if (st4 != THX_OK) { st = THX_ENOMEM; goto done; }
    /* 5. the current rows' potential columns: the transpose of the potential rows' current columns */
    for (size_t i = 0; i < nt; i++) {
        if (pidx[i] < 0) continue;
        size_t r = (size_t)pidx[i];
        for (size_t a = 0; a < N; a++) M[a * n + r] = M[r * n + a];
    }
    /* 6. deflation: alpha w w^T on the outer surface's potential block */
    sym_alpha(&sy, b);
    {
        size_t oo = b->off[b->outer], on = b->off[b->outer + 1] - oo;
        for (size_t c = oo; c < oo + on; c++)
            for (size_t a = oo; a < oo + on; a++) M[c * n + a] += sy.alpha * b->area[a] * b->area[c];
    }
    free(SS);
    SS = NULL;
    double t_asm = thx_wtime() - t0;
    t0 = thx_wtime();
    rhs = thx_malloc(ctx, n * (nd ? nd : 1) * sizeof *rhs);
    if (!rhs) { st = THX_ENOMEM; goto done; }
    THX_TRY(sym_rhs(ctx, &sy, b, pos, mom, nd, comp, rhs));
    if (n > INT_MAX / 2) { st = thx_error(ctx, THX_EINPUT, "bem: %zu unknowns, more than LAPACK's int", n); goto done; }
    {
        /* M = [A B^T; B C] with C (currents) positive definite: the currents are eliminated by
         * C's Cholesky factor L (W = L^-1 B, A - W^T W, the right-hand side likewise), and the
         * potentials' Schur complement, symmetric but indefinite (deflation), by LU: a third of
         * the LU's work on the whole, all of it in level-3 BLAS */
        int nN = (int)N, nP = (int)np, ld = (int)n, R = (int)nd, inf = 0;
        double one = 1, mone = -1;
        double *C = M + N * n + N, *B = M + N, *A = M;
        if (nP > 0) {
            dpotrf_("L", &nP, C, &ld, &inf);
            if (inf != 0) {
                st = thx_error(ctx, THX_ESOLVER, "bem: symmetric system: the current block (%zu triangles) is not "
                               "positive definite (LAPACK dpotrf info %d): are two surfaces touching?", np, inf);
                goto done;
            }
            dtrsm_("L", "L", "N", "N", &nP, &nN, &one, C, &ld, B, &ld);
            dsyrk_("L", "T", &nN, &nP, &mone, B, &ld, &one, A, &ld);
            if (R > 0) {
                dtrsm_("L", "L", "N", "N", &nP, &R, &one, C, &ld, rhs + N, &ld);
                dgemm_("T", "N", &nN, &R, &nP, &mone, B, &ld, rhs + N, &ld, &one, rhs, &ld);
            }
        }
        for (size_t c = 0; c < N; c++) /* the lower triangle to the upper */
            for (size_t r = c + 1; r < N; r++) A[r * n + c] = A[c * n + r];
        piv = thx_malloc(ctx, (N ? N : 1) * sizeof *piv);
        if (!piv) { st = THX_ENOMEM; goto done; }
        dgetrf_(&nN, &nN, A, &ld, piv, &inf);
        if (inf == 0 && R > 0) dgetrs_("N", &nN, &R, A, &ld, piv, rhs, &ld, &inf);
        if (inf != 0) {
            st = thx_error(ctx, THX_ESOLVER, "bem: symmetric system (%zu unknowns) singular (LAPACK info %d): are two "
                           "surfaces touching?", n, inf);
            goto done;
        }
    }
    /* potentials at the nodes, referenced to the outer surface's area-weighted mean */
    {
        size_t oo = b->off[b->outer], on = b->off[b->outer + 1] - oo;
        for (size_t d = 0; d < nd; d++) {
            double m = 0, w = 0;
            for (size_t a = oo; a < oo + on; a++) m += b->area[a] * rhs[d * n + a], w += b->area[a];
            for (size_t a = 0; a < N; a++) phi[d * N + a] = rhs[d * n + a] - m / w;
        }
    }
    if (info) {
        info->n_unknowns = n;
        info->t_assemble = t_asm;
        info->t_solve = thx_wtime() - t0;
        info->ipa_surface = -1;
    }
done:
    sym_free(&sy);
    free(SS);
    free(M);
    free(rhs);
    free(piv);
    return st;
}

/* Column j of the symmetric matrix (= row j), computed alone from the pair integrals: the entries
 * the serial assembly gives, in the same order of summation (tests/e2e_bem.sh compares the two
 * paths). g: 3 nt doubles of scratch. */
static void sym_column(const sym *s, const thx_bem *b, size_t j, double *col, double *g)
{
    const size_t S = s->S, N = s->N, nt = s->nt;
    const tri *T = s->T;
    memset(col, 0, s->n * sizeof *col);
    if (j < N) { /* the potential of node a */
        size_t a = j;
        memset(g, 0, 3 * nt * sizeof *g);
        for (size_t e = s->star_off[a]; e < s->star_off[a + 1]; e++) {
            size_t t = s->star[e];
            const tri *A = &T[t];
            int ja = corner(A, a);
            const double *ra = A->curl[ja];
            for (size_t k = 0; k < S; k++) {
                if (!s->share[(size_t)A->surf * S + k]) continue;
                double c = -s->cN[(size_t)A->surf * S + k];
                for (size_t u = s->toff[k]; u < s->toff[k + 1]; u++) {
                    double dd_ut[3];
                    double ss = pair_sym(s, t, u, NULL, dd_ut);
                    if (c != 0) {
                        double w = c * ss;
                        g[3 * u] += w * ra[0];
                        g[3 * u + 1] += w * ra[1];
                        g[3 * u + 2] += w * ra[2];
                    }
                    /* the current row of u, tested on u, the hat of a on t inner */
                    if (s->pidx[u] >= 0) col[s->pidx[u]] -= s->cD[k * S + (size_t)A->surf] * dd_ut[ja];
                }
            }
        }
        for (size_t u = 0; u < nt; u++) {
            const double *gu = g + 3 * u;
            if (gu[0] == 0 && gu[1] == 0 && gu[2] == 0) continue;
            for (int m = 0; m < 3; m++) {
                const double *rb = T[u].curl[m];
                col[T[u].node[m]] += gu[0] * rb[0] + gu[1] * rb[1] + gu[2] * rb[2];
            }
        }
        size_t oo = b->off[b->outer], on = b->off[b->outer + 1] - oo;
        if (a >= oo && a < oo + on)
            for (size_t c = oo; c < oo + on; c++) col[c] += s->alpha * b->area[c] * b->area[a];
    } else { /* the current of triangle t */
        size_t t = 0;
        while (s->pidx[t] != (long)j) t++;
        const tri *A = &T[t];
        for (size_t k = 0; k < S; k++) {
            if (!s->share[(size_t)A->surf * S + k]) continue;
            double cd = s->cD[(size_t)A->surf * S + k], cs = s->cS[k * S + (size_t)A->surf];
            for (size_t u = s->toff[k]; u < s->toff[k + 1]; u++) {
                double dd_tu[3];
                double ss = pair_sym(s, t, u, dd_tu, NULL);
                if (s->pidx[u] >= 0 && cs != 0) col[s->pidx[u]] = cs * ss;
                for (int m = 0; m < 3; m++) col[T[u].node[m]] -= cd * dd_tu[m];
            }
        }
    }
}

thx_status thx_bem_symmetric_rows(thx_ctx *ctx, const thx_bem *b, size_t i0, size_t i1, const double *pos,
                                  const double *mom, size_t nd, const int *comp, double *M, double *R, size_t *n_out)
{
    sym sy;
    THX_CHECK(sym_init(ctx, b, &sy));
    thx_status st = THX_OK;
    const size_t n = sy.n, nl = i1 > i0 ? i1 - i0 : 0;
    if (n_out) *n_out = n;
    if (!M) goto done; /* the size alone */
    sym_alpha(&sy, b);
    thx_status st2 = THX_OK;
#pragma omp parallel
    {
        double *col = malloc(n * sizeof *col), *g = malloc(3 * (sy.nt ? sy.nt : 1) * sizeof *g);
        if (!col || !g) {
#pragma omp atomic write
            st2 = THX_ENOMEM;
        }
#pragma omp for schedule(dynamic, 4)
        for (size_t j = i0; j < i1; j++) {
            if (!col || !g) continue;
            sym_column(&sy, b, j, col, g);
            for (size_t c = 0; c < n; c++) M[c * nl + (j - i0)] = col[c]; /* row j = column j */
        }
        free(col);
        free(g);
    }
    if (st2 != THX_OK) { st = THX_ENOMEM; goto done; }
    if (R && nd) {
        double *rhs = thx_malloc(ctx, n * nd * sizeof *rhs);
        if (!rhs) { st = THX_ENOMEM; goto done; }
        st = sym_rhs(ctx, &sy, b, pos, mom, nd, comp, rhs);
        for (size_t d = 0; d < nd && st == THX_OK; d++)
            for (size_t j = i0; j < i1; j++) R[d * nl + (j - i0)] = rhs[d * n + j];
        free(rhs);
    }
done:
    sym_free(&sy);
    return st;
}
