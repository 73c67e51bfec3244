/*
 * Marching tetrahedra: the one cutter behind equipotential surfaces and slices (field_impl.h).
 *
 * Two passes. The first (OpenMP, each thread one contiguous block of tetrahedra) finds the
 * (tetrahedron, value) pairs to cut: a tetrahedron whose node scalars span [lo, hi] is cut by
 * every value c with lo < c <= hi (a node at c counts as above: symbolic perturbation s + eps,
 * so no tolerance decides anything); it reads each node's bin among the sorted values (node_bins)
 * rather than its scalar. The blocks are joined in thread order and sorted by value
 * (stably), so the list is the same for any thread count. The second pass (serial, in that
 * order) makes the cut points, one per (edge, value) through a hash table, or one per (node,
 * value) where the cut passes through a node (the node's s equals c, or the interpolated point
 * rounds onto a node), and the triangles: one for a tetrahedron with one node on its own side,
 * two (the shorter diagonal) for a quadrilateral. Each triangle is turned so that its normal
 * points from the tetrahedron's lowest node to its highest (increasing s).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#ifdef _OPENMP
#include <omp.h>
#endif

#include "field_impl.h"

typedef struct {
    int32_t tet, k;
} cut_pair;

typedef struct {
    cut_pair *p;
    size_t n, cap;
    size_t bad; /* first tetrahedron with a non-finite scalar, or SIZE_MAX */
    int oom;
} cut_block;

static int push(cut_block *b, int32_t t, int32_t k)
{
    if (b->n == b->cap) {
        size_t c = b->cap ? 2 * b->cap : 4096;
        cut_pair *q = realloc(b->p, c * sizeof *q);
        if (!q) return -1;
        b->p = q;
        b->cap = c;
    }
    b->p[b->n++] = (cut_pair){t, k};
    return 0;
}

/* Index of the first sorted value > x. */
static size_t upper(const double *sv, size_t n, double x)
{
    size_t lo = 0, hi = n;
    while (lo < hi) {
        size_t mid = (lo + hi) / 2;
        if (sv[mid] > x) hi = mid;
        else lo = mid + 1;
    }
    return lo;
}

/* The bin of each node: how many of the sorted values are <= its scalar (a node is above value k
 * when its bin exceeds k), or BIN_BAD for a non-finite scalar. A tetrahedron whose nodes' bins
 * run from lo to hi is cut by the values lo .. hi-1: two bytes per node read in the pass over the
 * tetrahedra instead of eight, and integer comparisons. */
#define BIN_BAD 0xFFFFu

static void node_bins(const double *s, size_t n, const double *sv, size_t n_cuts, uint16_t *bin)
{
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; i++) {
        double x = s[i];
        bin[i] = !isfinite(x) ? (uint16_t)BIN_BAD : (uint16_t)upper(sv, n_cuts, x);
    }
}

static void find_pairs(const thx_volume *v, const uint16_t *bin, const int32_t *ord, const unsigned char *use,
                       cut_block *b, size_t t0, size_t t1)
{
    for (size_t t = t0; t < t1; t++) {
        const int32_t *q = v->tet + 4 * t;
        unsigned a = bin[q[0]], c = bin[q[1]], d = bin[q[2]], e = bin[q[3]];
        unsigned l1 = a < c ? a : c, l2 = d < e ? d : e, h1 = a < c ? c : a, h2 = d < e ? e : d;
        unsigned lo = l1 < l2 ? l1 : l2, hi = h1 < h2 ? h2 : h1;
        if (lo == hi && hi != BIN_BAD) continue;
        if (use && !use[v->region[t]]) continue;
        if (hi == BIN_BAD) {
            if (t < b->bad) b->bad = t;
            continue;
        }
        for (unsigned k = lo; k < hi; k++)
            if (push(b, (int32_t)t, ord[k])) b->oom = 1;
    }
}

