/* The cut mesh (thorax/field/field.h): its lifetime, growth, area, the cut-point table and the
 * pruning of faces reached from both sides. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "field_impl.h"

thx_status thx_field_mesh_create(thx_ctx *ctx, thx_field_mesh **out)
{
    *out = thx_calloc(ctx, 1, sizeof **out);
    return *out ? THX_OK : THX_ENOMEM;
}

static void free_all(thx_field_mesh *m)
{
    free(m->xyz);
    free(m->value);
    free(m->tri);
    free(m->tag);
    free(m->cell);
    free(m->cxyz);
    free(m->cvalue);
    free(m->seg);
    free(m->seg_tag);
    free(m->seg_tri);
}

void thx_field_mesh_destroy(thx_field_mesh **m)
{
    if (!m || !*m) return;
    free_all(*m);
    free(*m);
    *m = NULL;
}

void thx_field_mesh_clear(thx_field_mesh *m)
{
    free_all(m);
    memset(m, 0, sizeof *m);
}

double thx_field_mesh_area(const thx_field_mesh *m, int tag)
{
    double a = 0;
    for (size_t t = 0; t < m->n_tris; t++) {
        if (tag >= 0 && m->tag[t] != tag) continue;
        const double *p = m->xyz + 3 * (size_t)m->tri[3 * t], *q = m->xyz + 3 * (size_t)m->tri[3 * t + 1],
                     *r = m->xyz + 3 * (size_t)m->tri[3 * t + 2];
        double u[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]}, w[3] = {r[0] - p[0], r[1] - p[1], r[2] - p[2]};
        double c[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
        a += 0.5 * sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    }
    return a;
}

thx_status thx_field_mesh_append(thx_ctx *ctx, thx_field_mesh *dst, const thx_field_mesh *src, int32_t tag_offset)
{
    size_t p0 = dst->n_points, t0 = dst->n_tris, c0 = dst->n_cpoints, s0 = dst->n_segs;
    THX_CHECK(field_mesh_reserve(ctx, dst, p0 + src->n_points, t0 + src->n_tris));
    THX_CHECK(field_mesh_reserve_contours(ctx, dst, c0 + src->n_cpoints, s0 + src->n_segs));
    if (src->n_points) {
        memcpy(dst->xyz + 3 * p0, src->xyz, 3 * src->n_points * sizeof *src->xyz);
        memcpy(dst->value + p0, src->value, src->n_points * sizeof *src->value);
    }
    for (size_t t = 0; t < src->n_tris; t++) {
        for (int c = 0; c < 3; c++) dst->tri[3 * (t0 + t) + c] = src->tri[3 * t + c] + (int32_t)p0;
        dst->tag[t0 + t] = src->tag[t] + tag_offset;
        dst->cell[t0 + t] = src->cell[t];
    }
    if (src->n_cpoints) {
        memcpy(dst->cxyz + 3 * c0, src->cxyz, 3 * src->n_cpoints * sizeof *src->cxyz);
        memcpy(dst->cvalue + c0, src->cvalue, src->n_cpoints * sizeof *src->cvalue);
    }
    for (size_t s = 0; s < src->n_segs; s++) {
        for (int c = 0; c < 2; c++) dst->seg[2 * (s0 + s) + c] = src->seg[2 * s + c] + (int32_t)c0;
        dst->seg_tag[s0 + s] = src->seg_tag[s];
        dst->seg_tri[s0 + s] = src->seg_tri[s] + (int32_t)t0;
    }
    dst->n_points += src->n_points;
    dst->n_tris += src->n_tris;
    dst->n_cpoints += src->n_cpoints;
    dst->n_segs += src->n_segs;
    return THX_OK;
}

/* Capacity is not stored: arrays are sized to a power of two above the count, so the capacity
 * follows from the count alone. */
static size_t cap_of(size_t n)
{
    size_t c = 64;
    while (c < n) c *= 2;
    return c;
}

