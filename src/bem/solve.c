/* The boundary-element systems: dipoles (with the isolated problem approach and deflation) and
 * the heart-surface-potential transfer matrix; dense LU by LAPACK (thorax/bem/bem.h). */
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bem/bem_impl.h"

void thx_bem_opts_default(thx_bem_opts *o)
{
    memset(o, 0, sizeof *o);
    o->ipa = 1;
}

/* Each row of B over its own surface sums to 2 pi (the smooth-surface value): the diagonal takes
 * what the flat triangles at the node leave out (4 pi - its inner solid angle - 2 pi). */
static void fix_diagonal(const thx_bem *b, double *B, size_t ld, size_t i0, size_t i1)
{
    for (size_t k = 0; k < b->n; k++) {
        size_t o = b->off[k], e = b->off[k + 1];
        size_t a = o > i0 ? o : i0, z = e < i1 ? e : i1;
#pragma omp parallel for schedule(static)
        for (size_t i = a; i < z; i++) {
            double sum = 0;
            for (size_t j = o; j < e; j++)
                if (j != i) sum += B[j * ld + i - i0];
            B[i * ld + i - i0] = 2 * M_PI - sum;
        }
    }
}


const double thx_bem_edge_midpoints[3][4] = {{.5, .5, 0, 1. / 3}, {0, .5, .5, 1. / 3}, {.5, 0, .5, 1. / 3}};

/* V_inf of dipole (p, q) times the double-layer kernel seen from x, integrated over the triangle
 * (a, b, c) with normal n: the 3-point midpoint rule (exact for quadratics) on a recursive
 * subdivision fine enough near the dipole and near x. */
static double quad_tri(const double *x, const double *p, const double *q, const double *n, const double *a,
                       const double *b, const double *c, int depth)
{
    double g[3] = {(a[0] + b[0] + c[0]) / 3, (a[1] + b[1] + c[1]) / 3, (a[2] + b[2] + c[2]) / 3};
    double h = 0;
    const double *v[3] = {a, b, c};
    for (int i = 0; i < 3; i++) {
        const double *u = v[i], *w = v[(i + 1) % 3];
        double l = sqrt((u[0] - w[0]) * (u[0] - w[0]) + (u[1] - w[1]) * (u[1] - w[1]) + (u[2] - w[2]) * (u[2] - w[2]));
        if (l > h) h = l;
    }
    double dp = sqrt((g[0] - p[0]) * (g[0] - p[0]) + (g[1] - p[1]) * (g[1] - p[1]) + (g[2] - p[2]) * (g[2] - p[2]));
    double dx = sqrt((g[0] - x[0]) * (g[0] - x[0]) + (g[1] - x[1]) * (g[1] - x[1]) + (g[2] - x[2]) * (g[2] - x[2]));
    if (depth < 9 && (h > 0.4 * dp || h > 0.4 * dx)) {
        double ab[3], bc[3], ca[3];
        for (int k = 0; k < 3; k++) { ab[k] = (a[k] + b[k]) / 2; bc[k] = (b[k] + c[k]) / 2; ca[k] = (c[k] + a[k]) / 2; }
        return quad_tri(x, p, q, n, a, ab, ca, depth + 1) + quad_tri(x, p, q, n, ab, b, bc, depth + 1) +
               quad_tri(x, p, q, n, ca, bc, c, depth + 1) + quad_tri(x, p, q, n, ab, bc, ca, depth + 1);
    }
    double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    double cr[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    double area = 0.5 * sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]);
    double sum = 0;
    const double (*r)[4] = thx_bem_edge_midpoints;
    for (int i = 0; i < 3; i++) {
        double m[3];
        for (int k = 0; k < 3; k++) m[k] = r[i][0] * a[k] + r[i][1] * b[k] + r[i][2] * c[k];
        double rp[3] = {m[0] - p[0], m[1] - p[1], m[2] - p[2]}, rx[3] = {m[0] - x[0], m[1] - x[1], m[2] - x[2]};
        double lp = sqrt(rp[0] * rp[0] + rp[1] * rp[1] + rp[2] * rp[2]), lx = sqrt(rx[0] * rx[0] + rx[1] * rx[1] + rx[2] * rx[2]);
        double vinf = (q[0] * rp[0] + q[1] * rp[1] + q[2] * rp[2]) / (4 * M_PI * lp * lp * lp);
        sum += r[i][3] * vinf * (n[0] * rx[0] + n[1] * rx[1] + n[2] * rx[2]) / (lx * lx * lx);
    }
    return sum * area;
}

