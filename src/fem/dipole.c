/*
 * Current dipole sources in the finite-element forward problem (thorax/fem/fem.h,
 * thx_forward_dipoles; docs/decisions.md, "Dipole sources").
 *
 * Two ways to put a dipole on the mesh: Saint-Venant (default; venant_stencil below) and partial
 * integration. Partial integration: the source term of div(sigma grad phi) = div J_p for a dipole q at x0, J_p = q delta(x - x0),
 * tested against the hat function l_i: integrating by parts, f_i = -int l_i div J_p = q . grad
 * l_i(x0) — the load is q . grad l_i on the four corners of the tetrahedron that holds x0 and
 * zero elsewhere (the partial-integration or "direct" method). The four loads sum to zero
 * (the barycentric gradients do), so the pure Neumann problem of the whole volume is
 * consistent; one node is pinned to 0 for the solve and the potential is then shifted so that
 * its integral over the outer surface is zero, the reference of the analytic solutions of
 * concentric spheres (their expansions start at l = 1).
 *
 * Units: mm, S/m, the moment in mA·m. K is in mS (thorax/fem/fem.h); q . grad l_i is in mA·m/mm
 * = 1000 mA, so a load in µA is 10^6 q . grad l_i and phi comes out in mV.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/fem/fem.h"
#include "thorax/mesh/tet_locate.h"

/* mA·m per mm -> µA: the loads' factor for potentials in mV */
#define LOAD_SCALE 1e6

static double vol6(const double *a, const double *b, const double *c, const double *d)
{
    double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]},
           w[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
    return u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) + u[2] * (v[0] * w[1] - v[1] * w[0]);
}

/* Barycentric coordinates of p in tetrahedron q: the volume with p in place of corner k over the
 * tetrahedron's volume. */
static void bary(const double *xyz, const int32_t *q, const double *p, double l[4])
{
    const double *P[4];
    for (int k = 0; k < 4; k++) P[k] = xyz + 3 * (size_t)q[k];
    double V = vol6(P[0], P[1], P[2], P[3]);
    for (int k = 0; k < 4; k++) {
        const double *R[4] = {P[0], P[1], P[2], P[3]};
        R[k] = p;
        l[k] = vol6(R[0], R[1], R[2], R[3]) / V;
    }
}

void thx_fem_locate(const thx_volume *v, const double p[3], long *tet, double l[4])
{
    long best = -1;
    double best_min = -1e-9, bl[4] = {0, 0, 0, 0};
#pragma omp parallel
    {
        long my = -1;
        double my_min = -1e-9, ml[4] = {0, 0, 0, 0};
#pragma omp for schedule(static)
        for (long t = 0; t < (long)v->n_tets; t++) {
            const int32_t *q = v->tet + 4 * t;
            /* bounding box first */
            int out = 0;
            for (int j = 0; j < 3 && !out; j++) {
                double lo = v->xyz[3 * (size_t)q[0] + j], hi = lo;
                for (int k = 1; k < 4; k++) {
                    double x = v->xyz[3 * (size_t)q[k] + j];
                    lo = x < lo ? x : lo;
                    hi = x > hi ? x : hi;
                }
                double tol = 1e-9 * (hi - lo) + 1e-12;
                out = p[j] < lo - tol || p[j] > hi + tol;
            }
            if (out) continue;
            double b[4];
            bary(v->xyz, q, p, b);
            double mn = fmin(fmin(b[0], b[1]), fmin(b[2], b[3]));
            if (mn > my_min || (mn == my_min && my >= 0 && t < my)) {
                my = t;
                my_min = mn;
                memcpy(ml, b, sizeof ml);
            }
        }
#pragma omp critical
        if (my >= 0 && (my_min > best_min || (my_min == best_min && (best < 0 || my < best)))) {
            best = my;
            best_min = my_min;
            memcpy(bl, ml, sizeof bl);
        }
    }
    /* a point in several tetrahedra (on a face or an edge) goes to the one it is deepest in; ties:
       the lowest number — the same answer for any thread count */
    *tet = best;
    if (l) memcpy(l, bl, sizeof bl);
}