static thx_status grow(thx_ctx *ctx, void **p, size_t have, size_t need, size_t elem)
{
    if (need <= (have ? cap_of(have) : 0) && *p) return THX_OK;
    void *q = thx_realloc(ctx, *p, cap_of(need) * elem);
    if (!q) return THX_ENOMEM;
    *p = q;
    return THX_OK;
}

thx_status field_mesh_reserve(thx_ctx *ctx, thx_field_mesh *m, size_t n_points, size_t n_tris)
{
    if (n_points > (size_t)INT32_MAX || n_tris > (size_t)INT32_MAX / 3)
        return thx_error(ctx, THX_EINPUT, "cut mesh too large (%zu points, %zu triangles)", n_points, n_tris);
    THX_CHECK(grow(ctx, (void **)&m->xyz, m->n_points, n_points, 3 * sizeof *m->xyz));
    THX_CHECK(grow(ctx, (void **)&m->value, m->n_points, n_points, sizeof *m->value));
    THX_CHECK(grow(ctx, (void **)&m->tri, m->n_tris, n_tris, 3 * sizeof *m->tri));
    THX_CHECK(grow(ctx, (void **)&m->tag, m->n_tris, n_tris, sizeof *m->tag));
    THX_CHECK(grow(ctx, (void **)&m->cell, m->n_tris, n_tris, sizeof *m->cell));
    return THX_OK;
}

thx_status thx_field_mesh_reserve(thx_ctx *ctx, thx_field_mesh *m, size_t n_points, size_t n_tris)
{
    return field_mesh_reserve(ctx, m, n_points, n_tris);
}

thx_status field_mesh_reserve_contours(thx_ctx *ctx, thx_field_mesh *m, size_t n_cpoints, size_t n_segs)
{
    if (n_cpoints > (size_t)INT32_MAX || n_segs > (size_t)INT32_MAX / 2)
        return thx_error(ctx, THX_EINPUT, "contours too large (%zu points, %zu segments)", n_cpoints, n_segs);
    THX_CHECK(grow(ctx, (void **)&m->cxyz, m->n_cpoints, n_cpoints, 3 * sizeof *m->cxyz));
    THX_CHECK(grow(ctx, (void **)&m->cvalue, m->n_cpoints, n_cpoints, sizeof *m->cvalue));
    THX_CHECK(grow(ctx, (void **)&m->seg, m->n_segs, n_segs, 2 * sizeof *m->seg));
    THX_CHECK(grow(ctx, (void **)&m->seg_tag, m->n_segs, n_segs, sizeof *m->seg_tag));
    THX_CHECK(grow(ctx, (void **)&m->seg_tri, m->n_segs, n_segs, sizeof *m->seg_tri));
    return THX_OK;
}

/* ------------------------------------------------------------ the cut-point table */

thx_status field_hash_init(thx_ctx *ctx, field_hash *h, size_t expected)
{
    size_t n = 1024;
    while (n < 2 * expected + 16) n *= 2;
    h->slot = thx_malloc(ctx, n * sizeof *h->slot);
    if (!h->slot) return THX_ENOMEM;
    for (size_t i = 0; i < n; i++) h->slot[i].idx = -1;
    h->mask = n - 1;
    return THX_OK;
}

void field_hash_free(field_hash *h)
{
    free(h->slot);
    h->slot = NULL;
}

field_key *field_hash_slot(field_hash *h, int32_t a, int32_t b, int32_t k)
{
    uint64_t x = ((uint64_t)(uint32_t)a * 0x9E3779B97F4A7C15ull) ^ ((uint64_t)(uint32_t)b * 0xC2B2AE3D27D4EB4Full) ^
                 ((uint64_t)(uint32_t)k * 0x165667B19E3779F9ull);
    x ^= x >> 29;
    for (size_t i = (size_t)x & h->mask;; i = (i + 1) & h->mask) {
        field_key *s = &h->slot[i];
        if (s->idx < 0) {
            s->a = a;
            s->b = b;
            s->k = k;
            return s;
        }
        if (s->a == a && s->b == b && s->k == k) return s;
    }
}

/* ------------------------------------------------------------ pruning */