/* State of the second pass. */
typedef struct {
    const thx_volume *v;
    const double *s, *phi;
    int iso;
    field_hash h;
    thx_field_mesh *out;
    size_t p0;
    unsigned char *is_node; /* per point since p0 */
} cutter;

/* The cut point on the edge from node a (s < c) to node b (s >= c), for value index k. */
static int32_t edge_point(cutter *C, int32_t a, int32_t b, int32_t k, double c)
{
    const double *xa = C->v->xyz + 3 * (size_t)a, *xb = C->v->xyz + 3 * (size_t)b;
    double sa = C->s[a], sb = C->s[b], t = 1, x[3];
    int32_t node = -1;
    if (sb == c) {
        node = b;
    } else {
        t = (c - sa) / (sb - sa);
        for (int i = 0; i < 3; i++) x[i] = xa[i] + t * (xb[i] - xa[i]);
        if (x[0] == xb[0] && x[1] == xb[1] && x[2] == xb[2]) node = b;
        else if (x[0] == xa[0] && x[1] == xa[1] && x[2] == xa[2]) node = a;
    }
    field_key *slot = node >= 0 ? field_hash_slot(&C->h, node, node, k)
                                : field_hash_slot(&C->h, a < b ? a : b, a < b ? b : a, k);
    if (slot->idx >= 0) return slot->idx;
    thx_field_mesh *m = C->out;
    size_t p = m->n_points++;
    slot->idx = (int32_t)p;
    double *X = m->xyz + 3 * p;
    if (node >= 0) memcpy(X, C->v->xyz + 3 * (size_t)node, 3 * sizeof *X);
    else memcpy(X, x, 3 * sizeof *X);
    if (C->iso) m->value[p] = c;
    else if (!C->phi) m->value[p] = 0;
    else if (node >= 0) m->value[p] = C->phi[node];
    else m->value[p] = C->phi[a] + t * (C->phi[b] - C->phi[a]);
    C->is_node[p - C->p0] = node >= 0;
    return (int32_t)p;
}

/* Appends triangle (i, j, l) unless two corners coincide, turned so that its normal has a
 * positive component along dir. */
static void emit(cutter *C, int32_t i, int32_t j, int32_t l, const double *dir, int32_t tag, int32_t tet)
{
    if (i == j || j == l || i == l) return;
    thx_field_mesh *m = C->out;
    const double *p = m->xyz + 3 * (size_t)i, *q = m->xyz + 3 * (size_t)j, *r = m->xyz + 3 * (size_t)l;
    double u[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]}, w[3] = {r[0] - p[0], r[1] - p[1], r[2] - p[2]};
    double nx = u[1] * w[2] - u[2] * w[1], ny = u[2] * w[0] - u[0] * w[2], nz = u[0] * w[1] - u[1] * w[0];
    size_t t = m->n_tris++;
    int32_t *c = m->tri + 3 * t;
    c[0] = i;
    if (nx * dir[0] + ny * dir[1] + nz * dir[2] >= 0) c[1] = j, c[2] = l;
    else c[1] = l, c[2] = j;
    m->tag[t] = tag;
    m->cell[t] = tet;
}

static double dist2(const double *a, const double *b)
{
    double x = a[0] - b[0], y = a[1] - b[1], z = a[2] - b[2];
    return x * x + y * y + z * z;
}

