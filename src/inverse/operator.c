/* Regularization operators on the heart surface: the gradient and the Laplacian of the piecewise-
 * linear potential on its triangles (thorax/inverse/inverse.h, thx_inverse_operator). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "inverse/inverse_impl.h"

/* ∇φ_c of corner c of triangle t (φ the linear hat functions): n × e_c / |n|², e_c the edge
 * opposite c, counterclockwise; returns the area (0 for a degenerate triangle). */
static double tri_grads(const thx_surface *h, size_t t, double g[3][3])
{
    const double *p[3];
    for (int c = 0; c < 3; c++) p[c] = h->xyz + 3 * (size_t)h->tri[3 * t + c];
    double u[3], v[3], n[3];
    for (int d = 0; d < 3; d++) {
        u[d] = p[1][d] - p[0][d];
        v[d] = p[2][d] - p[0][d];
    }
    n[0] = u[1] * v[2] - u[2] * v[1];
    n[1] = u[2] * v[0] - u[0] * v[2];
    n[2] = u[0] * v[1] - u[1] * v[0];
    double nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
    if (!(nn > 0)) return 0;
    for (int c = 0; c < 3; c++) {
        const double *a = p[(c + 1) % 3], *b = p[(c + 2) % 3];
        double e[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
        g[c][0] = (n[1] * e[2] - n[2] * e[1]) / nn;
        g[c][1] = (n[2] * e[0] - n[0] * e[2]) / nn;
        g[c][2] = (n[0] * e[1] - n[1] * e[0]) / nn;
    }
    return 0.5 * sqrt(nn);
}

thx_status thx_inv_gradient(thx_ctx *ctx, const thx_surface *heart, double **G)
{
    size_t n = heart->n_nodes, r = 3 * heart->n_tris;
    *G = NULL;
    size_t cnt = r * n;
    double *g = thx_calloc(ctx, cnt ? cnt : 1, sizeof *g);
    if (!g) return THX_ENOMEM;
    for (size_t t = 0; t < heart->n_tris; t++) {
        double gr[3][3], a = tri_grads(heart, t, gr);
        if (a == 0) {
            free(g);
            return thx_error(ctx, THX_EGEOM, "surface \"%s\": triangle %zu has zero area; no surface gradient there",
                             heart->name, t + 1);
        }
        double w = sqrt(a);
        for (int c = 0; c < 3; c++)
            for (int d = 0; d < 3; d++) g[(size_t)heart->tri[3 * t + c] * r + 3 * t + (size_t)d] += w * gr[c][d];
    }
    *G = g;
    return THX_OK;
}

thx_status thx_inverse_operator(thx_ctx *ctx, const thx_surface *heart, int order, double **M)
{
    size_t n = heart->n_nodes;
    *M = NULL;
    if (order < 1 || order > 2) return thx_error(ctx, THX_EINPUT, "regularization order %d: 1 or 2 here", order);
    double *K = thx_calloc(ctx, n * n, sizeof *K), *mass = thx_calloc(ctx, n, sizeof *mass);
    if (!K || !mass) {
        free(K);
        free(mass);
        return THX_ENOMEM;
    }
    for (size_t t = 0; t < heart->n_tris; t++) {
        double gr[3][3], a = tri_grads(heart, t, gr);
        if (a == 0) {
            free(K);
            free(mass);
            return thx_error(ctx, THX_EGEOM, "surface \"%s\": triangle %zu has zero area; no surface gradient there",
                             heart->name, t + 1);
        }
        for (int i = 0; i < 3; i++) {
            size_t I = (size_t)heart->tri[3 * t + i];
            mass[I] += a / 3;
            for (int j = 0; j < 3; j++) {
                size_t J = (size_t)heart->tri[3 * t + j];
                K[J * n + I] += a * (gr[i][0] * gr[j][0] + gr[i][1] * gr[j][1] + gr[i][2] * gr[j][2]);
            }
        }
    }
    if (order == 1) {
        free(mass);
        *M = K;
        return THX_OK;
    }
    for (size_t i = 0; i < n; i++)
        if (!(mass[i] > 0)) {
            free(K);
            free(mass);
            return thx_error(ctx, THX_EGEOM, "surface \"%s\": node %zu is in no triangle; no Laplacian there",
                             heart->name, i + 1);
        }
    double *DK = thx_malloc(ctx, n * n * sizeof *DK), *M2 = thx_malloc(ctx, n * n * sizeof *M2);
    if (!DK || !M2) {
        free(K);
        free(mass);
        free(DK);
        free(M2);
        return THX_ENOMEM;
    }
    for (size_t j = 0; j < n; j++)
        for (size_t i = 0; i < n; i++) DK[j * n + i] = K[j * n + i] / mass[i];
    thx_inv_gemm('N', 'N', n, n, n, K, n, DK, n, 0.0, M2, n);
    free(K);
    free(DK);
    free(mass);
    *M = M2;
    return THX_OK;
}
