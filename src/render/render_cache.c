/*
 * The renderer's geometry cache (see render.c): each surface is uploaded once, with its
 * area-weighted normals, and kept keyed by its address, counts, array addresses and a hash of its
 * coordinates and triangles; the wire mode's unique edges are built at their first use. A frame
 * that redraws a surface with new values uploads only one float per node.
 */
#include "render_internal.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define CACHE_KEEP 32   /* surfaces kept uploaded beyond those of the current frame */

static uint64_t hash_bytes(uint64_t h, const void *data, size_t n)
{
    const unsigned char *b = data;
    size_t i = 0;
    for (; i + 8 <= n; i += 8) {
        uint64_t w;
        memcpy(&w, b + i, 8);
        h = (h ^ w) * 0x100000001b3ULL;
        h ^= h >> 29;
    }
    for (; i < n; i++) h = (h ^ b[i]) * 0x100000001b3ULL;
    return h;
}

static uint64_t surface_hash(const thx_surface *s, const double *normals)
{
    uint64_t h = 0xcbf29ce484222325ULL;
    if (s->xyz) h = hash_bytes(h, s->xyz, 3 * s->n_nodes * sizeof *s->xyz);
    if (s->tri) h = hash_bytes(h, s->tri, 3 * s->n_tris * sizeof *s->tri);
    if (normals) h = hash_bytes(h ^ 0x9e3779b97f4a7c15ULL, normals, 3 * s->n_nodes * sizeof *normals);
    return h;
}

void rn_entry_free_gl(surf_entry *e)
{
    GLuint b[5] = {e->vbo_geo, e->vbo_t, e->ebo_tri, e->ebo_edge, e->ebo_pts};
    glDeleteBuffers(5, b);
    glDeleteVertexArrays(1, &e->vao);
}

/* Whether the triangles form a closed, consistently oriented surface: every edge used exactly twice,
 * once in each direction. The directed edges are bucketed by their lower node and each bucket sorted:
 * O(edges). Returns 1 when closed and consistent, 0 when not, -1 when out of memory. */
static int closed_consistent(const thx_surface *s)
{
    size_t nn = s->n_nodes, nt = s->n_tris;
    if (!nt) return 0;
    size_t *start = calloc(nn + 2, sizeof *start);
    uint64_t *other = malloc(3 * nt * sizeof *other);
    int ok = 1;
    if (!start || !other) {
        ok = -1;
        goto done;
    }
    for (size_t t = 0; t < nt; t++)
        for (int k = 0; k < 3; k++) {
            uint32_t a = (uint32_t)s->tri[3 * t + k], b = (uint32_t)s->tri[3 * t + (k + 1) % 3];
            start[(a < b ? a : b) + 2]++;
        }
    for (size_t i = 2; i < nn + 2; i++) start[i] += start[i - 1];
    for (size_t t = 0; t < nt; t++)
        for (int k = 0; k < 3; k++) {
            uint32_t a = (uint32_t)s->tri[3 * t + k], b = (uint32_t)s->tri[3 * t + (k + 1) % 3];
            /* the upper node, and the direction in the lowest bit */
            other[start[(a < b ? a : b) + 1]++] = 2 * (uint64_t)(a < b ? b : a) + (a > b);
        }
    for (size_t i = 0; i < nn && ok; i++) {
        size_t b0 = start[i], b1 = start[i + 1];
        for (size_t j = b0 + 1; j < b1; j++) {
            uint64_t x = other[j];
            size_t k = j;
            for (; k > b0 && other[k - 1] > x; k--) other[k] = other[k - 1];
            other[k] = x;
        }
        if ((b1 - b0) % 2) ok = 0;
        for (size_t j = b0; j + 1 < b1 && ok; j += 2) /* pairs (2 u, 2 u + 1), each upper node once */
            if (other[j] % 2 || other[j + 1] != other[j] + 1 || (j + 2 < b1 && other[j + 2] / 2 == other[j] / 2))
                ok = 0;
    }
done:
    free(start);
    free(other);
    return ok;
}

/* Uploads the geometry of s into e: positions and vertex normals (floats, interleaved: normals given,
 * else area-weighted from the triangles), a per-node value buffer, and the triangles. */
