/*
 * Stiffness assembly for linear tetrahedra (thorax/fem/fem.h), plain C + OpenMP.
 *
 * Two passes, both parallel without atomics: the element matrices (10 unique
 * entries of the symmetric 4 x 4 |T| G sigma G^T per tetrahedron) are computed
 * per tetrahedron; then each row gathers from the tetrahedra around its node
 * (a node -> tetrahedra index), so each row is written by one thread only.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/fem/fem.h"
void thx_csr_free(thx_csr *a)
{
    if (!a) return;
    free(a->row);
    free(a->col);
    free(a->val);
    memset(a, 0, sizeof *a);
}

void thx_csr_mul(const thx_csr *a, const double *x, double *y)
{
#pragma omp parallel for schedule(static)
    for (long i = 0; i < (long)a->n_rows; i++) {
        double s = 0;
        for (int64_t k = a->row[i]; k < a->row[i + 1]; k++) s += a->val[k] * x[a->col[k]];
        y[i] = s;
    }
}

/* Symmetric positive definite: leading principal minors positive (Sylvester), symmetric to 1e-12. */
static int spd(const double s[9])
{
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            if (fabs(s[3 * i + j] - s[3 * j + i]) > 1e-12 * (fabs(s[3 * i + j]) + fabs(s[3 * j + i]) + 1e-300)) return 0;
    double m1 = s[0], m2 = s[0] * s[4] - s[1] * s[3];
    double m3 = s[0] * (s[4] * s[8] - s[5] * s[7]) - s[1] * (s[3] * s[8] - s[5] * s[6]) + s[2] * (s[3] * s[7] - s[4] * s[6]);
    return m1 > 0 && m2 > 0 && m3 > 0 && isfinite(m3);
}

/* Gradients of the barycentric functions (rows, 1/mm) and the volume (mm^3) of tetrahedron q. */
double thx_fem_tet_gradients(const double *xyz, const int32_t *q, double g[4][3])
{
    const double *p0 = xyz + 3 * (size_t)q[0];
    double e[3][3];
    for (int k = 0; k < 3; k++)
        for (int c = 0; c < 3; c++) e[k][c] = xyz[3 * (size_t)q[k + 1] + c] - p0[c];
    /* rows of the inverse of E (rows e1, e2, e3) transposed: grad l_k = column k of E^-1 */
    double det = e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) - e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0]) +
                 e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0]);
    double inv[3][3];
    inv[0][0] = (e[1][1] * e[2][2] - e[1][2] * e[2][1]) / det;
    inv[0][1] = (e[0][2] * e[2][1] - e[0][1] * e[2][2]) / det;
    inv[0][2] = (e[0][1] * e[1][2] - e[0][2] * e[1][1]) / det;
    inv[1][0] = (e[1][2] * e[2][0] - e[1][0] * e[2][2]) / det;
    inv[1][1] = (e[0][0] * e[2][2] - e[0][2] * e[2][0]) / det;
    inv[1][2] = (e[0][2] * e[1][0] - e[0][0] * e[1][2]) / det;
    inv[2][0] = (e[1][0] * e[2][1] - e[1][1] * e[2][0]) / det;
    inv[2][1] = (e[0][1] * e[2][0] - e[0][0] * e[2][1]) / det;
    inv[2][2] = (e[0][0] * e[1][1] - e[0][1] * e[1][0]) / det;
    /* x = p0 + E^T lambda' => lambda' = E^-T (x - p0): grad lambda_k (k = 1..3) = row k-1 of E^-T = column of E^-1 */
    for (int k = 0; k < 3; k++)
        for (int c = 0; c < 3; c++) g[k + 1][c] = inv[c][k];
    for (int c = 0; c < 3; c++) g[0][c] = -(g[1][c] + g[2][c] + g[3][c]);
    return det / 6.0;
}

thx_status thx_fem_active_nodes(thx_ctx *ctx, const thx_volume *v, const unsigned char *use_region, unsigned char **active)
{
    unsigned char *a = thx_calloc(ctx, v->n_nodes ? v->n_nodes : 1, 1);
    if (!a) return THX_ENOMEM;
    for (size_t t = 0; t < v->n_tets; t++) {
        int32_t r = v->region[t];
        if (use_region && (r < 0 || (size_t)r >= v->n_regions || !use_region[r])) continue;
        for (int k = 0; k < 4; k++) a[v->tet[4 * t + k]] = 1;
    }
    *active = a;
    return THX_OK;
}

thx_status thx_fem_assemble(thx_ctx *ctx, const thx_volume *v, const unsigned char *use_region, thx_csr *K)
{
    return thx_fem_assemble_rows(ctx, v, use_region, NULL, K);
}

