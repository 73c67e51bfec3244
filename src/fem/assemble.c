/*
 * Stiffness assembly for linear tetrahedra (thorax/fem/fem.h), plain C + OpenMP.
 *
 * Two passes, both parallel without atomics: the element matrices (10 unique
 * entries of the symmetric 4 x 4 |T| G sigma G^T per tetrahedron) are computed
 * per tetrahedron; then each row gathers from the tetrahedra around its node
 * (a node -> tetrahedra index), so each row is written by one thread only.
 *
 * Both passes visit the tetrahedra and the rows in space-filling order (a Morton
 * code of the centroid, of the node): a mesh's own numbering may scatter a node's
 * tetrahedra over the whole file (the high phantom's: a million tetrahedra apart
 * for half its nodes), and every gather was then a miss in the cache. A row's
 * sum runs over its tetrahedra in that order, the same whatever rows are asked
 * for (the partitioned assembly sums as the whole does).
 */
#include <math.h>
#include <stdint.h>
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

/* The 10 bits of v spread to every third bit (bit k -> bit 3k). */
static uint32_t spread3(uint32_t v)
{
    v &= 0x3ff;
    v = (v | (v << 16)) & 0x030000ff;
    v = (v | (v << 8)) & 0x0300f00f;
    v = (v | (v << 4)) & 0x030c30c3;
    v = (v | (v << 2)) & 0x09249249;
    return v;
}

/* A Morton code of p in the box [lo, lo + 1 / inv) (10 bits an axis). */
static uint32_t morton(const double p[3], const double lo[3], const double inv[3])
{
    uint32_t c[3];
    for (int a = 0; a < 3; a++) {
        double u = (p[a] - lo[a]) * inv[a] * 1024.0;
        c[a] = u <= 0 ? 0 : u >= 1023 ? 1023 : (uint32_t)u;
    }
    return spread3(c[0]) | spread3(c[1]) << 1 | spread3(c[2]) << 2;
}