static thx_status entry_upload(thx_ctx *ctx, surf_entry *e, const thx_surface *s, const double *normals, uint64_t hash)
{
    size_t nn = s->n_nodes, nt = s->n_tris;
    if (nn > UINT32_MAX || nt > (size_t)INT_MAX / 3 || (nn && !s->xyz) || (nt && !s->tri))
        return thx_error(ctx, THX_EINPUT, "renderer: surface \"%s\": %zu nodes and %zu triangles cannot be drawn",
                         s->name, nn, nt);
    for (size_t i = 0; i < 3 * nt; i++)
        if (s->tri[i] < 0 || (size_t)s->tri[i] >= nn)
            return thx_error(ctx, THX_EINPUT, "renderer: surface \"%s\": triangle %zu has node %d of %zu", s->name,
                             i / 3, (int)s->tri[i], nn);
    for (size_t i = 0; i < 3 * nn; i++)
        if (!isfinite(s->xyz[i]))
            return thx_error(ctx, THX_EINPUT, "renderer: surface \"%s\": node %zu has a non-finite coordinate",
                             s->name, i / 3);
    double *acc = thx_calloc(ctx, 3 * nn + 1, sizeof *acc);
    float *geo = thx_malloc(ctx, (6 * nn + 1) * sizeof *geo);
    if (!acc || !geo) {
        free(acc);
        free(geo);
        return THX_ENOMEM;
    }
    if (normals) memcpy(acc, normals, 3 * nn * sizeof *acc);
    else thx_surface_normal_sums(s, acc);
    for (int k = 0; k < 3; k++) e->lo[k] = INFINITY, e->hi[k] = -INFINITY;
    for (size_t i = 0; i < nn; i++) {
        double *n = acc + 3 * i, l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (int k = 0; k < 3; k++) {
            double x = s->xyz[3 * i + k];
            geo[6 * i + k] = (float)x;
            geo[6 * i + 3 + k] = l > 0 ? (float)(n[k] / l) : (k == 2 ? 1.0f : 0.0f);
            e->lo[k] = fmin(e->lo[k], x);
            e->hi[k] = fmax(e->hi[k], x);
        }
    }
    free(acc);
    if (!e->vao) {
        glGenVertexArrays(1, &e->vao);
        glGenBuffers(1, &e->vbo_geo);
        glGenBuffers(1, &e->vbo_t);
        glGenBuffers(1, &e->ebo_tri);
    }
    glBindVertexArray(e->vao);
    glBindBuffer(GL_ARRAY_BUFFER, e->vbo_geo);
    glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(6 * nn * sizeof(float)), geo, GL_STATIC_DRAW);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), (void *)0);
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), (void *)(3 * sizeof(float)));
    glBindBuffer(GL_ARRAY_BUFFER, e->vbo_t);
    glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(nn * sizeof(float)), NULL, GL_DYNAMIC_DRAW);
    glEnableVertexAttribArray(2);
    glVertexAttribPointer(2, 1, GL_FLOAT, GL_FALSE, sizeof(float), (void *)0);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, e->ebo_tri);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, (GLsizeiptr)(3 * nt * sizeof(uint32_t)), s->tri, GL_STATIC_DRAW);
    glBindVertexArray(0);
    glBindBuffer(GL_ARRAY_BUFFER, 0);
    free(geo);
    e->surf = s;
    e->n_nodes = nn;
    e->n_tris = nt;
    e->xyz = s->xyz;
    e->tri = s->tri;
    e->hash = hash;
    e->edges_ok = 0;
    e->n_edges = 0;
    int closed = closed_consistent(s);
    if (closed < 0) return thx_error(ctx, THX_ENOMEM, "renderer: out of memory checking surface \"%s\"", s->name);
    e->cull = closed ? (thx_surface_volume(s) > 0 ? GL_BACK : GL_FRONT) : 0;
    return rn_gl_check(ctx, "uploading a surface");
}

