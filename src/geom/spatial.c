/* Bounding-volume hierarchy over axis-aligned boxes (see thorax/geom/spatial.h). */
#include "thorax/geom/spatial.h"
#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

enum { LEAF_SIZE = 4, STACK_DEPTH = 128 };

typedef struct {
    double lo[3], hi[3];
    /* Internal node: left child is the next node in the array (preorder), right
     * child is `right`. Leaf (count > 0): items[first .. first+count-1]. */
    uint32_t right, first, count;
} bvh_node;

struct thx_bvh {
    size_t n_boxes, n_nodes;
    bvh_node *node;
    uint32_t *items;   /* box indices, permuted so that each leaf's boxes are contiguous */
    double *blo, *bhi; /* the boxes, 3 per box (copied) */
};

/* A box during the build: its centre and index, moved around by value so
 * that the scans of the build run through contiguous memory. */
typedef struct {
    double c[3];
    uint32_t i;
} build_item;

/* Total order used for the median split: centre coordinate along the axis,
 * then box index (so that equal centres still split deterministically). */
static int key_less(const build_item *a, const build_item *b, int axis)
{
    return a->c[axis] < b->c[axis] || (a->c[axis] == b->c[axis] && a->i < b->i);
}

static void swap_items(build_item *a, build_item *b)
{
    build_item t = *a;
    *a = *b;
    *b = t;
}

/* Rearranges it[0..n-1] so that it[k] is the element of rank k in key order,
 * with smaller elements before it and larger after (quickselect, median-of-3). */
static void select_kth(build_item *it, size_t n, size_t k, int axis)
{
    ptrdiff_t lo = 0, hi = (ptrdiff_t)n - 1, kk = (ptrdiff_t)k;
    while (hi > lo) {
        ptrdiff_t mid = lo + (hi - lo) / 2;
        /* order it[lo], it[mid], it[hi] so that the median of the three sits at mid */
        if (key_less(&it[mid], &it[lo], axis)) swap_items(&it[mid], &it[lo]);
        if (key_less(&it[hi], &it[lo], axis)) swap_items(&it[hi], &it[lo]);
        if (key_less(&it[hi], &it[mid], axis)) swap_items(&it[hi], &it[mid]);
        build_item pivot = it[mid];
        ptrdiff_t i = lo, j = hi;
        /* Hoare partition; keys are distinct (index tie-break), so it ends */
        while (i <= j) {
            while (key_less(&it[i], &pivot, axis)) i++;
            while (key_less(&pivot, &it[j], axis)) j--;
            if (i <= j) {
                swap_items(&it[i], &it[j]);
                i++;
                j--;
            }
        }
        /* now it[lo..j] <= pivot <= it[i..hi], j < i, and it[j+1..i-1] == pivot */
        if (kk <= j) hi = j;
        else if (kk >= i) lo = i;
        else return;
    }
}

/* Builds the subtree over it[first .. first+count-1]; node bounds are the
 * union of the children's (bottom-up), so each box is read once. */
static void build(thx_bvh *b, build_item *it, size_t first, size_t count, size_t depth)
{
    size_t self = b->n_nodes++;
    bvh_node *nd = &b->node[self]; /* b->node is sized up front: never moves */
    if (count <= LEAF_SIZE || depth + 2 >= STACK_DEPTH) {
        nd->first = (uint32_t)first;
        nd->count = (uint32_t)count;
        nd->right = 0;
        for (int a = 0; a < 3; a++) {
            nd->lo[a] = INFINITY;
            nd->hi[a] = -INFINITY;
        }
        for (size_t k = first; k < first + count; k++) {
            size_t i = it[k].i;
            b->items[k] = (uint32_t)i;
            for (int a = 0; a < 3; a++) {
                if (b->blo[3 * i + a] < nd->lo[a]) nd->lo[a] = b->blo[3 * i + a];
                if (b->bhi[3 * i + a] > nd->hi[a]) nd->hi[a] = b->bhi[3 * i + a];
            }
        }
        return;
    }
    /* split at the median of the box centres along their longest extent */
    double clo[3] = {INFINITY, INFINITY, INFINITY}, chi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t k = first; k < first + count; k++)
        for (int a = 0; a < 3; a++) {
            double c = it[k].c[a];
            if (c < clo[a]) clo[a] = c;
            if (c > chi[a]) chi[a] = c;
        }
    int axis = 0;
    for (int a = 1; a < 3; a++)
        if (chi[a] - clo[a] > chi[axis] - clo[axis]) axis = a;
    size_t half = count / 2;
    select_kth(it + first, count, half, axis);
    nd->count = 0;
    nd->first = 0;
    build(b, it, first, half, depth + 1);
    size_t right = b->n_nodes;
    b->node[self].right = (uint32_t)right;
    build(b, it, first + half, count - half, depth + 1);
    const bvh_node *l = &b->node[self + 1], *r = &b->node[right];
    for (int a = 0; a < 3; a++) {
        b->node[self].lo[a] = fmin(l->lo[a], r->lo[a]);
        b->node[self].hi[a] = fmax(l->hi[a], r->hi[a]);
    }
}