typedef struct {
    int32_t v[3]; /* sorted vertex ids */
    int32_t tag;
    size_t t;
} face_key;

static int face_cmp(const void *pa, const void *pb)
{
    const face_key *a = pa, *b = pb;
    if (a->tag != b->tag) return a->tag < b->tag ? -1 : 1;
    for (int i = 0; i < 3; i++)
        if (a->v[i] != b->v[i]) return a->v[i] < b->v[i] ? -1 : 1;
    return a->t < b->t ? -1 : a->t > b->t;
}

thx_status field_prune(thx_ctx *ctx, thx_field_mesh *m, size_t p0, size_t t0, const unsigned char *is_node)
{
    size_t nf = 0;
    for (size_t t = t0; t < m->n_tris; t++)
        if (is_node[m->tri[3 * t] - (int32_t)p0] && is_node[m->tri[3 * t + 1] - (int32_t)p0] &&
            is_node[m->tri[3 * t + 2] - (int32_t)p0])
            nf++;
    unsigned char *drop = NULL;
    if (nf > 1) {
        face_key *f = thx_malloc(ctx, nf * sizeof *f);
        drop = thx_calloc(ctx, m->n_tris - t0, 1);
        if (!f || !drop) {
            free(f);
            free(drop);
            return THX_ENOMEM;
        }
        nf = 0;
        for (size_t t = t0; t < m->n_tris; t++) {
            const int32_t *c = m->tri + 3 * t;
            if (!(is_node[c[0] - (int32_t)p0] && is_node[c[1] - (int32_t)p0] && is_node[c[2] - (int32_t)p0])) continue;
            int32_t a = c[0], b = c[1], d = c[2], x;
            if (a > b) x = a, a = b, b = x;
            if (b > d) x = b, b = d, d = x;
            if (a > b) x = a, a = b, b = x;
            f[nf++] = (face_key){{a, b, d}, m->tag[t], t};
        }
        qsort(f, nf, sizeof *f, face_cmp);
        for (size_t i = 0; i + 1 < nf;) {
            if (f[i].tag == f[i + 1].tag && !memcmp(f[i].v, f[i + 1].v, sizeof f[i].v)) {
                drop[f[i].t - t0] = drop[f[i + 1].t - t0] = 1; /* a pair: the film's two sides */
                i += 2;
            } else {
                i++;
            }
        }
        free(f);
    }
    /* compact the triangles and renumber the vertices in order of first use */
    size_t np = m->n_points - p0;
    int32_t *map = thx_malloc(ctx, (np ? np : 1) * sizeof *map);
    double *xyz = thx_malloc(ctx, 3 * (np ? np : 1) * sizeof *xyz), *val = thx_malloc(ctx, (np ? np : 1) * sizeof *val);
    if (!map || !xyz || !val) {
        free(map);
        free(xyz);
        free(val);
        free(drop);
        return THX_ENOMEM;
    }
    for (size_t i = 0; i < np; i++) map[i] = -1;
    size_t w = t0, used = 0;
    for (size_t t = t0; t < m->n_tris; t++) {
        if (drop && drop[t - t0]) continue;
        for (int c = 0; c < 3; c++) {
            size_t old = (size_t)m->tri[3 * t + c] - p0;
            if (map[old] < 0) {
                map[old] = (int32_t)(p0 + used);
                memcpy(xyz + 3 * used, m->xyz + 3 * (p0 + old), 3 * sizeof *xyz);
                val[used++] = m->value[p0 + old];
            }
            m->tri[3 * w + c] = map[old];
        }
        m->tag[w] = m->tag[t];
        m->cell[w] = m->cell[t];
        w++;
    }
    m->n_tris = w;
    if (used) { /* (m's arrays may still be NULL when nothing was kept) */
        memcpy(m->xyz + 3 * p0, xyz, 3 * used * sizeof *xyz);
        memcpy(m->value + p0, val, used * sizeof *val);
    }
    m->n_points = p0 + used;
    free(map);
    free(xyz);
    free(val);
    free(drop);
    return THX_OK;
}