/* The cache entry of s, uploading it when it is new or has changed. */
thx_status rn_cache_get(thx_ctx *ctx, thx_renderer *r, const thx_surface *s, const double *normals, surf_entry **out)
{
    uint64_t h = surface_hash(s, normals);
    surf_entry *same_ptr = NULL;
    for (size_t i = 0; i < r->n_cache; i++) {
        surf_entry *e = r->cache[i];
        if (e->surf != s) continue;
        if (e->n_nodes == s->n_nodes && e->n_tris == s->n_tris && e->xyz == s->xyz && e->tri == s->tri &&
            e->hash == h) {
            e->last_used = r->frame;
            *out = e;
            return THX_OK;
        }
        same_ptr = e;
    }
    surf_entry *e = same_ptr;
    if (!e) {
        THX_CHECK(rn_grow(ctx, (void **)&r->cache, &r->cap_cache, r->n_cache + 1, sizeof *r->cache));
        e = thx_calloc(ctx, 1, sizeof *e);
        if (!e) return THX_ENOMEM;
        r->cache[r->n_cache++] = e;
    }
    e->last_used = r->frame;
    thx_status st = entry_upload(ctx, e, s, normals, h);
    if (st != THX_OK) e->surf = NULL; /* never matches until uploaded again */
    *out = e;
    return st;
}

/* Drops the least recently used entries beyond CACHE_KEEP that the current frame did not use. */
void rn_cache_trim(thx_renderer *r)
{
    while (r->n_cache > CACHE_KEEP) {
        size_t oldest = SIZE_MAX;
        for (size_t i = 0; i < r->n_cache; i++)
            if (r->cache[i]->last_used != r->frame &&
                (oldest == SIZE_MAX || r->cache[i]->last_used < r->cache[oldest]->last_used))
                oldest = i;
        if (oldest == SIZE_MAX) return;
        rn_entry_free_gl(r->cache[oldest]);
        free(r->cache[oldest]);
        r->cache[oldest] = r->cache[--r->n_cache];
    }
}

/* The unique edges of the triangles, for the wire mode (built at its first use): the edges are
 * bucketed by their lower node, each bucket sorted and deduplicated, in O(edges). */
thx_status rn_entry_edges(thx_ctx *ctx, surf_entry *e, const thx_surface *s)
{
    if (e->edges_ok) return THX_OK;
    size_t nn = s->n_nodes, nt = s->n_tris;
    size_t *start = thx_calloc(ctx, nn + 2, sizeof *start);
    uint32_t *other = thx_malloc(ctx, (3 * nt + 1) * sizeof *other);
    uint32_t *pairs = thx_malloc(ctx, (6 * nt + 1) * sizeof *pairs);
    thx_status st = THX_OK;
    if (!start || !other || !pairs) {
        st = THX_ENOMEM;
        goto done;
    }
    for (size_t t = 0; t < nt; t++)
        for (int k = 0; k < 3; k++) {
            uint32_t a = (uint32_t)s->tri[3 * t + k], b = (uint32_t)s->tri[3 * t + (k + 1) % 3];
            start[(a < b ? a : b) + 2]++;
        }
    for (size_t i = 2; i < nn + 2; i++) start[i] += start[i - 1];
    for (size_t t = 0; t < nt; t++)
        for (int k = 0; k < 3; k++) {
            uint32_t a = (uint32_t)s->tri[3 * t + k], b = (uint32_t)s->tri[3 * t + (k + 1) % 3];
            other[start[(a < b ? a : b) + 1]++] = a < b ? b : a;
        }
    size_t ne = 0;
    for (size_t i = 0; i < nn; i++) {
        size_t b0 = start[i], b1 = start[i + 1];
        for (size_t j = b0 + 1; j < b1; j++) { /* insertion sort: buckets hold a handful */
            uint32_t x = other[j];
            size_t k = j;
            for (; k > b0 && other[k - 1] > x; k--) other[k] = other[k - 1];
            other[k] = x;
        }
        for (size_t j = b0; j < b1; j++)
            if (j == b0 || other[j] != other[j - 1]) {
                pairs[2 * ne] = (uint32_t)i;
                pairs[2 * ne + 1] = other[j];
                ne++;
            }
    }
    if (!e->ebo_edge) glGenBuffers(1, &e->ebo_edge);
    glBindVertexArray(e->vao);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, e->ebo_edge);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, (GLsizeiptr)(2 * ne * sizeof(uint32_t)), pairs, GL_STATIC_DRAW);
    glBindVertexArray(0);
    e->n_edges = ne;
    e->edges_ok = 1;
done:
    free(start);
    free(other);
    free(pairs);
    return st;
}