thx_status thx_bvh_create(thx_ctx *ctx, const double *lo, const double *hi, size_t n, thx_bvh **out)
{
    *out = NULL;
    if (n >= UINT32_MAX / 2) return thx_error(ctx, THX_EINPUT, "bvh: %zu boxes is more than supported", n);
    for (size_t i = 0; i < 3 * n; i++)
        if (!(lo[i] <= hi[i])) /* also catches NaN */
            return thx_error(ctx, THX_EINPUT, "bvh: box %zu is empty or not a number", i / 3);
    thx_bvh *b = thx_calloc(ctx, 1, sizeof *b);
    build_item *it = NULL;
    if (!b) return THX_ENOMEM;
    b->n_boxes = n;
    size_t cap = n ? 2 * n : 1;
    b->node = thx_malloc(ctx, cap * sizeof *b->node);
    b->items = thx_malloc(ctx, (n ? n : 1) * sizeof *b->items);
    b->blo = thx_malloc(ctx, (n ? 3 * n : 1) * sizeof(double));
    b->bhi = thx_malloc(ctx, (n ? 3 * n : 1) * sizeof(double));
    it = thx_malloc(ctx, (n ? n : 1) * sizeof *it);
    if (!b->node || !b->items || !b->blo || !b->bhi || !it) {
        free(it);
        thx_bvh_destroy(&b);
        return THX_ENOMEM;
    }
    if (n) {
        memcpy(b->blo, lo, 3 * n * sizeof(double));
        memcpy(b->bhi, hi, 3 * n * sizeof(double));
    }
    for (size_t i = 0; i < n; i++) {
        it[i].i = (uint32_t)i;
        for (int a = 0; a < 3; a++) it[i].c[a] = 0.5 * lo[3 * i + a] + 0.5 * hi[3 * i + a];
    }
    if (n) build(b, it, 0, n, 0);
    free(it);
    *out = b;
    return THX_OK;
}

thx_status thx_bvh_create_triangles(thx_ctx *ctx, const double *xyz, size_t n_nodes, const int32_t *tri,
                                    size_t n_tris, thx_bvh **out)
{
    *out = NULL;
    double *lo = thx_malloc(ctx, (n_tris ? 3 * n_tris : 1) * sizeof(double));
    double *hi = thx_malloc(ctx, (n_tris ? 3 * n_tris : 1) * sizeof(double));
    thx_status st = THX_OK;
    if (!lo || !hi) {
        st = THX_ENOMEM;
        goto done;
    }
    for (size_t t = 0; t < n_tris; t++) {
        for (int k = 0; k < 3; k++) {
            int32_t v = tri[3 * t + k];
            if (v < 0 || (size_t)v >= n_nodes) {
                st = thx_error(ctx, THX_EINPUT, "bvh: triangle %zu refers to node %ld (of %zu)", t, (long)v, n_nodes);
                goto done;
            }
        }
        for (int a = 0; a < 3; a++) {
            double x0 = xyz[3 * (size_t)tri[3 * t] + a], x1 = xyz[3 * (size_t)tri[3 * t + 1] + a];
            double x2 = xyz[3 * (size_t)tri[3 * t + 2] + a];
            lo[3 * t + a] = fmin(x0, fmin(x1, x2));
            hi[3 * t + a] = fmax(x0, fmax(x1, x2));
        }
    }
    st = thx_bvh_create(ctx, lo, hi, n_tris, out);
done:
    free(lo);
    free(hi);
    return st;
}