static void cut_tet(cutter *C, int32_t tet, int32_t k, double c, int32_t tag)
{
    const int32_t *q = C->v->tet + 4 * (size_t)tet;
    int above[4], na = 0, lo = 0, hi = 0;
    for (int i = 0; i < 4; i++) {
        above[i] = C->s[q[i]] >= c;
        na += above[i];
        if (C->s[q[i]] < C->s[q[lo]]) lo = i;
        if (C->s[q[i]] > C->s[q[hi]]) hi = i;
    }
    const double *xl = C->v->xyz + 3 * (size_t)q[lo], *xh = C->v->xyz + 3 * (size_t)q[hi];
    double dir[3] = {xh[0] - xl[0], xh[1] - xl[1], xh[2] - xl[2]};
    if (na == 1 || na == 3) {
        int lone = 0;
        while (above[lone] != (na == 1)) lone++;
        int32_t p[3], np = 0;
        for (int i = 0; i < 4; i++) {
            if (i == lone) continue;
            p[np++] = na == 1 ? edge_point(C, q[i], q[lone], k, c) : edge_point(C, q[lone], q[i], k, c);
        }
        emit(C, p[0], p[1], p[2], dir, tag, tet);
        return;
    }
    int b[2], a[2], nb = 0, nu = 0; /* below, above */
    for (int i = 0; i < 4; i++) {
        if (above[i]) a[nu++] = i;
        else b[nb++] = i;
    }
    /* the quadrilateral's corners in order round it: pr, pt, qt, qr */
    int32_t v0 = edge_point(C, q[b[0]], q[a[0]], k, c), v1 = edge_point(C, q[b[0]], q[a[1]], k, c),
            v2 = edge_point(C, q[b[1]], q[a[1]], k, c), v3 = edge_point(C, q[b[1]], q[a[0]], k, c);
    const double *X = C->out->xyz;
    if (dist2(X + 3 * (size_t)v0, X + 3 * (size_t)v2) <= dist2(X + 3 * (size_t)v1, X + 3 * (size_t)v3)) {
        emit(C, v0, v1, v2, dir, tag, tet);
        emit(C, v0, v2, v3, dir, tag, tet);
    } else {
        emit(C, v0, v1, v3, dir, tag, tet);
        emit(C, v1, v2, v3, dir, tag, tet);
    }
}

typedef struct {
    double v;
    int32_t i;
} val_idx;

static int by_value(const void *pa, const void *pb)
{
    const val_idx *a = pa, *b = pb;
    return a->v < b->v ? -1 : a->v > b->v ? 1 : (a->i > b->i) - (a->i < b->i);
}

