/*
 * In-plane patches of a laced surface given interior nodes (internal to src/geom; build.c's step 3b).
 *
 * The lacing closes what neither layer can reach (a pocket cut off in its plane, a filled pocket: a
 * CT skull's cavity closed in the plane where the frontal sinus notches its loop) with triangles in
 * the plane of one layer, made from that region's boundary nodes only. A large round region so
 * triangulated has triangles down to a fraction of a degree (~300 boundary nodes: 0.2-0.6 degrees),
 * which thorax check fails (its 1-degree floor: what thorax mesh can take). Such a patch is
 * triangulated again as a grid cap is: its boundary kept edge for edge, grid nodes inside.
 */
#ifndef THORAX_GEOM_INPLANE_H
#define THORAX_GEOM_INPLANE_H

#include <stddef.h>

#include "thorax/core/core.h"
#include "thorax/model/surface.h"

/* Triangles [0, n_laced) of s whose three nodes share one z are grouped into patches by shared edges.
 * A patch with an angle under min_angle_deg whose boundary is one simple loop is triangulated again by
 * thx_cap_triangulate with grid nodes `grid` mm apart (at least grid/2 from the loop), kept when its
 * smallest angle is larger than the patch's was. The patches' triangles are replaced in place of the
 * first ones and the rest removed (the other triangles keep their order); new nodes are appended (z of
 * the patch). *node_cap and *tri_cap: the capacities of s->xyz (nodes) and s->tri (triangles), grown as
 * needed. *n_refined: the patches triangulated again. Deterministic. */
thx_status thx_inplane_refine(thx_ctx *ctx, thx_surface *s, size_t n_laced, double grid, double min_angle_deg,
                              size_t *node_cap, size_t *tri_cap, size_t *n_refined);

/* Smallest angle (degrees) of the triangle (a, b, c) in the (x, y) plane; of triangle t of s in the
 * (x, y) plane (an in-plane one). */
double inplane_min_angle2(double ax, double ay, double bx, double by, double cx, double cy);
double inplane_tri_min_angle(const thx_surface *s, size_t t);

/* Step 3c (inplane_resolve.c): in each layer plane where the in-plane triangles (caps, cut pockets and
 * tongues) overlap or an in-plane edge is in other than two triangles (the slices below and above both
 * cut the same part of their shared layer), those triangles are replaced by one triangulation of the
 * region they should cover: the even-odd interior of the in-plane edges that exactly one laced ("wall")
 * triangle uses, by a constrained Delaunay triangulation with grid nodes `grid` mm apart (at least
 * grid/2 from the boundary). A plane where that region is not well formed (an edge in three wall
 * triangles, a boundary node with other than two boundary edges, boundary edges that cross) is left as
 * it was. The new in-plane triangles come last (*n_new_tris of them). A well-formed plane with an in-plane angle under min_angle_deg (a patch step 3b could not
 * take) is triangulated the same way, kept when its smallest angle is larger. New triangles are appended, new nodes appended (the plane's z); nodes only the old triangles
 * used stay (thx_surface_drop_unused). *n_resolved: the planes replaced. Deterministic. */
thx_status thx_inplane_resolve(thx_ctx *ctx, thx_surface *s, double grid, double min_angle_deg, size_t *node_cap,
                               size_t *tri_cap, size_t *n_resolved, size_t *n_new_tris);

/* Removes the nodes no triangle uses, renumbering the rest in order. *n_dropped: how many. */
thx_status thx_surface_drop_unused(thx_ctx *ctx, thx_surface *s, size_t *n_dropped);

#endif
