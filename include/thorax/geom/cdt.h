/*
 * thorax/geom/cdt.h — 2D constrained Delaunay triangulation and end caps
 * (paper 3.2, "Completing the model").
 *
 * All orientation decisions use the exact predicates of thorax/geom/predicates.h,
 * so the results are exact for the given double coordinates (no epsilon).
 * Indices are 0-based. Triangles are returned counterclockwise in the (x, y)
 * plane (positive signed area). Output is deterministic: the same input gives
 * the same triangles in the same order.
 */
#ifndef THORAX_CDT_H
#define THORAX_CDT_H

#include "thorax/model/surface.h"
#ifdef __cplusplus
extern "C" {
#endif

/*
 * Constrained Delaunay triangulation of the convex hull of pts[0..n-1].
 *
 * segs holds n_segs constraint segments as index pairs (segs[2k], segs[2k+1]);
 * every segment is an edge of the output, and every other edge is locally
 * Delaunay (constrained Delaunay: no vertex visible from a triangle lies
 * strictly inside its circumcircle). Without segments the result is a
 * Delaunay triangulation; with cocircular points, which of the valid
 * triangulations is returned is unspecified but deterministic.
 * Points on the hull between two hull corners (collinear) are vertices of the
 * triangulation, so the triangle count is 2n - h - 2 (h = number of points on
 * the hull boundary, corners and collinear ones).
 *
 * On success *tris holds 3 * *n_tris vertex indices (counterclockwise), owned
 * by the caller (free()). If n < 3 or all points are collinear there is no
 * triangle: THX_OK with *n_tris = 0 and *tris = NULL (segments are then not
 * checked).
 *
 * Errors (message in ctx, *tris = NULL, *n_tris = 0):
 *   THX_EINPUT  a segment index out of range or a segment with equal ends;
 *               a non-finite coordinate.
 *   THX_EGEOM   two points coincide; a segment passes through another input
 *               point; two segments cross (a shared endpoint is fine; a
 *               repeated segment is fine).
 *   THX_ENOMEM
 * Cost: O(n log n) expected (points are inserted in Hilbert-curve order with
 * a walk from the previous insertion); segment recovery is linear in the
 * number of edges each segment crosses.
 */
thx_status thx_cdt2d(thx_ctx *ctx, const thx_vec2 *pts, size_t n, const int32_t *segs, size_t n_segs,
                     int32_t **tris, size_t *n_tris);

/*
 * Triangulates the end cap bounded by a simple closed loop (paper 3.2: "either
 * by triangulating the points in the layer, or by adding a grid of points to
 * fill in the region ... and then triangulating the resulting augmented
 * layer", then removing triangles outside a concave curve by the inside test
 * on their centroids).
 *
 * loop: n >= 3 distinct points of a simple polygon, either direction, any
 *   concavity; the closing edge loop[n-1] -> loop[0] is implicit (do not
 *   repeat the first point).
 * grid_spacing == 0: "polygon" method, no new points.
 * grid_spacing > 0: "grid" method: the nodes of the square grid
 *   ((i + 1/2) h, (j + 1/2) h), i, j integers, h = grid_spacing (in the
 *   loop's own coordinates, so the grid does not depend on the loop's start
 *   point or direction) that lie inside the loop at a distance >= tol from it
 *   are added (the caller typically passes tol = 0.5 h, so that no sliver
 *   forms against the loop). tol >= 0.
 *
 * Output: *out_pts holds the n loop points (same order) followed by the added
 * grid points (row by row, increasing y then x); *tris holds 3 * *n_tris
 * 0-based indices into *out_pts, counterclockwise in the (x, y) plane
 * (positive area; the caller flips them for a cap seen from the other side).
 * Both arrays are owned by the caller (free()).
 * Guarantees: each loop edge i -> i+1 is an edge of exactly one output
 * triangle, every other edge of exactly two (the cap is watertight against
 * the loop), and the triangle areas sum to |thx_loop_area(loop)| (up to
 * rounding).
 * Errors: THX_EINPUT (n < 3, negative spacing or tol, non-finite
 *   coordinates, more than 10^8 grid nodes); THX_EGEOM (the loop repeats a
 *   point or intersects itself, including a vertex lying on another edge);
 *   THX_ENOMEM. On error the outputs are NULL / 0.
 */
thx_status thx_cap_triangulate(thx_ctx *ctx, const thx_vec2 *loop, size_t n, double grid_spacing, double tol,
                               thx_vec2 **out_pts, size_t *n_out, int32_t **tris, size_t *n_tris);

#ifdef __cplusplus
}
#endif
#endif