void thx_bvh_destroy(thx_bvh **b)
{
    if (!b || !*b) return;
    free((*b)->node);
    free((*b)->items);
    free((*b)->blo);
    free((*b)->bhi);
    free(*b);
    *b = NULL;
}

size_t thx_bvh_size(const thx_bvh *b) { return b ? b->n_boxes : 0; }

static int box_overlap(const double *alo, const double *ahi, const double *blo, const double *bhi)
{
    return alo[0] <= bhi[0] && blo[0] <= ahi[0] && alo[1] <= bhi[1] && blo[1] <= ahi[1] && alo[2] <= bhi[2] &&
           blo[2] <= ahi[2];
}

int thx_bvh_query_box(const thx_bvh *b, const double lo[3], const double hi[3], thx_bvh_visit_fn fn, void *user)
{
    if (!b || b->n_boxes == 0) return 0;
    uint32_t stack[STACK_DEPTH];
    size_t sp = 0;
    stack[sp++] = 0;
    while (sp) {
        const bvh_node *nd = &b->node[stack[--sp]];
        if (!box_overlap(nd->lo, nd->hi, lo, hi)) continue;
        if (nd->count) {
            for (uint32_t k = nd->first; k < nd->first + nd->count; k++) {
                size_t i = b->items[k];
                if (box_overlap(b->blo + 3 * i, b->bhi + 3 * i, lo, hi)) {
                    int r = fn(user, i);
                    if (r) return r;
                }
            }
        } else {
            /* push right first so the left subtree is visited first (fixed order) */
            stack[sp++] = nd->right;
            stack[sp++] = (uint32_t)(nd - b->node) + 1;
        }
    }
    return 0;
}

/* Does the segment p + t d, t in [0,1], meet the box widened by a relative
 * margin? The margin absorbs the rounding of the slab arithmetic. */
static int segment_hits_box(const double *p, const double *d, const double *lo, const double *hi)
{
    double t0 = 0.0, t1 = 1.0;
    for (int a = 0; a < 3; a++) {
        double m = 1e-9 * (fabs(lo[a]) + fabs(hi[a]) + (hi[a] - lo[a])) + 1e-300;
        double l = lo[a] - m, h = hi[a] + m;
        if (d[a] == 0.0) {
            if (p[a] < l || p[a] > h) return 0;
            continue;
        }
        double inv = 1.0 / d[a];
        double ta = (l - p[a]) * inv, tb = (h - p[a]) * inv;
        if (ta > tb) { double t = ta; ta = tb; tb = t; }
        /* widen the parameter interval a little too: inv may be rounded */
        double w = 1e-12 * (fabs(ta) + fabs(tb));
        ta -= w;
        tb += w;
        if (ta > t0) t0 = ta;
        if (tb < t1) t1 = tb;
        if (t0 > t1) return 0;
    }
    return 1;
}

int thx_bvh_query_segment(const thx_bvh *b, const double p[3], const double q[3], thx_bvh_visit_fn fn, void *user)
{
    if (!b || b->n_boxes == 0) return 0;
    double d[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
    uint32_t stack[STACK_DEPTH];
    size_t sp = 0;
    stack[sp++] = 0;
    while (sp) {
        const bvh_node *nd = &b->node[stack[--sp]];
        if (!segment_hits_box(p, d, nd->lo, nd->hi)) continue;
        if (nd->count) {
            for (uint32_t k = nd->first; k < nd->first + nd->count; k++) {
                size_t i = b->items[k];
                if (segment_hits_box(p, d, b->blo + 3 * i, b->bhi + 3 * i)) {
                    int r = fn(user, i);
                    if (r) return r;
                }
            }
        } else {
            stack[sp++] = nd->right;
            stack[sp++] = (uint32_t)(nd - b->node) + 1;
        }
    }
    return 0;
}
