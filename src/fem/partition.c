/*
 * A partition of a volume mesh's nodes among MPI ranks (thx_fem_partition, thorax/fem/fem.h):
 * recursive coordinate bisection. Chosen over a graph partitioner (METIS, ParMETIS) because its
 * parts are boxes: convex, so that sort-last rendering can order them along every ray (volume
 * rendering's ordered blending), and the same cut serves the solve and the pictures; its cut is
 * close to a graph partitioner's on a tetrahedral mesh of even density (docs/design/parallel.md).
 */
#include <stdlib.h>
#include <string.h>

#include "thorax/fem/fem.h"

typedef struct {
    const double *xyz;
    int axis;
} cut_of;

/* (coordinate on the axis, node number): a total order, so the cut does not depend on qsort. */
static int by_axis(const void *a, const void *b, void *user)
{
    const cut_of *c = user;
    int32_t i = *(const int32_t *)a, j = *(const int32_t *)b;
    double x = c->xyz[3 * (size_t)i + c->axis], y = c->xyz[3 * (size_t)j + c->axis];
    if (x != y) return x < y ? -1 : 1;
    return (i > j) - (i < j);
}

/* Nodes idx[0..n) into parts p0 .. p0 + np - 1. */
static void bisect(const double *xyz, const unsigned char *kind, int32_t *idx, size_t n, int p0, int np, int32_t *part)
{
    if (np == 1 || n == 0) {
        for (size_t k = 0; k < n; k++) part[idx[k]] = p0;
        return;
    }
    double lo[3], hi[3];
    for (int c = 0; c < 3; c++) lo[c] = hi[c] = xyz[3 * (size_t)idx[0] + c];
    for (size_t k = 1; k < n; k++)
        for (int c = 0; c < 3; c++) {
            double x = xyz[3 * (size_t)idx[k] + c];
            if (x < lo[c]) lo[c] = x;
            if (x > hi[c]) hi[c] = x;
        }
    cut_of cut = {xyz, 0};
    for (int c = 1; c < 3; c++)
        if (hi[c] - lo[c] > hi[cut.axis] - lo[cut.axis]) cut.axis = c;
    qsort_r(idx, n, sizeof *idx, by_axis, &cut);
    int left = np / 2;
    size_t free_total = 0;
    for (size_t k = 0; k < n; k++) free_total += kind[idx[k]] == 1;
    /* the left side's share of the free nodes, rounded: left / np of them */
    size_t want = (free_total * (size_t)left + (size_t)np / 2) / (size_t)np, seen = 0, k = 0;
    while (k < n && seen < want) seen += kind[idx[k++]] == 1;
    /* the prescribed and other active nodes just past the cut go with the left side too, up to the
       next free node (they own no row) */
    while (k < n && kind[idx[k]] != 1) k++;
    bisect(xyz, kind, idx, k, p0, left, part);
    bisect(xyz, kind, idx + k, n - k, p0 + left, np - left, part);
}

thx_status thx_fem_partition(thx_ctx *ctx, const thx_volume *v, const unsigned char *kind, int n_parts, int32_t *part)
{
    if (n_parts < 1) return thx_error(ctx, THX_EINPUT, "fem: a partition into %d parts", n_parts);
    size_t nn = v->n_nodes, n = 0;
    int32_t *idx = thx_malloc(ctx, (nn ? nn : 1) * sizeof *idx);
    if (!idx) return THX_ENOMEM;
    for (size_t i = 0; i < nn; i++) {
        part[i] = -1;
        if (kind[i]) idx[n++] = (int32_t)i;
    }
    bisect(v->xyz, kind, idx, n, 0, n_parts, part);
    free(idx);
    return THX_OK;
}