/* The isolated problem's right-hand side for chi = phi0 - (2/sigma) V_inf (smooth where V_inf is
 * peaked: a dipole near the surface): (1/2 pi) (K V_inf)(r_i), K the double layer as the discrete
 * system has it (the flat triangles at r_i give 0; the diagonal term B_ii V_inf(r_i)). */
static void isolated_rhs(const thx_bem *b, size_t k, const double *B, size_t ld, const double *p, const double *q,
                         double *out)
{
    const thx_surface *s = b->surf[k];
    size_t o = b->off[k];
#pragma omp parallel for schedule(dynamic, 4)
    for (size_t i = 0; i < s->n_nodes; i++) {
        const double *x = s->xyz + 3 * i;
        double sum = 0;
        for (size_t t = 0; t < s->n_tris; t++) {
            const int32_t *v = s->tri + 3 * t;
            if (v[0] == (int32_t)i || v[1] == (int32_t)i || v[2] == (int32_t)i) continue;
            const double *a = s->xyz + 3 * v[0], *bb = s->xyz + 3 * v[1], *c = s->xyz + 3 * v[2];
            double e1[3] = {bb[0] - a[0], bb[1] - a[1], bb[2] - a[2]}, e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
            double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
            double nl = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            if (!(nl > 0)) continue;
            for (int j = 0; j < 3; j++) n[j] /= nl;
            sum += quad_tri(x, p, q, n, a, bb, c, 0);
        }
        double r[3] = {x[0] - p[0], x[1] - p[1], x[2] - p[2]};
        double r2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
        double vi = (q[0] * r[0] + q[1] * r[1] + q[2] * r[2]) / (4 * M_PI * r2 * sqrt(r2));
        out[i] = (sum + B[(o + i) * ld + o + i] * vi) / (2 * M_PI);
    }
}

static size_t surface_of(const thx_bem *b, size_t i)
{
    size_t k = 0;
    while (b->off[k + 1] <= i) k++;
    return k;
}

static thx_status lu_solve(thx_ctx *ctx, double *A, size_t n, double *rhs, size_t nrhs, const char *what)
{
    if (n > INT_MAX || nrhs > INT_MAX) return thx_error(ctx, THX_EINPUT, "bem: %s: %zu unknowns, more than LAPACK's int", what, n);
    int N = (int)n, R = (int)nrhs, info = 0;
    int *piv = thx_malloc(ctx, (n ? n : 1) * sizeof *piv);
    if (!piv) return THX_ENOMEM;
    dgetrf_(&N, &N, A, &N, piv, &info);
    if (info == 0 && R > 0) dgetrs_("N", &N, &R, A, &N, piv, rhs, &N, &info);
    free(piv);
    if (info != 0)
        return thx_error(ctx, THX_ESOLVER, "bem: %s: the %zu x %zu system is singular (LAPACK dgetrf info %d): are "
                         "two surfaces touching?", what, n, n, info);
    return THX_OK;
}

thx_status thx_bem_dipole_compartments(thx_ctx *ctx, const thx_bem *b, const double *pos, const double *mom, size_t nd,
                                       int *comp)
{
    size_t S = b->n;
    for (size_t k = 0; k < S; k++)
        if (!(b->sig_in[k] > 0))
            return thx_error(ctx, THX_EINPUT, "bem: surface '%s': conductivity inside %g S/m; dipoles need every "
                             "compartment conducting", b->surf[k]->name, b->sig_in[k]);
    /* each dipole's compartment: the innermost surface holding it */
    for (size_t d = 0; d < nd; d++) {
        const double *p = pos + 3 * d;
        const double *q = mom + 3 * d;
        if (!isfinite(p[0] + p[1] + p[2] + q[0] + q[1] + q[2]))
            return thx_error(ctx, THX_EINPUT, "dipole %zu: a value is not finite", d + 1);
        int c = -1;
        for (size_t k = 0; k < S; k++) {
            size_t t;
            double w[3], qq[3];
            double dist = thx_surface_nearest(b->surf[k], p, &t, w, qq);
            if (dist <= 1e-9 * b->scale)
                return thx_error(ctx, THX_EINPUT, "dipole %zu at (%g, %g, %g) lies on surface '%s'", d + 1, p[0], p[1],
                                 p[2], b->surf[k]->name);
            if (thx_bem_surface_angle(b, k, p) > 2 * M_PI) {
                /* innermost: a surface inside the current one */
                if (c < 0) c = (int)k;
                else {
                    int a = (int)k;
                    while (a >= 0 && a != c) a = b->parent[a];
                    if (a == c) c = (int)k;
                }
            }
        }
        if (c < 0)
            return thx_error(ctx, THX_EINPUT, "dipole %zu at (%g, %g, %g) is outside the outer surface '%s'", d + 1, p[0],
                             p[1], p[2], b->surf[b->outer]->name);
        comp[d] = c;
    }
    return THX_OK;
}

