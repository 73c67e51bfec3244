/*
 * A hash set of sorted node triples (internal to src/mesh): faces (a < b < c)
 * and, with c = -1, edges. Open addressing over a power-of-two table whose
 * empty slots have a = -1 (the table is filled with 0xff bytes). Used by the
 * sliver repair (protected faces and edges) and the mesher (the faces on the
 * surfaces that cut the mesh into pieces).
 */
#ifndef THORAX_MESH_TRISET_H
#define THORAX_MESH_TRISET_H

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/core/core.h"
typedef struct { int32_t a, b, c; } triple;
typedef struct { triple *slot; size_t mask; } tset;

static inline triple tri_sorted(int32_t a, int32_t b, int32_t c)
{
    int32_t t;
    if (a > b) { t = a; a = b; b = t; }
    if (b > c) { t = b; b = c; c = t; }
    if (a > b) { t = a; a = b; b = t; }
    return (triple){a, b, c};
}

static inline triple edge_sorted(int32_t a, int32_t b) { return a < b ? (triple){a, b, -1} : (triple){b, a, -1}; }

static inline size_t tset_hash(triple k)
{
    uint64_t h = (uint64_t)(uint32_t)k.a * 0x9E3779B97F4A7C15ull;
    h ^= (uint64_t)(uint32_t)k.b * 0xC2B2AE3D27D4EB4Full + (h >> 29);
    h ^= (uint64_t)(uint32_t)k.c * 0x165667B19E3779F9ull + (h >> 32);
    return (size_t)(h ^ (h >> 31));
}

/* An empty set with room for n keys (at most half full). */
static inline thx_status tset_init(thx_ctx *ctx, tset *s, size_t n)
{
    size_t cap = 16;
    while (cap < 2 * n + 16) cap <<= 1;
    s->slot = thx_malloc(ctx, cap * sizeof *s->slot);
    if (!s->slot) return THX_ENOMEM;
    memset(s->slot, 0xff, cap * sizeof *s->slot);
    s->mask = cap - 1;
    return THX_OK;
}

static inline int tset_has(const tset *s, triple k)
{
    for (size_t i = tset_hash(k) & s->mask;; i = (i + 1) & s->mask) {
        const triple *e = &s->slot[i];
        if (e->a < 0) return 0;
        if (e->a == k.a && e->b == k.b && e->c == k.c) return 1;
    }
}

static inline void tset_add(tset *s, triple k)
{
    for (size_t i = tset_hash(k) & s->mask;; i = (i + 1) & s->mask) {
        triple *e = &s->slot[i];
        if (e->a < 0) { *e = k; return; }
        if (e->a == k.a && e->b == k.b && e->c == k.c) return;
    }
}

#endif
