/*
 * thorax/geom/landmark_mesh.h — triangle meshes of map3d landmarks (thorax/model/landmarks.h)
 * for drawing with the surfaces: tubes for arteries, catheters, cannulas and rods, spheres for
 * sites, discs for planes, arrows for fibres (geom layer).
 *
 * A radius within 1e-9 of the point's coordinates (the tolerance at which points coincide) counts
 * as 0 below.
 *
 * Every mesh is a closed, edge-manifold triangle surface, triangles counterclockwise seen from
 * outside (thx_surface_volume > 0), with no triangle of zero area; several disjoint closed
 * pieces for a segment of several sites. Millimetres, the landmarks' frame.
 *
 * Shapes (docs/decisions.md, "Landmark meshes"):
 *  - Tube (artery, cath, cannula): a polygonal tube along the points, `sides` facets around, the
 *    radius at each point linearly interpolated between points. Cross-sections are carried along
 *    the polyline by parallel transport (no twist); at a bend the ring lies in the bisecting
 *    plane, stretched there so that both straight pieces keep their round section (a mitre
 *    joint). The polygon's size is chosen so that its area is pi r^2: the tube's volume is the
 *    frustum volume sum pi h (r1^2 + r1 r2 + r2^2) / 3 exactly for a straight tube, whatever
 *    `sides`. Ends are closed by flat caps, or by a point where the end's radius is 0. A radius
 *    of 0 inside a tube, or at every point, is drawn as min_radius. A point repeated (at one
 *    place as its predecessor) with the same radius is skipped; with another radius it makes a
 *    flat step.
 *  - Spheres (occlusion, closure, stimulus, lead, paceneedle, recneedle): an icosphere of the
 *    point's radius (min_radius where it is 0) at every point, nodes on the sphere.
 *  - Disc (plane): a flat cylinder about the centroid of the three points, axis their normal,
 *    radius point 1's radius, thickness point 2's (min_radius where 0, and never more than the
 *    disc's diameter), `disc_sides` facets around.
 *  - Rod: a tube of point 1's radius (min_radius where 0) along the points.
 *  - Arrow (fiber): a tube of point 1's radius (min_radius where 0) along the points, with a
 *    cone of 2.5 times that radius at the last point (its length the lesser of 6 radii and 40%
 *    of the last piece).
 */
#ifndef THORAX_GEOM_LANDMARK_MESH_H
#define THORAX_GEOM_LANDMARK_MESH_H

#include "thorax/model/landmarks.h"
#include "thorax/model/surface.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    int sides;          /* facets around a tube, rod or arrow, 3..256 (default 12) */
    int disc_sides;     /* facets around a plane's disc, 3..1024 (default 48) */
    int sphere_level;   /* icosphere subdivisions, 0..5 (default 2: 162 nodes, 320 triangles) */
    double min_radius;  /* mm, 0.001..1e7: drawn where a radius is 0 (default 0.5) */
} thx_landmark_mesh_opts;

void thx_landmark_mesh_opts_default(thx_landmark_mesh_opts *o);

/* One mesh per segment, in the set's order. */
typedef struct {
    size_t n;              /* = the set's segments */
    thx_surface **surf;    /* n surfaces, named "landmark_K_TYPE" (K 1-based), role "other" */
    float (*rgba)[4];      /* n colours (thx_landmark_color) */
} thx_landmark_meshes;

/* The colour a segment is drawn in: its own (r g b / 255, alpha 1) when the file gave one, else
 * its type's default: map3d's manual where it says (occlusion cyan, closure blue, stimulus
 * yellow), map3d's program otherwise (artery and cannula red, lead blue, cath cyan, rod, needles
 * and fiber green, plane magenta); a plane's alpha is 0.5, as in map3d. */
void thx_landmark_color(const thx_landmark_segment *s, float rgba[4]);
/* The default colour of a type (as above). */
void thx_landmark_type_color(thx_landmark_type t, float rgba[4]);

/* The mesh of segment k (0-based, for names and messages) of a set; the segment is validated
 * first (thx_landmark_segment_validate). o NULL: defaults. Caller destroys *out. */
thx_status thx_landmark_segment_mesh(thx_ctx *ctx, const thx_landmark_segment *s, size_t k,
                                     const thx_landmark_mesh_opts *o, thx_surface **out);
/* The meshes of every segment (set validated first). Caller destroys *out with
 * thx_landmark_meshes_destroy. */
thx_status thx_landmarks_mesh(thx_ctx *ctx, const thx_landmarks *lm, const thx_landmark_mesh_opts *o,
                              thx_landmark_meshes **out);
/* Frees the meshes and colours; accepts NULL; nulls *m. */
void thx_landmark_meshes_destroy(thx_landmark_meshes **m);

#ifdef __cplusplus
}
#endif
#endif