thx_status thx_bem_dipoles(thx_ctx *ctx, const thx_bem *b, const double *pos, const double *mom, size_t nd,
                           const thx_bem_opts *o, double *phi, thx_bem_info *info)
{
    thx_bem_opts def;
    if (!o) { thx_bem_opts_default(&def); o = &def; }
    thx_bem_info inf;
    memset(&inf, 0, sizeof inf);
    inf.ipa_surface = -1;
    size_t N = b->off[b->n], S = b->n;
    thx_status st = THX_OK;
    double *B = NULL, *A1 = NULL, *rhs1 = NULL;
    int *comp = NULL;
    comp = thx_malloc(ctx, (nd ? nd : 1) * sizeof *comp);
    if (!comp) return THX_ENOMEM;
    st = thx_bem_dipole_compartments(ctx, b, pos, mom, nd, comp);
    if (st != THX_OK) goto done;
    if (o->method == THX_BEM_SYMMETRIC) {
        st = thx_bem_dipoles_symmetric(ctx, b, pos, mom, nd, comp, phi, &inf);
        goto done;
    }
    double t0 = thx_wtime();
    B = thx_calloc(ctx, N * N, sizeof *B);
    double *rhs = phi;
    if (!B) { st = THX_ENOMEM; goto done; }
    inf.matrix_bytes = (double)N * (double)N * sizeof(double);
    unsigned char use[256];
    if (S > sizeof use) { st = thx_error(ctx, THX_EINPUT, "bem: %zu surfaces, at most %zu", S, sizeof use); goto done; }
    memset(use, 1, S);
    thx_bem_assemble_rows(b, 0, N, use, -1, B, NULL, N);
    fix_diagonal(b, B, N, 0, N);
    inf.t_assemble = thx_wtime() - t0;
    t0 = thx_wtime();
    /* right-hand sides: V_inf at every node */
    for (size_t d = 0; d < nd; d++)
        for (size_t i = 0; i < N; i++) {
            size_t k = surface_of(b, i);
            const double *x = b->surf[k]->xyz + 3 * (i - b->off[k]), *p = pos + 3 * d, *q = mom + 3 * d;
            double r[3] = {x[0] - p[0], x[1] - p[1], x[2] - p[2]};
            double r2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
            rhs[d * N + i] = (q[0] * r[0] + q[1] * r[1] + q[2] * r[2]) / (4 * M_PI * r2 * sqrt(r2));
        }
    /* the isolated problem for the dipoles in a leaf compartment that conducts more than outside
     * (Hämäläinen & Sarvas 1989): phi0 on that surface alone in an insulator; the full problem
     * is then solved for the rest with right-hand side -(s- s+/(s- - s+)) phi0 on that surface */
    for (size_t k = 0; k < S && o->ipa; k++) {
        int leaf = 1;
        for (size_t l = 0; l < S; l++) leaf &= b->parent[l] != (int)k;
        double sm = b->sig_in[k], sp = b->sig_out[k];
        if (!leaf || !(sp < sm) || k == b->outer) continue;
        size_t nk = 0;
        for (size_t d = 0; d < nd; d++) nk += comp[d] == (int)k;
        if (!nk) continue;
        size_t n1 = b->off[k + 1] - b->off[k], o1 = b->off[k];
        A1 = thx_malloc(ctx, n1 * n1 * sizeof *A1);
        rhs1 = thx_malloc(ctx, n1 * nk * sizeof *rhs1);
        if (!A1 || !rhs1) { st = THX_ENOMEM; goto done; }
        double atot = 0;
        for (size_t j = 0; j < n1; j++) atot += b->area[o1 + j];
        for (size_t j = 0; j < n1; j++)
            for (size_t i = 0; i < n1; i++)
                A1[j * n1 + i] = (i == j ? sm / 2 : 0) - sm / (4 * M_PI) * B[(o1 + j) * N + o1 + i] + sm * b->area[o1 + j] / atot;
        /* phi0 = (2/sigma) V_inf + chi: chi carries no peak of V_inf and suits linear elements */
        for (size_t d = 0, c = 0; d < nd; d++)
            if (comp[d] == (int)k) { isolated_rhs(b, k, B, N, pos + 3 * d, mom + 3 * d, rhs1 + c * n1); c++; }
        inf.matrix_bytes += (double)n1 * (double)n1 * sizeof(double);
        THX_TRY(lu_solve(ctx, A1, n1, rhs1, nk, "isolated problem"));
        for (size_t d = 0, c = 0; d < nd; d++)
            if (comp[d] == (int)k) {
                for (size_t i = 0; i < n1; i++) rhs1[c * n1 + i] += 2 / sm * rhs[d * N + o1 + i];
                c++;
            }
        double alpha = sm / (sm - sp), beta = -sm * sp / (sm - sp);
        for (size_t d = 0, c = 0; d < nd; d++) {
            if (comp[d] != (int)k) continue;
            for (size_t i = 0; i < N; i++) rhs[d * N + i] = 0;
            for (size_t i = 0; i < n1; i++) rhs[d * N + o1 + i] = beta * rhs1[c * n1 + i];
            /* keep phi0 (times alpha) where the correction is added after the solve */
            for (size_t i = 0; i < n1; i++) rhs1[c * n1 + i] *= alpha;
            c++;
        }
        inf.ipa_surface = (int)k;
        free(A1);
        A1 = NULL;
        /* the full solve below; the isolated parts are added after it */
        break;
    }
    /* the full system: A = diag(mean sigma) - (ds_l / 4 pi) B + deflation by the outer surface's
     * area-weighted constant (the constant null vector of the pure Neumann problem) */
    {
        double *w = thx_calloc(ctx, N, sizeof *w);
        if (!w) { st = THX_ENOMEM; goto done; }
        size_t oo = b->off[b->outer], on = b->off[b->outer + 1] - oo;
        double atot = 0;
        for (size_t j = 0; j < on; j++) atot += b->area[oo + j];
        for (size_t j = 0; j < on; j++) w[oo + j] = b->area[oo + j] / atot;
        double cdef = b->sig_in[b->outer];
        for (size_t j = 0; j < N; j++) {
            size_t l = surface_of(b, j);
            double f = -(b->sig_in[l] - b->sig_out[l]) / (4 * M_PI);
            double *col = B + j * N;
            for (size_t i = 0; i < N; i++) col[i] = f * col[i] + cdef * w[j];
            col[j] += (b->sig_in[l] + b->sig_out[l]) / 2;
        }
        st = lu_solve(ctx, B, N, rhs, nd, "dipoles");
        if (st == THX_OK && inf.ipa_surface >= 0) {
            size_t k = (size_t)inf.ipa_surface, n1 = b->off[k + 1] - b->off[k], o1 = b->off[k];
            for (size_t d = 0, c = 0; d < nd; d++)
                if (comp[d] == (int)k) {
                    for (size_t i = 0; i < n1; i++) rhs[d * N + o1 + i] += rhs1[c * n1 + i];
                    c++;
                }
        }
        /* reference: zero area-weighted mean over the outer surface */
        for (size_t d = 0; d < nd && st == THX_OK; d++) {
            double mean = 0;
            for (size_t j = 0; j < N; j++) mean += w[j] * rhs[d * N + j];
            for (size_t j = 0; j < N; j++) rhs[d * N + j] -= mean;
        }
        free(w);
    }
    inf.t_solve = thx_wtime() - t0;
    inf.n_unknowns = N;
done:
    free(B);
    free(A1);
    free(rhs1);
    free(comp);
    if (info) *info = inf;
    return st;
}

