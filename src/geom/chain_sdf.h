/*
 * Signed distance to a closed chain in its layer plane, accelerated by a tree of boxes.
 * Internal to src/geom (lacing, caps and orientation ask it millions of times).
 *
 * The chain's edges are grouped in blocks of CHAIN_BLOCK consecutive edges, and the blocks in a
 * balanced binary tree over their order along the chain, each node with the bounding box of its
 * run of edges (the run from point `first` to point `last`). A query descends the tree, nearer
 * child first, and skips a node that can neither be nearer than the best distance so far nor
 * contribute to the winding number. The winding number is counted by signed crossings of the ray
 * from q toward +x (the paper's angle sum divided by 2 pi, see thorax/geom/inside.h); a node that
 * lies wholly to the right of q (every x > q.x) adds, without a visit, the signed crossings of its
 * run with the line y = q.y, which telescope to [last.y > q.y] - [first.y > q.y]. So a query
 * costs O(log n) plus the blocks near q and along the ray, where the plain loop (issue 24: a
 * 40,000-point comb took 45 s to build) cost O(n).
 */
#ifndef THORAX_CHAIN_SDF_H
#define THORAX_CHAIN_SDF_H

#include "thorax/model/surface.h"
#define CHAIN_BLOCK 8

typedef struct {
    double x0, y0, x1, y1;
    size_t first, last; /* the node's run of edges: from point first to point last (mod n) */
} chain_box;

typedef struct {
    size_t n;            /* points (= edges) of the closed chain */
    const thx_vec2 *p;   /* borrowed */
    size_t n_blocks;
    size_t leaves;       /* tree: node 1 the root, node k's children 2k and 2k+1, leaves from `leaves` */
    chain_box *box;      /* owned, 2 * leaves nodes (empty ones have x0 = +inf) */
} chain_index;

/* Builds the tree of chain p[0..n-1]; returns 0, or -1 when out of memory. */
int chain_index_init(chain_index *ci, const thx_vec2 *p, size_t n);
void chain_index_free(chain_index *ci);
/* Signed distance from q to the chain: negative inside (nonzero winding number). */
double chain_index_sdf(const chain_index *ci, thx_vec2 q);

#endif
