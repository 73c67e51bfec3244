/* Contour lines on a cut mesh (thorax/field/field.h): marching triangles over its vertex values,
 * the two-dimensional form of cut.c's rules. One contour point per (triangle edge, value), or
 * per (vertex, value) where the line passes through a vertex (its value equals c: it counts as
 * above c); a segment that would join a point to itself is dropped, and a segment along a mesh
 * edge reached from the triangles on both sides (the line lies on that edge) is dropped twice
 * over. Each segment is turned so that, seen from the triangle's normal side, greater values
 * lie on its left. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "field_impl.h"

typedef struct {
    thx_field_mesh *m;
    field_hash h;
    size_t c0;
    unsigned char *on_vertex; /* per contour point since c0 */
} contourer;

static int32_t point(contourer *C, int32_t a, int32_t b, int32_t k, double c)
{
    thx_field_mesh *m = C->m;
    const double *xa = m->xyz + 3 * (size_t)a, *xb = m->xyz + 3 * (size_t)b;
    double wa = m->value[a], wb = m->value[b], x[3];
    int32_t vert = -1;
    if (wb == c) {
        vert = b;
    } else {
        double t = (c - wa) / (wb - wa);
        for (int i = 0; i < 3; i++) x[i] = xa[i] + t * (xb[i] - xa[i]);
        if (x[0] == xb[0] && x[1] == xb[1] && x[2] == xb[2]) vert = b;
        else if (x[0] == xa[0] && x[1] == xa[1] && x[2] == xa[2]) vert = a;
    }
    field_key *s = vert >= 0 ? field_hash_slot(&C->h, vert, vert, k)
                             : field_hash_slot(&C->h, a < b ? a : b, a < b ? b : a, k);
    if (s->idx >= 0) return s->idx;
    size_t p = m->n_cpoints++;
    s->idx = (int32_t)p;
    memcpy(m->cxyz + 3 * p, vert >= 0 ? m->xyz + 3 * (size_t)vert : x, 3 * sizeof *x);
    m->cvalue[p] = c;
    C->on_vertex[p - C->c0] = vert >= 0;
    return (int32_t)p;
}