thx_status thx_fem_assemble_rows(thx_ctx *ctx, const thx_volume *v, const unsigned char *use_region,
                                 const unsigned char *rows, thx_csr *K)
{
    memset(K, 0, sizeof *K);
    size_t nn = v->n_nodes, nt = v->n_tets;
    if (nn > INT32_MAX) return thx_error(ctx, THX_EINPUT, "fem: %zu nodes: more than 32-bit indices hold", nn);
    for (size_t r = 0; r < v->n_regions; r++) {
        if (use_region && !use_region[r]) continue;
        if (!spd(v->regions[r].sigma))
            return thx_error(ctx, THX_EINPUT,
                             "fem: region '%s': the conductivity tensor is not symmetric positive definite "
                             "(%g %g %g; %g %g %g; %g %g %g S/m)",
                             v->regions[r].name, v->regions[r].sigma[0], v->regions[r].sigma[1], v->regions[r].sigma[2],
                             v->regions[r].sigma[3], v->regions[r].sigma[4], v->regions[r].sigma[5],
                             v->regions[r].sigma[6], v->regions[r].sigma[7], v->regions[r].sigma[8]);
    }
    thx_status st = THX_OK;
    double *ke = NULL;
    size_t *nstart = NULL;
    int32_t *ntet = NULL;
    unsigned char *use = NULL;
    int64_t *row = NULL;
    int32_t *col = NULL;
    double *val = NULL;
    /* element matrices, upper triangle (00 01 02 03 11 12 13 22 23 33) */
    ke = thx_malloc(ctx, 10 * (nt ? nt : 1) * sizeof *ke);
    use = thx_malloc(ctx, nt ? nt : 1);
    if (!ke || !use) { st = THX_ENOMEM; goto done; }
    long bad = -1;
#pragma omp parallel for schedule(static)
    for (long t = 0; t < (long)nt; t++) {
        int32_t r = v->region[t];
        use[t] = !use_region || (r >= 0 && (size_t)r < v->n_regions && use_region[r]);
        if (r < 0 || (size_t)r >= v->n_regions) use[t] = 0;
        if (rows && use[t]) { /* only the tetrahedra around a row asked for */
            const int32_t *q = v->tet + 4 * t;
            use[t] = rows[q[0]] || rows[q[1]] || rows[q[2]] || rows[q[3]];
        }
        if (!use[t]) continue;
        double g[4][3];
        double vol = thx_fem_tet_gradients(v->xyz, v->tet + 4 * t, g);
        if (!(vol > 0)) {
#pragma omp critical
            if (bad < 0 || t < bad) bad = t;
            continue;
        }
        const double *s = v->regions[r].sigma;
        double sg[4][3];
        for (int a = 0; a < 4; a++)
            for (int c = 0; c < 3; c++) sg[a][c] = s[3 * c] * g[a][0] + s[3 * c + 1] * g[a][1] + s[3 * c + 2] * g[a][2];
        int k = 0;
        for (int a = 0; a < 4; a++)
            for (int b = a; b < 4; b++) ke[10 * t + k++] = vol * (g[a][0] * sg[b][0] + g[a][1] * sg[b][1] + g[a][2] * sg[b][2]);
    }
    if (bad >= 0) {
        st = thx_error(ctx, THX_EGEOM, "fem: tetrahedron %ld has non-positive volume (run thorax check)", bad + 1);
        goto done;
    }
    /* node -> tetrahedra */
    nstart = thx_calloc(ctx, nn + 1, sizeof *nstart);
    if (!nstart) { st = THX_ENOMEM; goto done; }
    for (size_t t = 0; t < nt; t++)
        if (use[t])
            for (int k = 0; k < 4; k++) nstart[v->tet[4 * t + k] + 1]++;
    for (size_t i = 0; i < nn; i++) nstart[i + 1] += nstart[i];
    ntet = thx_malloc(ctx, (nstart[nn] ? nstart[nn] : 1) * sizeof *ntet);
    if (!ntet) { st = THX_ENOMEM; goto done; }
    {
        size_t *fill = thx_malloc(ctx, (nn ? nn : 1) * sizeof *fill);
        if (!fill) { st = THX_ENOMEM; goto done; }
        memcpy(fill, nstart, nn * sizeof *fill);
        for (size_t t = 0; t < nt; t++)
            if (use[t])
                for (int k = 0; k < 4; k++) ntet[fill[v->tet[4 * t + k]]++] = (int32_t)t;
        free(fill);
    }
    /* row lengths: distinct neighbours (the node itself included), deduplicated with a per-thread mark */
    row = thx_calloc(ctx, nn + 1, sizeof *row);
    if (!row) { st = THX_ENOMEM; goto done; }
    int fail = 0;
#pragma omp parallel
    {
        int32_t *mark = malloc((nn ? nn : 1) * sizeof *mark);
        if (!mark) {
#pragma omp atomic write
            fail = 1;
        } else {
            for (size_t i = 0; i < nn; i++) mark[i] = -1;
#pragma omp for schedule(dynamic, 1024)
            for (long i = 0; i < (long)nn; i++) {
                int64_t u = 0;
                if (rows && !rows[i]) continue; /* a row not asked for stays empty */
                for (size_t k = nstart[i]; k < nstart[i + 1]; k++)
                    for (int c = 0; c < 4; c++) {
                        int32_t j = v->tet[4 * (size_t)ntet[k] + c];
                        if (mark[j] != (int32_t)i) { mark[j] = (int32_t)i; u++; }
                    }
                row[i + 1] = u;
            }
            free(mark);
        }
    }
    if (fail) { st = THX_ENOMEM; goto done; }
    for (size_t i = 0; i < nn; i++) row[i + 1] += row[i];
    col = thx_malloc(ctx, (row[nn] ? (size_t)row[nn] : 1) * sizeof *col);
    val = thx_calloc(ctx, row[nn] ? (size_t)row[nn] : 1, sizeof *val);
    if (!col || !val) { st = THX_ENOMEM; goto done; }
#pragma omp parallel
    {
        int32_t *pos = malloc((nn ? nn : 1) * sizeof *pos); /* column -> slot in the current row, or -1 */
        if (!pos) {
#pragma omp atomic write
            fail = 1;
        } else {
            for (size_t i = 0; i < nn; i++) pos[i] = -1;
#pragma omp for schedule(dynamic, 1024)
            for (long i = 0; i < (long)nn; i++) {
                int32_t *c = col + row[i];
                double *a = val + row[i];
                int32_t u = 0;
                if (rows && !rows[i]) continue;
                for (size_t k = nstart[i]; k < nstart[i + 1]; k++)
                    for (int q = 0; q < 4; q++) {
                        int32_t j = v->tet[4 * (size_t)ntet[k] + q];
                        if (pos[j] < 0) { pos[j] = 0; c[u++] = j; }
                    }
                /* sorted columns (insertion sort: rows are short) */
                for (int32_t x = 1; x < u; x++) {
                    int32_t key = c[x], y = x - 1;
                    while (y >= 0 && c[y] > key) { c[y + 1] = c[y]; y--; }
                    c[y + 1] = key;
                }
                for (int32_t x = 0; x < u; x++) pos[c[x]] = x;
                static const int idx[4][4] = {{0, 1, 2, 3}, {1, 4, 5, 6}, {2, 5, 7, 8}, {3, 6, 8, 9}};
                for (size_t k = nstart[i]; k < nstart[i + 1]; k++) {
                    size_t t = (size_t)ntet[k];
                    const int32_t *q = v->tet + 4 * t;
                    int li = 0;
                    while (q[li] != i) li++;
                    for (int b2 = 0; b2 < 4; b2++) a[pos[q[b2]]] += ke[10 * t + idx[li][b2]];
                }
                for (int32_t x = 0; x < u; x++) pos[c[x]] = -1;
            }
            free(pos);
        }
    }
    if (fail) { st = THX_ENOMEM; goto done; }
    K->n_rows = K->n_cols = (int32_t)nn;
    K->row = row;
    K->col = col;
    K->val = val;
    row = NULL;
    col = NULL;
    val = NULL;
done:
    free(ke);
    free(use);
    free(nstart);
    free(ntet);
    free(row);
    free(col);
    free(val);
    return st;
}