int thx_fem_locate_walk(const thx_tet_locator *loc, const thx_volume *v, const double p[3], long start, long *tet,
                        double l[4])
{
    long t = loc ? thx_tet_locate(loc, p, start, NULL) : -1;
    if (t >= 0) {
        double b[4];
        bary(v->xyz, v->tet + 4 * t, p, b);
        if (fmin(fmin(b[0], b[1]), fmin(b[2], b[3])) > 1e-9) {
            *tet = t;
            if (l) memcpy(l, b, sizeof b);
            return 1;
        }
    }
    thx_fem_locate(v, p, tet, l);
    return 0;
}

/* The partial-integration stencil: the corners of tet, w = the gradients of their hat functions (1/mm). */
static int pi_stencil(const thx_volume *v, long tet, int32_t *node, double (*w)[3])
{
    const int32_t *c = v->tet + 4 * tet;
    double g[4][3];
    thx_fem_tet_gradients(v->xyz, c, g);
    for (int k = 0; k < 4; k++) {
        node[k] = c[k];
        memcpy(w[k], g[k], sizeof g[k]);
    }
    return 4;
}

void thx_dipole_load(const thx_volume *v, long tet, const double q[3], double *load)
{
    int32_t node[4];
    double w[4][3];
    pi_stencil(v, tet, node, w);
    for (int k = 0; k < 4; k++) load[node[k]] += LOAD_SCALE * (q[0] * w[k][0] + q[1] * w[k][1] + q[2] * w[k][2]);
}

/* ---- Saint-Venant: monopoles on the nodes around the dipole whose moments match it ---- */

#define VENANT_MAX 96      /* nodes in a stencil: the node nearest the dipole and its neighbours */
#define VENANT_LAMBDA 1e-6 /* Buchner et al. (1997)'s regularization of the higher moments */

/* Solves the n x n system A x = b (row-major, overwritten) by Gaussian elimination with partial
 * pivoting; 0, or -1 if singular. */
static int dense_solve(int n, double *A, double *b)
{
    for (int k = 0; k < n; k++) {
        int piv = k;
        for (int i = k + 1; i < n; i++)
            if (fabs(A[i * n + k]) > fabs(A[piv * n + k])) piv = i;
        if (!(fabs(A[piv * n + k]) > 0)) return -1;
        if (piv != k) {
            for (int j = 0; j < n; j++) { double t = A[k * n + j]; A[k * n + j] = A[piv * n + j]; A[piv * n + j] = t; }
            double t = b[k]; b[k] = b[piv]; b[piv] = t;
        }
        for (int i = k + 1; i < n; i++) {
            double f = A[i * n + k] / A[k * n + k];
            if (f == 0) continue;
            for (int j = k; j < n; j++) A[i * n + j] -= f * A[k * n + j];
            b[i] -= f * b[k];
        }
    }
    for (int k = n - 1; k >= 0; k--) {
        double s = b[k];
        for (int j = k + 1; j < n; j++) s -= A[k * n + j] * b[j];
        b[k] = s / A[k * n + k];
    }
    return 0;
}

/*
 * The Saint-Venant stencil of a dipole at p in tetrahedron tet: the corner of tet nearest p (n0)
 * and every node sharing a tetrahedron of tet's region with it carry monopole currents c_j with
 * sum c_j = 0 (no net charge), sum c_j (x_j - p) = q (the dipole moment) and the second moments
 * sum c_j (x_j - p)(x_j - p)^T as small as the regularization lets them be:
 *   c = argmin |t - X c|^2 + lambda |W c|^2,
 * X's rows the moments of order 0, 1, 2 of the scaled offsets (x_j - p) / a (a: their mean
 * length), t = (0, q / a, 0), W = diag(|x_j - p| / a) (Buchner et al. 1997; Wolters et al. 2007).
 * c is linear in q: w[j][axis] is c_j for the unit moment along axis (per mm: the loads are
 * 10^6 q . w in µA, as for partial integration). M: room for VENANT_MAX^2 doubles. Returns the
 * stencil's size; -2 if n0 lies on an interface between regions (iface[n0]: the monopoles
 * would then spread on both sides of it; measured on OpenMEEG's dipole 5, 2.85 mm under the skull,
 * that is worse than partial integration, and leaving the interface nodes out is worse still —
 * docs/decisions.md) or fewer than 10 nodes are found: the caller uses partial integration for
 * that dipole; -1 if the system cannot be solved.
 */