thx_status field_cut(thx_ctx *ctx, const thx_volume *v, const double *s, const double *cuts, size_t n_cuts,
                     int32_t tag0, const double *phi, int iso, const unsigned char *use_region, const char *what,
                     thx_field_mesh *out)
{
    if (!n_cuts) return THX_OK;
    if (n_cuts > 60000 || v->n_tets > (size_t)INT32_MAX)
        return thx_error(ctx, THX_EINPUT, "too many values (%zu) or tetrahedra (%zu) to cut", n_cuts, v->n_tets);
    for (size_t i = 0; i < n_cuts; i++)
        if (!isfinite(cuts[i])) return thx_error(ctx, THX_EINPUT, "cut value %zu (%g) is not finite", i + 1, cuts[i]);
    int32_t *ord = thx_malloc(ctx, n_cuts * sizeof *ord);
    double *sv = thx_malloc(ctx, n_cuts * sizeof *sv);
    int nthr = 1;
#ifdef _OPENMP
    nthr = omp_get_max_threads();
#endif
    cut_block *blk = thx_calloc(ctx, (size_t)nthr, sizeof *blk);
    cut_pair *pairs = NULL;
    size_t *cnt = NULL;
    uint16_t *bins = NULL;
    cutter C = {.v = v, .s = s, .phi = phi, .iso = iso, .out = out, .p0 = out->n_points};
    thx_status st = THX_OK;
    if (!ord || !sv || !blk) {
        st = THX_ENOMEM;
        goto done;
    }
    /* the values sorted, with their indices */
    val_idx *vi = thx_malloc(ctx, n_cuts * sizeof *vi);
    if (!vi) {
        st = THX_ENOMEM;
        goto done;
    }
    for (size_t i = 0; i < n_cuts; i++) vi[i] = (val_idx){cuts[i], (int32_t)i};
    qsort(vi, n_cuts, sizeof *vi, by_value);
    for (size_t i = 0; i < n_cuts; i++) {
        sv[i] = vi[i].v;
        ord[i] = vi[i].i;
        if (i && sv[i] == sv[i - 1]) {
            free(vi);
            st = thx_error(ctx, THX_EINPUT, "cut value %g given twice", sv[i]);
            goto done;
        }
    }
    free(vi);
    for (int i = 0; i < nthr; i++) blk[i].bad = SIZE_MAX;
    bins = thx_malloc(ctx, (v->n_nodes ? v->n_nodes : 1) * sizeof *bins);
    if (!bins) {
        st = THX_ENOMEM;
        goto done;
    }
    node_bins(s, v->n_nodes, sv, n_cuts, bins);
#pragma omp parallel num_threads(nthr)
    {
        int id = 0, T = 1;
#ifdef _OPENMP
        id = omp_get_thread_num();
        T = omp_get_num_threads();
#endif
        size_t t0 = v->n_tets * (size_t)id / (size_t)T, t1 = v->n_tets * ((size_t)id + 1) / (size_t)T;
        find_pairs(v, bins, ord, use_region, &blk[id], t0, t1);
    }
    size_t total = 0, bad = SIZE_MAX;
    for (int i = 0; i < nthr; i++) {
        if (blk[i].oom) {
            st = thx_error(ctx, THX_ENOMEM, "out of memory");
            goto done;
        }
        if (blk[i].bad < bad) bad = blk[i].bad;
        total += blk[i].n;
    }
    if (bad != SIZE_MAX) {
        const int32_t *q = v->tet + 4 * bad;
        int i = 0;
        while (i < 3 && isfinite(s[q[i]])) i++;
        st = thx_error(ctx, THX_EINPUT, "node %ld (of tetrahedron %zu) has a non-finite %s (%g)", (long)q[i] + 1,
                       bad + 1, what, s[q[i]]);
        goto done;
    }
    /* by value, stably: the order of the tetrahedra within each value kept */
    pairs = thx_malloc(ctx, (total ? total : 1) * sizeof *pairs);
    cnt = thx_calloc(ctx, n_cuts + 1, sizeof *cnt);
    if (!pairs || !cnt) {
        st = THX_ENOMEM;
        goto done;
    }
    for (int i = 0; i < nthr; i++)
        for (size_t j = 0; j < blk[i].n; j++) cnt[blk[i].p[j].k + 1]++;
    for (size_t k = 0; k < n_cuts; k++) cnt[k + 1] += cnt[k];
    for (int i = 0; i < nthr; i++) {
        for (size_t j = 0; j < blk[i].n; j++) pairs[cnt[blk[i].p[j].k]++] = blk[i].p[j];
        free(blk[i].p);
        blk[i].p = NULL;
    }
    if (total > (size_t)INT32_MAX / 8) {
        st = thx_error(ctx, THX_EINPUT, "cut of %zu tetrahedra: too large", total);
        goto done;
    }
    THX_TRY(field_mesh_reserve(ctx, out, out->n_points + 4 * total, out->n_tris + 2 * total));
    THX_TRY(field_hash_init(ctx, &C.h, 2 * total));
    C.is_node = thx_calloc(ctx, 4 * total + 1, 1);
    if (!C.is_node) {
        st = THX_ENOMEM;
        goto done;
    }
    size_t t_first = out->n_tris;
    for (size_t i = 0; i < total; i++)
        cut_tet(&C, pairs[i].tet, pairs[i].k, cuts[pairs[i].k], tag0 + pairs[i].k);
    st = field_prune(ctx, out, C.p0, t_first, C.is_node);
done:
    for (int i = 0; blk && i < nthr; i++) free(blk[i].p);
    free(blk);
    free(ord);
    free(sv);
    free(pairs);
    free(cnt);
    free(bins);
    free(C.is_node);
    field_hash_free(&C.h);
    return st;
}