void thx_fem_currents(const thx_volume *v, const unsigned char *use_region, const double *phi, double *j_tet,
                      double *j_node)
{
    size_t nt = v->n_tets, nn = v->n_nodes;
    double *w = NULL;
    if (j_node) {
        memset(j_node, 0, 3 * nn * sizeof *j_node);
        w = calloc(nn ? nn : 1, sizeof *w);
    }
    for (size_t t = 0; t < nt; t++) {
        int32_t r = v->region[t];
        int use = r >= 0 && (size_t)r < v->n_regions && (!use_region || use_region[r]);
        double J[3] = {0, 0, 0}, vol = 0;
        if (use) {
            double g[4][3];
            vol = thx_fem_tet_gradients(v->xyz, v->tet + 4 * t, g);
            double gp[3] = {0, 0, 0};
            for (int k = 0; k < 4; k++)
                for (int c = 0; c < 3; c++) gp[c] += phi[v->tet[4 * t + k]] * g[k][c];
            const double *s = v->regions[r].sigma;
            /* grad in V/mm -> V/m: x 1000 */
            for (int c = 0; c < 3; c++) J[c] = -1000.0 * (s[3 * c] * gp[0] + s[3 * c + 1] * gp[1] + s[3 * c + 2] * gp[2]);
        }
        if (j_tet) memcpy(j_tet + 3 * t, J, sizeof J);
        if (j_node && w && use)
            for (int k = 0; k < 4; k++) {
                int32_t i = v->tet[4 * t + k];
                for (int c = 0; c < 3; c++) j_node[3 * (size_t)i + c] += vol * J[c];
                w[i] += vol;
            }
    }
    if (j_node && w)
        for (size_t i = 0; i < nn; i++)
            if (w[i] > 0)
                for (int c = 0; c < 3; c++) j_node[3 * i + c] /= w[i];
    free(w);
}