static int venant_stencil(const thx_volume *v, const unsigned char *iface, long tet, const double p[3], int32_t *node,
                          double (*w)[3], double *M)
{
    const int32_t *c4 = v->tet + 4 * tet;
    int32_t n0 = -1;
    double best = INFINITY;
    for (int k = 0; k < 4; k++) {
        const double *x = v->xyz + 3 * (size_t)c4[k];
        double d = (x[0] - p[0]) * (x[0] - p[0]) + (x[1] - p[1]) * (x[1] - p[1]) + (x[2] - p[2]) * (x[2] - p[2]);
        if (d < best) { best = d; n0 = c4[k]; }
    }
    if (n0 < 0 || iface[n0]) return -2;
    int32_t region = v->region[tet];
    int n = 0;
    node[n++] = n0;
    for (size_t t = 0; t < v->n_tets; t++) {
        if (v->region[t] != region) continue;
        const int32_t *q = v->tet + 4 * t;
        if (q[0] != n0 && q[1] != n0 && q[2] != n0 && q[3] != n0) continue;
        for (int k = 0; k < 4; k++) {
            int seen = 0;
            for (int j = 0; j < n && !seen; j++) seen = node[j] == q[k];
            if (!seen) {
                if (n == VENANT_MAX) return -1;
                node[n++] = q[k];
            }
        }
    }
    if (n < 10) return -2; /* fewer nodes than moment conditions */
    /* offsets and their scale */
    double D[VENANT_MAX][3], a = 0;
    for (int j = 0; j < n; j++) {
        for (int k = 0; k < 3; k++) D[j][k] = v->xyz[3 * (size_t)node[j] + k] - p[k];
        a += sqrt(D[j][0] * D[j][0] + D[j][1] * D[j][1] + D[j][2] * D[j][2]);
    }
    a /= n;
    if (!(a > 0)) return -1;
    /* X: 10 rows (1; dx dy dz; dxdx dydy dzdz dxdy dxdz dydz) x n, scaled */
    double X[10][VENANT_MAX], W2[VENANT_MAX];
    for (int j = 0; j < n; j++) {
        double x = D[j][0] / a, y = D[j][1] / a, z = D[j][2] / a;
        double r[10] = {1, x, y, z, x * x, y * y, z * z, x * y, x * z, y * z};
        for (int i = 0; i < 10; i++) X[i][j] = r[i];
        W2[j] = x * x + y * y + z * z;
    }
    for (int axis = 0; axis < 3; axis++) {
        double b[VENANT_MAX];
        for (int i = 0; i < n; i++) {
            for (int j = 0; j < n; j++) {
                double s = 0;
                for (int r = 0; r < 10; r++) s += X[r][i] * X[r][j];
                M[i * n + j] = s + (i == j ? VENANT_LAMBDA * W2[i] : 0);
            }
            b[i] = X[1 + axis][i] / a; /* X^T t with t = e_(1+axis) / a */
        }
        if (dense_solve(n, M, b)) return -1;
        double sum = 0;
        for (int j = 0; j < n; j++) sum += b[j];
        for (int j = 0; j < n; j++) w[j][axis] = b[j] - sum / n; /* no net current, exactly */
    }
    return n;
}