thx_status thx_bem_transfer_rows(thx_ctx *ctx, const thx_bem *b, size_t h, size_t i0, size_t i1, double *M, double *R,
                                 size_t ld)
{
    size_t N = b->off[b->n], S = b->n;
    double sp = b->sig_out[h];
    size_t nh = b->off[h + 1] - b->off[h], oh = b->off[h];
    double *SL = thx_calloc(ctx, ld * (nh ? nh : 1), sizeof *SL);
    if (!SL) return THX_ENOMEM;
    memset(M, 0, ld * N * sizeof *M);
    unsigned char use[256];
    if (S > sizeof use) { free(SL); return thx_error(ctx, THX_EINPUT, "bem: %zu surfaces, at most %zu", S, sizeof use); }
    memset(use, 1, S);
    thx_bem_assemble_rows(b, i0, i1, use, (int)h, M, SL, ld);
    fix_diagonal(b, M, ld, i0, i1);
    /* the right-hand sides: the heart's potential columns moved over (inside the heart: sigma 0) */
    for (size_t j = 0; j < nh; j++)
        for (size_t i = i0; i < i1; i++)
            R[j * ld + i - i0] = -(i == oh + j ? sp / 2 : 0) - sp / (4 * M_PI) * M[(oh + j) * ld + i - i0];
    /* the system: potential columns off the heart, the single layer of the heart's normal
     * derivative in the heart's columns */
    for (size_t j = 0; j < N; j++) {
        double *col = M + j * ld;
        if (j >= oh && j < oh + nh) {
            for (size_t i = i0; i < i1; i++) col[i - i0] = sp / (4 * M_PI) * SL[(j - oh) * ld + i - i0];
            continue;
        }
        size_t l = surface_of(b, j);
        double f = -(b->sig_in[l] - b->sig_out[l]) / (4 * M_PI);
        for (size_t i = i0; i < i1; i++) col[i - i0] *= f;
        if (j >= i0 && j < i1) col[j - i0] += (b->sig_in[l] + b->sig_out[l]) / 2;
    }
    free(SL);
    return THX_OK;
}

