/*
 * Signed distance to a closed chain in its layer plane, accelerated by blocks.
 * Internal to src/geom (lacing and orientation ask it millions of times).
 *
 * The chain's edges are grouped in blocks of CHAIN_BLOCK consecutive edges
 * with their bounding boxes. A query skips a block when the block can neither
 * be nearer than the best distance so far nor contribute to the winding
 * number (the horizontal ray from p toward +x cannot cross it), so the result
 * is exactly that of the plain loop over all edges, at a fraction of the cost.
 * The winding number is counted by signed crossings, which equals the
 * paper's angle sum divided by 2 pi (see thorax/geom/inside.h).
 */
#ifndef THORAX_CHAIN_SDF_H
#define THORAX_CHAIN_SDF_H

#include "thorax/model/surface.h"
#define CHAIN_BLOCK 8

typedef struct {
    double x0, y0, x1, y1;
} chain_box;

typedef struct {
    size_t n;            /* points (= edges) of the closed chain */
    const thx_vec2 *p;   /* borrowed */
    size_t n_blocks;
    chain_box *box;      /* owned */
} chain_index;

/* Builds the block boxes of chain p[0..n-1]; returns 0, or -1 when out of memory. */
int chain_index_init(chain_index *ci, const thx_vec2 *p, size_t n);
void chain_index_free(chain_index *ci);
/* Signed distance from q to the chain: negative inside (nonzero winding number). */
double chain_index_sdf(const chain_index *ci, thx_vec2 q);

#endif