static void add_load(const int32_t *node, const double (*w)[3], int n, const double q[3], double *load)
{
    for (int k = 0; k < n; k++) load[node[k]] += LOAD_SCALE * (q[0] * w[k][0] + q[1] * w[k][1] + q[2] * w[k][2]);
}

/* The regions that conduct: a conductivity tensor that is not all zero (a region of conductivity
 * 0 is an insulator, outside the domain). */
static thx_status conducting(thx_ctx *ctx, const thx_volume *v, unsigned char **use)
{
    unsigned char *u = thx_malloc(ctx, v->n_regions ? v->n_regions : 1);
    if (!u) return THX_ENOMEM;
    for (size_t r = 0; r < v->n_regions; r++) {
        u[r] = 0;
        for (int k = 0; k < 9; k++) u[r] |= v->regions[r].sigma[k] != 0;
    }
    *use = u;
    return THX_OK;
}

thx_status thx_forward_dipoles(thx_ctx *ctx, const thx_model *m, const thx_dipoles *d, const thx_forward_opts *o,
                               thx_forward_result *r)
{
    memset(r, 0, sizeof *r);
    thx_forward_opts def;
    if (!o) { thx_forward_opts_default(&def); o = &def; }
    const thx_volume *v = m->volume;
    const char *src = d->path[0] ? d->path : "dipoles";
    if (!v || !v->n_tets) return thx_error(ctx, THX_EINPUT, "forward: the model has no volume mesh (run thorax mesh)");
    size_t outer = 0, n_outer = 0;
    for (size_t s = 0; s < m->n_surfaces; s++)
        if (m->surf[s]->role == THX_ROLE_OUTER) { outer = s; n_outer++; }
    if (n_outer != 1)
        return thx_error(ctx, THX_EINPUT, "forward: the model has %zu surfaces of role outer; exactly one is needed", n_outer);
    if (v->n_surfaces != m->n_surfaces)
        return thx_error(ctx, THX_EINPUT, "forward: the volume's node tables list %zu surfaces, the model %zu", v->n_surfaces,
                         m->n_surfaces);
    if (!d->n || !d->n_frames) return thx_error(ctx, THX_EINPUT, "%s: no dipole", src);
    thx_status st = THX_OK;
    unsigned char *use = NULL, *kind = NULL;
    long *tet = NULL;
    size_t *col = NULL, n_scan = 0;
    thx_tet_locator *loc = NULL;
    double *phi = NULL, *load = NULL, *basis = NULL, *wt = NULL, *work = NULL;
    int *sn = NULL;
    unsigned char *iface = NULL;
    int32_t *snode = NULL;
    double (*sw)[3] = NULL;
    thx_csr K;
    memset(&K, 0, sizeof K);
    thx_fem_system *S = NULL;
    const thx_surface *os = m->surf[outer];
    size_t nn = v->n_nodes, ns = os->n_nodes, n = d->n, nf = d->n_frames;
    THX_TRY(conducting(ctx, v, &use));
    /* every dipole: finite, in a conducting tetrahedron (found by the walk, each dipole's starting
       from the previous one's tetrahedron; the scan where the walk cannot decide) */
    tet = thx_malloc(ctx, n * sizeof *tet);
    if (!tet) { st = THX_ENOMEM; goto done; }
    THX_TRY(thx_tet_locator_create(ctx, v, &loc));
    for (size_t i = 0; i < n; i++) {
        const double *p = d->pos + 3 * i;
        char at[768];
        snprintf(at, sizeof at, "%s:%zu: dipole %zu at (%g, %g, %g) mm", src, d->line[i], i + 1, p[0], p[1], p[2]);
        if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2])) { st = thx_error(ctx, THX_EINPUT, "%s: not a finite position", at); goto done; }
        if (!thx_fem_locate_walk(loc, v, p, i > 0 ? tet[i - 1] : -1, &tet[i], NULL)) n_scan++;
        if (tet[i] < 0) { st = thx_error(ctx, THX_EINPUT, "%s lies outside the volume mesh", at); goto done; }
        int32_t rg = v->region[tet[i]];
        if (rg < 0 || (size_t)rg >= v->n_regions) { st = thx_error(ctx, THX_EINPUT, "%s: its tetrahedron %ld has no region", at, tet[i] + 1); goto done; }
        if (!use[rg]) {
            st = thx_error(ctx, THX_EINPUT, "%s lies in region '%s', whose conductivity is 0 (an insulator: no current source there)",
                           at, v->regions[rg].name);
            goto done;
        }
    }
    /* each dipole's stencil: nodes and, per node, the load of a unit moment along each axis */
    sn = thx_malloc(ctx, n * sizeof *sn);
    snode = thx_malloc(ctx, n * VENANT_MAX * sizeof *snode);
    sw = thx_malloc(ctx, n * VENANT_MAX * sizeof *sw);
    work = thx_malloc(ctx, VENANT_MAX * VENANT_MAX * sizeof *work);
    iface = thx_calloc(ctx, nn ? nn : 1, 1);
    if (!sn || !snode || !sw || !work || !iface) { st = THX_ENOMEM; goto done; }
    {
        /* nodes of tetrahedra of two regions or more: interfaces */
        int32_t *first = thx_malloc(ctx, (nn ? nn : 1) * sizeof *first);
        if (!first) { st = THX_ENOMEM; goto done; }
        for (size_t i = 0; i < nn; i++) first[i] = -1;
        for (size_t t = 0; t < v->n_tets; t++)
            for (int k = 0; k < 4; k++) {
                int32_t a = v->tet[4 * t + k];
                if (first[a] < 0) first[a] = v->region[t];
                else if (first[a] != v->region[t]) iface[a] = 1;
            }
        free(first);
    }
    for (size_t i = 0; i < n; i++) {
        int32_t *nd = snode + i * VENANT_MAX;
        double (*w)[3] = sw + i * VENANT_MAX;
        sn[i] = o->dipole_method == THX_DIPOLE_PARTIAL ? pi_stencil(v, tet[i], nd, w)
                                                       : venant_stencil(v, iface, tet[i], d->pos + 3 * i, nd, w, work);
        if (sn[i] == -2) { /* at an interface: partial integration (counted in the result) */
            sn[i] = pi_stencil(v, tet[i], nd, w);
            r->n_fallback++;
        }
        if (sn[i] < 0) {
            const double *p = d->pos + 3 * i;
            st = thx_error(ctx, THX_EGEOM, "%s:%zu: dipole %zu at (%g, %g, %g) mm: no Saint-Venant stencil around its nearest node "
                           "(more than %d neighbours, or a degenerate one): use partial integration", src, d->line[i], i + 1, p[0],
                           p[1], p[2], VENANT_MAX);
            goto done;
        }
    }
    for (size_t f = 0; f < nf; f++)
        for (size_t k = 0; k < 3 * n; k++)
            if (!isfinite(d->moment[3 * n * f + k])) {
                st = thx_error(ctx, THX_EINPUT, "%s:%zu: frame %zu: the moment of dipole %zu is not finite", src, d->frame_line[f],
                               f + 1, k / 3 + 1);
                goto done;
            }
    double t0 = thx_wtime();
    THX_TRY(thx_fem_assemble_kept(ctx, v, use, &K, &r->assembly)); /* (every rank holds the whole matrix) */
    r->t_assemble = thx_wtime() - t0;
    THX_TRY(thx_fem_active_nodes(ctx, v, use, &kind));
    THX_TRY(thx_fem_system_create(ctx, &K, kind, 1, &S));
    /* the reference: weights of the outer surface's nodes in the integral of the piecewise-linear
       potential over it (a third of each triangle's area to each corner), normalized */
    wt = thx_calloc(ctx, ns ? ns : 1, sizeof *wt);
    if (!wt) { st = THX_ENOMEM; goto done; }
    {
        double tot = 0;
        for (size_t t = 0; t < os->n_tris; t++) {
            const int32_t *c = os->tri + 3 * t;
            const double *a = os->xyz + 3 * (size_t)c[0], *b = os->xyz + 3 * (size_t)c[1], *e = os->xyz + 3 * (size_t)c[2];
            double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w[3] = {e[0] - a[0], e[1] - a[1], e[2] - a[2]};
            double x[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
            double ar = 0.5 * sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
            for (int k = 0; k < 3; k++) wt[c[k]] += ar / 3;
            tot += ar;
        }
        if (!(tot > 0)) { st = thx_error(ctx, THX_EINPUT, "forward: the outer surface '%s' has no area", os->name); goto done; }
        for (size_t i = 0; i < ns; i++) wt[i] /= tot;
    }
    /* solves: one per frame, or (more frames than 3 n) one per dipole and axis, combined. The
       right-hand sides go to the solver as dense blocks (thx_fem_solve_block: with a factorization,
       one multi-right-hand-side solve per block; o->block = 1 or an iterative solver: one by one) */
    int by_axis = nf > 3 * n;
    size_t ns_solve = by_axis ? 3 * n : nf;
    size_t keep = o->keep_volume ? nn : ns;
    THX_TRY(thx_series_create(ctx, ns, nf, &r->torso));
    if (o->keep_volume) THX_TRY(thx_series_create(ctx, nn, nf, &r->volume));
    if (by_axis) basis = thx_malloc(ctx, 3 * n * keep * sizeof *basis);
    /* the solves with a load (a frame whose moments are all zero has phi = 0: no solve) */
    col = thx_malloc(ctx, (ns_solve ? ns_solve : 1) * sizeof *col);
    if (!col || (by_axis && !basis)) { st = THX_ENOMEM; goto done; }
    size_t n_col = 0;
    for (size_t k = 0; k < ns_solve; k++) {
        int any = by_axis;
        for (size_t i = 0; i < 3 * n && !any; i++) any = d->moment[3 * n * k + i] != 0;
        if (any) col[n_col++] = k;
        else {
            memset(r->torso->v + k * ns, 0, ns * sizeof(double));
            if (r->volume) memset(r->volume->v + k * nn, 0, nn * sizeof(double));
        }
    }
    thx_fem_system_hint_rhs(S, n_col);
    if (o->block) thx_fem_system_set_block(S, o->block);
    size_t nb = thx_fem_system_block(S);
    nb = nb < n_col ? nb : n_col ? n_col : 1;
    r->block = nb;
    phi = thx_calloc(ctx, nn * nb > 0 ? nn * nb : 1, sizeof *phi);
    load = thx_calloc(ctx, nn * nb > 0 ? nn * nb : 1, sizeof *load);
    if (!phi || !load) { st = THX_ENOMEM; goto done; }
    r->it_min = 1 << 30;
    for (size_t c0 = 0; c0 < n_col; c0 += nb) {
        size_t kb = n_col - c0 < nb ? n_col - c0 : nb;
        memset(load, 0, nn * kb * sizeof *load);
        if (!o->warm) memset(phi, 0, nn * kb * sizeof *phi);
        else if (c0 > 0 && nb > 1) memcpy(phi, phi + (nb - 1) * nn, nn * sizeof *phi); /* the warm start */
        for (size_t q = 0; q < kb; q++) {
            size_t k = col[c0 + q];
            double *lq = load + q * nn;
            if (by_axis) {
                double e[3] = {0, 0, 0};
                e[k % 3] = 1;
                add_load(snode + (k / 3) * VENANT_MAX, sw + (k / 3) * VENANT_MAX, sn[k / 3], e, lq);
            } else {
                const double *qm = d->moment + 3 * n * k;
                for (size_t i = 0; i < n; i++)
                    if (qm[3 * i] != 0 || qm[3 * i + 1] != 0 || qm[3 * i + 2] != 0)
                        add_load(snode + i * VENANT_MAX, sw + i * VENANT_MAX, sn[i], qm + 3 * i, lq);
            }
        }
        thx_fem_solve_stats ss;
        THX_TRY(thx_fem_solve_block(ctx, S, phi, load, kb, o->warm, &ss));
        r->it_min = ss.iterations_min < r->it_min ? ss.iterations_min : r->it_min;
        r->it_max = ss.iterations > r->it_max ? ss.iterations : r->it_max;
        r->it_total += ss.iterations_total;
        r->max_residual = fmax(r->max_residual, ss.residual);
        r->t_solve += ss.seconds;
        for (size_t q = 0; q < kb; q++) {
            size_t k = col[c0 + q];
            double *pq = phi + q * nn;
            /* the reference: zero integral over the outer surface */
            double c = 0;
            for (size_t i = 0; i < ns; i++) c += wt[i] * pq[v->surf_node[outer][i]];
            for (size_t i = 0; i < nn; i++)
                if (kind[i]) pq[i] -= c;
            if (by_axis) {
                double *bk = basis + k * keep;
                if (o->keep_volume) memcpy(bk, pq, nn * sizeof *pq);
                else
                    for (size_t i = 0; i < ns; i++) bk[i] = pq[v->surf_node[outer][i]];
            } else {
                for (size_t i = 0; i < ns; i++) r->torso->v[k * ns + i] = pq[v->surf_node[outer][i]];
                if (r->volume) memcpy(r->volume->v + k * nn, pq, nn * sizeof *pq);
            }
        }
        if (o->progress) o->progress(o->user, c0 + kb, n_col);
    }
    if (by_axis) {
        /* frame f = sum over dipoles and axes of the moment times that solution */
        for (size_t f = 0; f < nf; f++) {
            double *out = r->volume ? r->volume->v + f * nn : r->torso->v + f * ns;
            memset(out, 0, keep * sizeof *out);
            const double *q = d->moment + 3 * n * f;
            for (size_t k = 0; k < 3 * n; k++) {
                if (q[k] == 0) continue;
                const double *b = basis + k * keep;
                for (size_t i = 0; i < keep; i++) out[i] += q[k] * b[i];
            }
            if (r->volume)
                for (size_t i = 0; i < ns; i++) r->torso->v[f * ns + i] = out[v->surf_node[outer][i]];
        }
    }
    if (r->it_min == 1 << 30) r->it_min = 0;
    thx_series *outs[2] = {r->torso, r->volume};
    for (int k = 0; k < 2; k++) {
        if (!outs[k]) continue;
        memcpy(outs[k]->time, d->time, nf * sizeof *d->time);
        snprintf(outs[k]->unit, sizeof outs[k]->unit, "mV");
        snprintf(outs[k]->time_unit, sizeof outs[k]->time_unit, "%s", d->time_unit);
    }
    snprintf(r->torso->label, sizeof r->torso->label, "potentials on '%.40s' (dipole sources, %s)", os->name,
             d->separate ? "one frame per dipole" : "all dipoles in every frame");
    if (r->volume) snprintf(r->volume->label, sizeof r->volume->label, "potentials at the volume nodes (dipole sources)");
    thx_fem_system_info(S, &r->n_free, &r->n_prescribed, &r->t_setup);
    r->t_matrix = thx_fem_system_matrix_seconds(S);
    thx_fem_system_describe(S, r->ksp, r->pc, &r->ranks);
    thx_fem_system_factor_info(S, &r->factor);
    r->n_located_by_scan = n_scan;
done:
    if (st != THX_OK) thx_forward_result_free(r);
    thx_fem_system_destroy(&S);
    thx_csr_free(&K);
    free(use);
    free(kind);
    thx_tet_locator_destroy(&loc);
    free(tet);
    free(col);
    free(phi);
    free(load);
    free(basis);
    free(wt);
    free(sn);
    free(snode);
    free(sw);
    free(work);
    free(iface);
    return st;
}
