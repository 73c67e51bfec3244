/*
 * A partition of a volume mesh's nodes among MPI ranks (thx_fem_partition, thorax/fem/fem.h):
 * recursive coordinate bisection. Chosen over a graph partitioner (METIS, ParMETIS) because its
 * parts are boxes: convex, so that sort-last rendering can order them along every ray (volume
 * rendering's ordered blending), and the same cut serves the solve and the pictures; its cut is
 * close to a graph partitioner's on a tetrahedral mesh of even density (docs/design/parallel.md).
 */
#include <math.h>
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

/* Nodes idx[0..n) into parts p0 .. p0 + np - 1; the cuts made (np - 1 of them) from *nc on in cuts
 * (when not NULL), parents before children. */
static void bisect(const double *xyz, const unsigned char *kind, int32_t *idx, size_t n, int p0, int np, int32_t *part,
                   thx_fem_cut *cuts, int *nc)
{
    if (np == 1) {
        for (size_t k = 0; k < n; k++) part[idx[k]] = p0;
        return;
    }
    if (n == 0) { /* no nodes left: empty parts, cut anywhere */
        if (cuts)
            for (int q = 1; q < np; q++) cuts[(*nc)++] = (thx_fem_cut){.lo = p0 + q - 1, .mid = p0 + q, .hi = p0 + np, .axis = 0, .at = 0};
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
    if (cuts) { /* the plane between the two sides' nodes (on a tie, through them) */
        double a = k > 0 ? xyz[3 * (size_t)idx[k - 1] + cut.axis] : lo[cut.axis];
        double b = k < n ? xyz[3 * (size_t)idx[k] + cut.axis] : hi[cut.axis];
        cuts[(*nc)++] = (thx_fem_cut){.lo = p0, .mid = p0 + left, .hi = p0 + np, .axis = cut.axis, .at = 0.5 * (a + b)};
    }
    bisect(xyz, kind, idx, k, p0, left, part, cuts, nc);
    bisect(xyz, kind, idx + k, n - k, p0 + left, np - left, part, cuts, nc);
}

thx_status thx_fem_partition(thx_ctx *ctx, const thx_volume *v, const unsigned char *kind, int n_parts, int32_t *part)
{
    return thx_fem_partition_cuts(ctx, v, kind, n_parts, part, NULL);
}

thx_status thx_fem_partition_cuts(thx_ctx *ctx, const thx_volume *v, const unsigned char *kind, int n_parts, int32_t *part,
                                  thx_fem_cut *cuts)
{
    if (n_parts < 1) return thx_error(ctx, THX_EINPUT, "fem: a partition into %d parts", n_parts);
    size_t nn = v->n_nodes, n = 0;
    int32_t *idx = thx_malloc(ctx, (nn ? nn : 1) * sizeof *idx);
    if (!idx) return THX_ENOMEM;
    for (size_t i = 0; i < nn; i++) {
        part[i] = -1;
        if (kind[i]) idx[n++] = (int32_t)i;
    }
    int nc = 0;
    bisect(v->xyz, kind, idx, n, 0, n_parts, part, cuts, &nc);
    free(idx);
    return THX_OK;
}

/* The cut that splits parts [lo, hi), from index k on (a child follows its parent). */
static int find_cut(const thx_fem_cut *cuts, int n, int k, int lo, int hi)
{
    for (; k < n; k++)
        if (cuts[k].lo == lo && cuts[k].hi == hi) return k;
    return -1;
}

int thx_fem_cut_part(const thx_fem_cut *cuts, int n_parts, const double p[3])
{
    int lo = 0, hi = n_parts, k = 0;
    while (hi - lo > 1) {
        k = find_cut(cuts, n_parts - 1, k, lo, hi);
        if (k < 0) return -1;
        if (p[cuts[k].axis] < cuts[k].at) hi = cuts[k].mid;
        else lo = cuts[k].mid;
    }
    return lo;
}

/* Parts [lo, hi) back to front from the eye into order (from *at on). */
static void order_parts(const thx_fem_cut *cuts, int n, int k, int lo, int hi, const double eye[3], int *order, int *at)
{
    if (hi - lo == 1) {
        order[(*at)++] = lo;
        return;
    }
    k = find_cut(cuts, n, k, lo, hi);
    if (k < 0) { /* (not a bisection's cuts: keep the numbers' order) */
        for (int q = lo; q < hi; q++) order[(*at)++] = q;
        return;
    }
    const thx_fem_cut *c = &cuts[k];
    /* the side of the plane away from the eye is behind: drawn first */
    int below_first = eye[c->axis] >= c->at;
    if (below_first) {
        order_parts(cuts, n, k + 1, lo, c->mid, eye, order, at);
        order_parts(cuts, n, k + 1, c->mid, hi, eye, order, at);
    } else {
        order_parts(cuts, n, k + 1, c->mid, hi, eye, order, at);
        order_parts(cuts, n, k + 1, lo, c->mid, eye, order, at);
    }
}

void thx_fem_cut_order(const thx_fem_cut *cuts, int n_parts, const double eye[3], int *order)
{
    int at = 0;
    order_parts(cuts, n_parts - 1, 0, 0, n_parts, eye, order, &at);
}

void thx_fem_cut_box(const thx_fem_cut *cuts, int n_parts, int part, double box[2][3])
{
    for (int k = 0; k < 3; k++) box[0][k] = -INFINITY, box[1][k] = INFINITY;
    for (int k = 0; k + 1 < n_parts; k++) { /* parents first: [lo, mid) below the plane, [mid, hi) at or above */
        const thx_fem_cut *c = cuts + k;
        if (part < c->lo || part >= c->hi) continue;
        if (part < c->mid) box[1][c->axis] = fmin(box[1][c->axis], c->at);
        else box[0][c->axis] = fmax(box[0][c->axis], c->at);
    }
}
