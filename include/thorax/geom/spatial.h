/*
 * thorax/geom/spatial.h — a bounding-volume hierarchy over axis-aligned boxes
 * (typically the bounding boxes of a surface's triangles), for "which
 * triangles may touch this one / this segment" queries in O(log n + k).
 *
 * Invariants:
 *  - Boxes are closed: two boxes that merely touch (share a face, an edge or a
 *    corner) overlap. Queries are therefore conservative, never missing a
 *    candidate whose exact geometry could touch the query.
 *  - The tree is built by median splits on the longest axis of the box
 *    centres, ties broken by box index: the same input gives the same tree and
 *    the same visiting order, whatever the thread count.
 *  - A built tree is read-only; concurrent queries from many threads are safe.
 */
#ifndef THORAX_SPATIAL_H
#define THORAX_SPATIAL_H

#include "thorax/core/core.h"
#ifdef __cplusplus
extern "C" {
#endif

typedef struct thx_bvh thx_bvh;

/* Called once per box found by a query, with the box index; returning
 * non-zero stops the query (the query then returns that value). */
typedef int (*thx_bvh_visit_fn)(void *user, size_t box);

/* Builds a tree over n boxes; box i spans [lo[3i..3i+2], hi[3i..3i+2]]
 * (lo <= hi componentwise; NaN coordinates are rejected with THX_EINPUT).
 * The tree copies what it needs; caller destroys *out. n = 0 is allowed. */
thx_status thx_bvh_create(thx_ctx *ctx, const double *lo, const double *hi, size_t n, thx_bvh **out);

/* Convenience: a tree over the bounding boxes of triangles tri[3t..3t+2]
 * (0-based node indices into xyz, all < n_nodes; checked: THX_EINPUT). */
thx_status thx_bvh_create_triangles(thx_ctx *ctx, const double *xyz, size_t n_nodes, const int32_t *tri,
                                    size_t n_tris, thx_bvh **out);

/* Frees the tree; accepts NULL; nulls *b. */
void thx_bvh_destroy(thx_bvh **b);

/* Number of boxes the tree was built over. */
size_t thx_bvh_size(const thx_bvh *b);

/* Visits every box overlapping the closed box [lo, hi]. */
int thx_bvh_query_box(const thx_bvh *b, const double lo[3], const double hi[3], thx_bvh_visit_fn fn, void *user);

/* Visits every box that the closed segment p-q may touch. The slab test runs
 * in floating point on boxes widened by a relative margin, so it may report
 * extra boxes but never misses one the segment touches; callers decide with
 * exact predicates. */
int thx_bvh_query_segment(const thx_bvh *b, const double p[3], const double q[3], thx_bvh_visit_fn fn, void *user);

#ifdef __cplusplus
}
#endif
#endif