/* idx[0 .. n-1] sorted by key (30 bits), stably: three passes of 10 bits. key2, idx2: n of scratch. */
static void sort_by_key(uint32_t *key, int32_t *idx, size_t n, uint32_t *key2, int32_t *idx2)
{
    for (int pass = 0; pass < 3; pass++) {
        size_t count[1025] = {0};
        int sh = 10 * pass;
        for (size_t i = 0; i < n; i++) count[((key[i] >> sh) & 1023) + 1]++;
        for (int b = 0; b < 1024; b++) count[b + 1] += count[b];
        for (size_t i = 0; i < n; i++) {
            size_t at = count[(key[i] >> sh) & 1023]++;
            key2[at] = key[i];
            idx2[at] = idx[i];
        }
        memcpy(key, key2, n * sizeof *key);
        memcpy(idx, idx2, n * sizeof *idx);
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
    int32_t *ntet = NULL, *order = NULL, *tq = NULL, *rows_order = NULL, *idx2 = NULL;
    uint32_t *key = NULL, *key2 = NULL;
    unsigned char *use = NULL;
    int64_t *row = NULL;
    int32_t *col = NULL;
    double *val = NULL;
    use = thx_malloc(ctx, nt ? nt : 1);
    if (!use) { st = THX_ENOMEM; goto done; }
#pragma omp parallel for schedule(static)
    for (long t = 0; t < (long)nt; t++) {
        int32_t r = v->region[t];
        use[t] = !use_region || (r >= 0 && (size_t)r < v->n_regions && use_region[r]);
        if (r < 0 || (size_t)r >= v->n_regions) use[t] = 0;
        if (rows && use[t]) { /* only the tetrahedra around a row asked for */
            const int32_t *q = v->tet + 4 * t;
            use[t] = rows[q[0]] || rows[q[1]] || rows[q[2]] || rows[q[3]];
        }
    }
    /* the tetrahedra used, in the Morton order of their centroids; the rows in that of their nodes */
    size_t m = 0;
    for (size_t t = 0; t < nt; t++) m += use[t];
    size_t big = (m > nn ? m : nn) + 1;
    order = thx_malloc(ctx, (m ? m : 1) * sizeof *order);
    rows_order = thx_malloc(ctx, (nn ? nn : 1) * sizeof *rows_order);
    key = thx_malloc(ctx, big * sizeof *key);
    key2 = thx_malloc(ctx, big * sizeof *key2);
    idx2 = thx_malloc(ctx, big * sizeof *idx2);
    if (!order || !rows_order || !key || !key2 || !idx2) { st = THX_ENOMEM; goto done; }
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY}, inv[3];
    for (size_t i = 0; i < nn; i++)
        for (int c = 0; c < 3; c++) {
            double x = v->xyz[3 * i + (size_t)c];
            if (x < lo[c]) lo[c] = x;
            if (x > hi[c]) hi[c] = x;
        }
    for (int c = 0; c < 3; c++) inv[c] = hi[c] > lo[c] ? 1.0 / (hi[c] - lo[c]) : 1.0;
    for (size_t t = 0, k = 0; t < nt; t++)
        if (use[t]) order[k++] = (int32_t)t;
#pragma omp parallel for schedule(static)
    for (long k = 0; k < (long)m; k++) {
        const int32_t *q = v->tet + 4 * (size_t)order[k];
        double c[3];
        for (int a = 0; a < 3; a++)
            c[a] = 0.25 * (v->xyz[3 * (size_t)q[0] + a] + v->xyz[3 * (size_t)q[1] + a] + v->xyz[3 * (size_t)q[2] + a] +
                           v->xyz[3 * (size_t)q[3] + a]);
        key[k] = morton(c, lo, inv);
    }
    sort_by_key(key, order, m, key2, idx2);
#pragma omp parallel for schedule(static)
    for (long i = 0; i < (long)nn; i++) {
        key[i] = morton(v->xyz + 3 * (size_t)i, lo, inv);
        rows_order[i] = (int32_t)i;
    }
    sort_by_key(key, rows_order, nn, key2, idx2);
    free(key);
    free(key2);
    free(idx2);
    key = key2 = NULL;
    idx2 = NULL;
    /* element matrices and their nodes in that order, upper triangle (00 01 02 03 11 12 13 22 23 33) */
    ke = thx_malloc(ctx, 10 * (m ? m : 1) * sizeof *ke);
    tq = thx_malloc(ctx, 4 * (m ? m : 1) * sizeof *tq);
    if (!ke || !tq) { st = THX_ENOMEM; goto done; }
    long bad = -1;
#pragma omp parallel for schedule(static)
    for (long k = 0; k < (long)m; k++) {
        size_t t = (size_t)order[k];
        memcpy(tq + 4 * k, v->tet + 4 * t, 4 * sizeof *tq);
        double g[4][3];
        double vol = thx_fem_tet_gradients(v->xyz, v->tet + 4 * t, g);
        if (!(vol > 0)) {
#pragma omp critical
            if (bad < 0 || (long)t < bad) bad = (long)t;
            continue;
        }
        const double *sg0 = v->regions[v->region[t]].sigma;
        double sg[4][3];
        for (int a = 0; a < 4; a++)
            for (int c = 0; c < 3; c++) sg[a][c] = sg0[3 * c] * g[a][0] + sg0[3 * c + 1] * g[a][1] + sg0[3 * c + 2] * g[a][2];
        int e = 0;
        for (int a = 0; a < 4; a++)
            for (int b = a; b < 4; b++) ke[10 * k + e++] = vol * (g[a][0] * sg[b][0] + g[a][1] * sg[b][1] + g[a][2] * sg[b][2]);
    }
    if (bad >= 0) {
        st = thx_error(ctx, THX_EGEOM, "fem: tetrahedron %ld has non-positive volume (run thorax check)", bad + 1);
        goto done;
    }
    /* node -> tetrahedra (their places in that order, ascending) */
    nstart = thx_calloc(ctx, nn + 1, sizeof *nstart);
    if (!nstart) { st = THX_ENOMEM; goto done; }
    for (size_t k = 0; k < m; k++)
        for (int c = 0; c < 4; c++) nstart[tq[4 * k + (size_t)c] + 1]++;
    for (size_t i = 0; i < nn; i++) nstart[i + 1] += nstart[i];
    ntet = thx_malloc(ctx, (nstart[nn] ? nstart[nn] : 1) * sizeof *ntet);
    if (!ntet) { st = THX_ENOMEM; goto done; }
    {
        size_t *fill = thx_malloc(ctx, (nn ? nn : 1) * sizeof *fill);
        if (!fill) { st = THX_ENOMEM; goto done; }
        memcpy(fill, nstart, nn * sizeof *fill);
        for (size_t k = 0; k < m; k++)
            for (int c = 0; c < 4; c++) ntet[fill[tq[4 * k + (size_t)c]]++] = (int32_t)k;
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
            for (long x = 0; x < (long)nn; x++) {
                int32_t i = rows_order[x];
                int64_t u = 0;
                if (rows && !rows[i]) continue; /* a row not asked for stays empty */
                for (size_t k = nstart[i]; k < nstart[i + 1]; k++)
                    for (int c = 0; c < 4; c++) {
                        int32_t j = tq[4 * (size_t)ntet[k] + c];
                        if (mark[j] != i) { mark[j] = i; u++; }
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
            for (long x = 0; x < (long)nn; x++) {
                int32_t i = rows_order[x];
                int32_t *c = col + row[i];
                double *a = val + row[i];
                int32_t u = 0;
                if (rows && !rows[i]) continue;
                for (size_t k = nstart[i]; k < nstart[i + 1]; k++)
                    for (int q = 0; q < 4; q++) {
                        int32_t j = tq[4 * (size_t)ntet[k] + q];
                        if (pos[j] < 0) { pos[j] = 0; c[u++] = j; }
                    }
                /* sorted columns (insertion sort: rows are short) */
                for (int32_t y = 1; y < u; y++) {
                    int32_t kk = c[y], z = y - 1;
                    while (z >= 0 && c[z] > kk) { c[z + 1] = c[z]; z--; }
                    c[z + 1] = kk;
                }
                for (int32_t y = 0; y < u; y++) pos[c[y]] = y;
                static const int idx[4][4] = {{0, 1, 2, 3}, {1, 4, 5, 6}, {2, 5, 7, 8}, {3, 6, 8, 9}};
                for (size_t k = nstart[i]; k < nstart[i + 1]; k++) {
                    size_t e = (size_t)ntet[k];
                    const int32_t *q = tq + 4 * e;
                    int li = 0;
                    while (q[li] != i) li++;
                    for (int b2 = 0; b2 < 4; b2++) a[pos[q[b2]]] += ke[10 * e + idx[li][b2]];
                }
                for (int32_t y = 0; y < u; y++) pos[c[y]] = -1;
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
    free(order);
    free(tq);
    free(rows_order);
    free(key);
    free(key2);
    free(idx2);
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
