/*
 * Verification runs of the finite-element solver against closed forms
 * (thorax verify; tests/test_fem_verify.c; docs/validation.md).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/fem.h"
#include "thorax/verify.h"

static double mean_edge(const thx_volume *v)
{
    static const int e[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
    double s = 0;
    for (size_t t = 0; t < v->n_tets; t++)
        for (int k = 0; k < 6; k++) {
            const double *p = v->xyz + 3 * (size_t)v->tet[4 * t + e[k][0]], *q = v->xyz + 3 * (size_t)v->tet[4 * t + e[k][1]];
            s += sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]));
        }
    return v->n_tets ? s / (6.0 * (double)v->n_tets) : 0;
}

thx_status thx_verify_shells(thx_ctx *ctx, int l, double s1, double s2, int n, thx_verify_row *row)
{
    const double a = 40, b = 70, c = 100;
    memset(row, 0, sizeof *row);
    row->n = n;
    thx_volume *v = NULL;
    int32_t *inner = NULL, *outer = NULL;
    size_t ni = 0, no = 0;
    thx_csr K;
    memset(&K, 0, sizeof K);
    unsigned char *kind = NULL;
    double *phi = NULL, *num = NULL, *ref = NULL, *Kp = NULL;
    thx_fem_system *S = NULL;
    thx_status st = THX_OK;
    int nr = n / 2 > 0 ? n / 2 : 1;
    THX_TRY(thx_shells_mesh(ctx, a, b, c, s1, s2, n, nr, nr, &v, &inner, &ni, &outer, &no));
    row->nodes = v->n_nodes;
    row->tets = v->n_tets;
    row->h = mean_edge(v);
    THX_TRY(thx_fem_assemble(ctx, v, NULL, &K));
    kind = thx_malloc(ctx, v->n_nodes);
    phi = thx_calloc(ctx, v->n_nodes, sizeof *phi);
    num = thx_malloc(ctx, (no ? no : 1) * sizeof *num);
    ref = thx_malloc(ctx, (no ? no : 1) * sizeof *ref);
    Kp = thx_malloc(ctx, v->n_nodes * sizeof *Kp);
    if (!kind || !phi || !num || !ref || !Kp) { st = THX_ENOMEM; goto done; }
    memset(kind, 1, v->n_nodes);
    for (size_t k = 0; k < ni; k++) {
        const double *p = v->xyz + 3 * (size_t)inner[k];
        double r = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
        kind[inner[k]] = 2;
        phi[inner[k]] = thx_legendre(l, p[2] / r);
    }
    THX_TRY(thx_fem_system_create(ctx, &K, kind, 0, &S));
    thx_fem_solve_stats ss;
    THX_TRY(thx_fem_solve(ctx, S, phi, NULL, 0, &ss));
    row->iterations = ss.iterations;
    row->seconds = ss.seconds;
    double emax = 0, rmax = 0;
    for (size_t k = 0; k < no; k++) {
        const double *p = v->xyz + 3 * (size_t)outer[k];
        double r = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
        num[k] = phi[outer[k]];
        /* the analytic solution at the node's angle on the sphere r = c (the node lies on it) */
        ref[k] = thx_shells_potential(l, a, b, c, s1, s2, c, p[2] / r);
        emax = fmax(emax, fabs(num[k] - ref[k]));
        rmax = fmax(rmax, fabs(ref[k]));
    }
    row->rdm = thx_rdm(num, ref, no);
    row->mag = thx_mag(num, ref, no);
    row->max_err = rmax > 0 ? emax / rmax : emax;
    /* conservation: the current leaving the inner sphere sums to zero (the outer one is insulated) */
    thx_csr_mul(&K, phi, Kp);
    double net = 0, mag = 0;
    for (size_t k = 0; k < ni; k++) {
        net += Kp[inner[k]];
        mag += fabs(Kp[inner[k]]);
    }
    row->net_current = mag > 0 ? fabs(net) / mag : fabs(net);
done:
    thx_fem_system_destroy(&S);
    thx_csr_free(&K);
    thx_volume_destroy(&v);
    free(inner);
    free(outer);
    free(kind);
    free(phi);
    free(num);
    free(ref);
    free(Kp);
    return st;
}

thx_status thx_verify_slab(thx_ctx *ctx, double *rel_err, size_t *nodes)
{
    /* skeletal muscle-like: fibres tilted in the x-z plane, 4:1 along the fibre */
    const double th = 0.5;
    double ct = cos(th), sn = sin(th), sl = 0.5, st_ = 0.125;
    double sigma[9] = {sl * ct * ct + st_ * sn * sn, 0, (sl - st_) * ct * sn, 0, st_, 0, (sl - st_) * ct * sn, 0,
                       sl * sn * sn + st_ * ct * ct};
    thx_volume *v = NULL;
    int32_t *ends = NULL;
    size_t ne = 0;
    thx_csr K;
    memset(&K, 0, sizeof K);
    unsigned char *kind = NULL;
    double *phi = NULL;
    thx_fem_system *S = NULL;
    thx_status st = THX_OK;
    THX_TRY(thx_slab_mesh(ctx, 60, 30, 20, 12, 6, 4, sigma, &v, &ends, &ne));
    THX_TRY(thx_fem_assemble(ctx, v, NULL, &K));
    kind = thx_malloc(ctx, v->n_nodes);
    phi = thx_calloc(ctx, v->n_nodes, sizeof *phi);
    if (!kind || !phi) { st = THX_ENOMEM; goto done; }
    memset(kind, 1, v->n_nodes);
    for (size_t k = 0; k < ne; k++) {
        kind[ends[k]] = 2;
        phi[ends[k]] = thx_slab_potential(sigma, v->xyz + 3 * (size_t)ends[k]);
    }
    THX_TRY(thx_fem_system_create(ctx, &K, kind, 0, &S));
    thx_fem_solve_stats ss;
    THX_TRY(thx_fem_solve(ctx, S, phi, NULL, 0, &ss));
    double e = 0, m = 0;
    for (size_t i = 0; i < v->n_nodes; i++) {
        double x = thx_slab_potential(sigma, v->xyz + 3 * i);
        e = fmax(e, fabs(phi[i] - x));
        m = fmax(m, fabs(x));
    }
    *rel_err = m > 0 ? e / m : e;
    if (nodes) *nodes = v->n_nodes;
done:
    thx_fem_system_destroy(&S);
    thx_csr_free(&K);
    thx_volume_destroy(&v);
    free(ends);
    free(kind);
    free(phi);
    return st;
}
