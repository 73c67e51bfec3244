/*
 * Disjoint sets over 0 .. n-1 (a header-only helper of core): parent[i] = i at the
 * start; find with path halving; union makes the smaller root the root, so
 * the representatives, and every count derived from them, do not depend on
 * the order of the unions.
 */
#ifndef THORAX_CORE_UNION_FIND_H
#define THORAX_CORE_UNION_FIND_H

#include <stddef.h>

static inline size_t uf_find(size_t *parent, size_t x)
{
    while (parent[x] != x) {
        parent[x] = parent[parent[x]];
        x = parent[x];
    }
    return x;
}

static inline void uf_union(size_t *parent, size_t a, size_t b)
{
    a = uf_find(parent, a);
    b = uf_find(parent, b);
    if (a < b) parent[b] = a;
    else if (b < a) parent[a] = b;
}

#endif