thx_status thx_bem_transfer_check(thx_ctx *ctx, const thx_bem *b, size_t h)
{
    size_t S = b->n;
    if (h >= S) return thx_error(ctx, THX_EINPUT, "bem: heart surface %zu of %zu", h + 1, S);
    if (h == b->outer) return thx_error(ctx, THX_EINPUT, "bem: the heart '%s' is the outermost surface", b->surf[h]->name);
    for (size_t k = 0; k < S; k++) {
        if (b->parent[k] == (int)h)
            return thx_error(ctx, THX_EINPUT, "bem: surface '%s' is inside the heart '%s'; the heart is a hole in the "
                             "heart-surface formulation", b->surf[k]->name, b->surf[h]->name);
        if (k != h && !(b->sig_in[k] > 0))
            return thx_error(ctx, THX_EINPUT, "bem: surface '%s': conductivity inside %g S/m", b->surf[k]->name, b->sig_in[k]);
    }
    return THX_OK;
}

thx_status thx_bem_transfer(thx_ctx *ctx, const thx_bem *b, size_t h, const thx_bem_opts *o, double *T,
                            thx_bem_info *info)
{
    (void)o;
    thx_bem_info inf;
    memset(&inf, 0, sizeof inf);
    inf.ipa_surface = -1;
    THX_CHECK(thx_bem_transfer_check(ctx, b, h));
    size_t N = b->off[b->n];
    size_t nh = b->off[h + 1] - b->off[h];
    size_t oo = b->off[b->outer], on = b->off[b->outer + 1] - oo;
    thx_status st = THX_OK;
    double t0 = thx_wtime();
    double *B = thx_malloc(ctx, N * N * sizeof *B), *R = thx_malloc(ctx, N * nh * sizeof *R);
    if (!B || !R) { st = THX_ENOMEM; goto done; }
    inf.matrix_bytes = ((double)N * (double)N + 2.0 * (double)N * (double)nh) * sizeof(double);
    THX_TRY(thx_bem_transfer_rows(ctx, b, h, 0, N, B, R, N));
    inf.t_assemble = thx_wtime() - t0;
    t0 = thx_wtime();
    THX_TRY(lu_solve(ctx, B, N, R, nh, "transfer matrix"));
    for (size_t j = 0; j < nh; j++) memcpy(T + j * on, R + j * N + oo, on * sizeof *T);
    inf.t_solve = thx_wtime() - t0;
    inf.n_unknowns = N;
done:
    free(B);
    free(R);
    if (info) *info = inf;
    return st;
}