static void segment(contourer *C, size_t t, int32_t k, double c)
{
    thx_field_mesh *m = C->m;
    const int32_t *q = m->tri + 3 * t;
    int above[3], na = 0, lo = 0, hi = 0;
    for (int i = 0; i < 3; i++) {
        double w = m->value[q[i]];
        above[i] = w >= c;
        na += above[i];
        if (w < m->value[q[lo]]) lo = i;
        if (w > m->value[q[hi]]) hi = i;
    }
    if (na == 0 || na == 3) return;
    int lone = 0;
    while (above[lone] != (na == 1)) lone++;
    int32_t e[2];
    for (int i = 0, j = 0; i < 3; i++) {
        if (i == lone) continue;
        e[j++] = na == 1 ? point(C, q[i], q[lone], k, c) : point(C, q[lone], q[i], k, c);
    }
    if (e[0] == e[1]) return;
    /* left of the segment, seen from the normal: n x d; it must point to increasing value */
    const double *p0 = m->xyz + 3 * (size_t)q[0], *p1 = m->xyz + 3 * (size_t)q[1], *p2 = m->xyz + 3 * (size_t)q[2];
    double u[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]}, w[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
    double n[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
    const double *a = m->cxyz + 3 * (size_t)e[0], *b = m->cxyz + 3 * (size_t)e[1];
    double d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    double l[3] = {n[1] * d[2] - n[2] * d[1], n[2] * d[0] - n[0] * d[2], n[0] * d[1] - n[1] * d[0]};
    const double *xh = m->xyz + 3 * (size_t)q[hi], *xl = m->xyz + 3 * (size_t)q[lo];
    double g = l[0] * (xh[0] - xl[0]) + l[1] * (xh[1] - xl[1]) + l[2] * (xh[2] - xl[2]);
    size_t s = m->n_segs++;
    m->seg[2 * s] = g >= 0 ? e[0] : e[1];
    m->seg[2 * s + 1] = g >= 0 ? e[1] : e[0];
    m->seg_tag[s] = k;
    m->seg_tri[s] = (int32_t)t;
}

typedef struct {
    int32_t a, b, k;
    size_t s;
} seg_key;

static int seg_cmp(const void *pa, const void *pb)
{
    const seg_key *x = pa, *y = pb;
    if (x->k != y->k) return x->k < y->k ? -1 : 1;
    if (x->a != y->a) return x->a < y->a ? -1 : 1;
    if (x->b != y->b) return x->b < y->b ? -1 : 1;
    return x->s < y->s ? -1 : x->s > y->s;
}

/* Drops pairs of segments between the same two vertex points (a line along a shared edge seen
 * from both triangles), then the contour points no segment uses. */
static thx_status prune(thx_ctx *ctx, contourer *C, size_t s0)
{
    thx_field_mesh *m = C->m;
    size_t n = 0;
    for (size_t s = s0; s < m->n_segs; s++)
        n += C->on_vertex[m->seg[2 * s] - (int32_t)C->c0] && C->on_vertex[m->seg[2 * s + 1] - (int32_t)C->c0];
    unsigned char *drop = thx_calloc(ctx, m->n_segs - s0 + 1, 1);
    seg_key *f = thx_malloc(ctx, (n ? n : 1) * sizeof *f);
    size_t np = m->n_cpoints - C->c0;
    int32_t *map = thx_malloc(ctx, (np ? np : 1) * sizeof *map);
    double *xyz = thx_malloc(ctx, 3 * (np ? np : 1) * sizeof *xyz), *val = thx_malloc(ctx, (np ? np : 1) * sizeof *val);
    if (!drop || !f || !map || !xyz || !val) {
        free(drop);
        free(f);
        free(map);
        free(xyz);
        free(val);
        return THX_ENOMEM;
    }
    n = 0;
    for (size_t s = s0; s < m->n_segs; s++) {
        int32_t a = m->seg[2 * s], b = m->seg[2 * s + 1];
        if (!(C->on_vertex[a - (int32_t)C->c0] && C->on_vertex[b - (int32_t)C->c0])) continue;
        f[n++] = (seg_key){a < b ? a : b, a < b ? b : a, m->seg_tag[s], s};
    }
    qsort(f, n, sizeof *f, seg_cmp);
    for (size_t i = 0; i + 1 < n;) {
        if (f[i].k == f[i + 1].k && f[i].a == f[i + 1].a && f[i].b == f[i + 1].b) {
            drop[f[i].s - s0] = drop[f[i + 1].s - s0] = 1;
            i += 2;
        } else {
            i++;
        }
    }
    for (size_t i = 0; i < np; i++) map[i] = -1;
    size_t w = s0, used = 0;
    for (size_t s = s0; s < m->n_segs; s++) {
        if (drop[s - s0]) continue;
        for (int c = 0; c < 2; c++) {
            size_t old = (size_t)m->seg[2 * s + c] - C->c0;
            if (map[old] < 0) {
                map[old] = (int32_t)(C->c0 + used);
                memcpy(xyz + 3 * used, m->cxyz + 3 * (C->c0 + old), 3 * sizeof *xyz);
                val[used++] = m->cvalue[C->c0 + old];
            }
            m->seg[2 * w + c] = map[old];
        }
        m->seg_tag[w] = m->seg_tag[s];
        m->seg_tri[w] = m->seg_tri[s];
        w++;
    }
    m->n_segs = w;
    if (used) { /* (m's arrays may still be NULL when nothing was kept) */
        memcpy(m->cxyz + 3 * C->c0, xyz, 3 * used * sizeof *xyz);
        memcpy(m->cvalue + C->c0, val, used * sizeof *val);
    }
    m->n_cpoints = C->c0 + used;
    free(xyz);
    free(val);
    free(drop);
    free(f);
    free(map);
    return THX_OK;
}

thx_status thx_field_contours(thx_ctx *ctx, thx_field_mesh *m, const double *values, size_t n_values)
{
    for (size_t k = 0; k < n_values; k++)
        if (!isfinite(values[k])) return thx_error(ctx, THX_EINPUT, "contour value %zu (%g) is not finite", k + 1, values[k]);
    if (!n_values || !m->n_tris) return THX_OK;
    if (n_values > 100000) return thx_error(ctx, THX_EINPUT, "too many contour values (%zu)", n_values);
    /* the triangles each value crosses, counted first: every array sized once */
    size_t n_cut = 0;
    for (size_t t = 0; t < m->n_tris; t++) {
        const int32_t *q = m->tri + 3 * t;
        double lo = fmin(fmin(m->value[q[0]], m->value[q[1]]), m->value[q[2]]);
        double hi = fmax(fmax(m->value[q[0]], m->value[q[1]]), m->value[q[2]]);
        for (size_t k = 0; k < n_values; k++) n_cut += values[k] > lo && values[k] <= hi;
    }
    contourer C = {.m = m, .c0 = m->n_cpoints};
    size_t s0 = m->n_segs;
    THX_CHECK(field_mesh_reserve_contours(ctx, m, m->n_cpoints + 2 * n_cut, m->n_segs + n_cut));
    THX_CHECK(field_hash_init(ctx, &C.h, 2 * n_cut));
    C.on_vertex = thx_calloc(ctx, 2 * n_cut + 1, 1);
    if (!C.on_vertex) {
        field_hash_free(&C.h);
        return THX_ENOMEM;
    }
    for (size_t k = 0; k < n_values; k++)
        for (size_t t = 0; t < m->n_tris; t++) segment(&C, t, (int32_t)k, values[k]);
    thx_status st = prune(ctx, &C, s0);
    free(C.on_vertex);
    field_hash_free(&C.h);
    return st;
}