/* Rows of the refined system assembled at a time (the blocks' right-hand sides are combined by W
 * as they come, so the fine right-hand sides are never held whole). */
#define REFINE_ROW_BLOCK 128

double thx_bem_transfer_refined_bytes(const thx_bem *b, size_t heart, int levels)
{
    if (heart >= b->n) return 0;
    size_t nh = b->off[heart + 1] - b->off[heart], nf = nh;
    thx_bem_refined_counts(nh, b->surf[heart]->n_tris, levels, &nf, NULL);
    double N = (double)(b->off[b->n] - nh) + (double)nf, blk = REFINE_ROW_BLOCK;
    if (levels <= 0) return (N * N + 2.0 * N * (double)nh) * sizeof(double);
    /* the matrix, the combined right-hand sides, a block of rows of the matrix, of the fine
     * right-hand sides and of the single layer */
    return (N * N + N * (double)nh + blk * (N + 2.0 * (double)nf)) * sizeof(double);
}

thx_status thx_bem_transfer_refined(thx_ctx *ctx, const thx_bem *b, size_t h, int levels, const thx_bem_opts *o,
                                    double *T, thx_bem_info *info)
{
    if (levels == 0) return thx_bem_transfer(ctx, b, h, o, T, info);
    thx_bem_info inf;
    memset(&inf, 0, sizeof inf);
    inf.ipa_surface = -1;
    THX_CHECK(thx_bem_transfer_check(ctx, b, h));
    thx_status st = THX_OK;
    thx_bem *f = NULL;
    thx_bem_refinement W;
    memset(&W, 0, sizeof W);
    double *M = NULL, *RW = NULL, *Mb = NULL, *Rb = NULL;
    double t0 = thx_wtime();
    THX_TRY(thx_bem_refine(ctx, b, h, levels, &f, &W));
    size_t N = f->off[f->n], nf = W.n_fine, nc = W.n_coarse;
    size_t oo = f->off[f->outer], on = f->off[f->outer + 1] - oo;
    size_t blk = REFINE_ROW_BLOCK < N ? REFINE_ROW_BLOCK : N;
    M = thx_malloc(ctx, N * N * sizeof *M);
    RW = thx_calloc(ctx, N * nc, sizeof *RW);
    Mb = thx_malloc(ctx, blk * N * sizeof *Mb);
    Rb = thx_malloc(ctx, blk * nf * sizeof *Rb);
    if (!M || !RW || !Mb || !Rb) { st = THX_ENOMEM; goto done; }
    inf.matrix_bytes = thx_bem_transfer_refined_bytes(b, h, levels);
    for (size_t i0 = 0; i0 < N; i0 += blk) {
        size_t i1 = i0 + blk < N ? i0 + blk : N, ld = i1 - i0;
        THX_TRY(thx_bem_transfer_rows(ctx, f, h, i0, i1, Mb, Rb, ld));
        for (size_t j = 0; j < N; j++) memcpy(M + j * N + i0, Mb + j * ld, ld * sizeof *M);
        /* the right-hand side of a coarse hat function: its fine nodes' columns, weighted */
        for (size_t q = 0; q < nf; q++)
            for (int k = 0; k < 3; k++) {
                double w = W.w[3 * q + k];
                if (w == 0) continue;
                double *dst = RW + W.node[3 * q + k] * N + i0;
                const double *src = Rb + q * ld;
                for (size_t i = 0; i < ld; i++) dst[i] += w * src[i];
            }
    }
    free(Mb);
    free(Rb);
    Mb = Rb = NULL;
    inf.t_assemble = thx_wtime() - t0;
    t0 = thx_wtime();
    THX_TRY(lu_solve(ctx, M, N, RW, nc, "transfer matrix (refined heart)"));
    for (size_t j = 0; j < nc; j++) memcpy(T + j * on, RW + j * N + oo, on * sizeof *T);
    inf.t_solve = thx_wtime() - t0;
    inf.n_unknowns = N;
done:
    free(M);
    free(RW);
    free(Mb);
    free(Rb);
    thx_bem_refinement_free(&W);
    thx_bem_destroy(&f);
    if (info) *info = inf;
    return st;
}
