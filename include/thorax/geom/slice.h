/*
 * thorax/geom/slice.h — cross-sections of closed surfaces by planes z = const.
 *
 * The inverse of model construction's first step: where digitized contours
 * are the cross-sections of the body with the image planes, slicing a closed
 * surface gives the contours it would have been digitized as. Used to rebuild
 * surfaces made elsewhere from their contours (and to test the builder against
 * known surfaces).
 */
#ifndef THORAX_SLICE_H
#define THORAX_SLICE_H

#include "thorax/model/contours.h"
#include "thorax/geom/contours_valid.h"
#include "thorax/model/model.h"
#ifdef __cplusplus
extern "C" {
#endif

/*
 * Cuts the closed surface s (a 2-manifold) with the plane z = z0 and returns
 * the closed loops of the cross-section in *loops (n_loops of them; each
 * loop's points are malloc'd, as is the array; free with thx_slice_free).
 * A node exactly on the plane counts as lying just above it (symbolic
 * perturbation), so every crossing is transversal and every loop closes;
 * consecutive equal points are merged. Loops run counterclockwise seen from
 * above when the surface is oriented outward (they go around the material on
 * their left). THX_EGEOM if an edge crossing the plane does not belong to
 * exactly two triangles (the surface is not closed there).
 */
thx_status thx_surface_slice(thx_ctx *ctx, const thx_surface *s, double z0, thx_loop **loops, size_t *n_loops);
void thx_slice_free(thx_loop **loops, size_t n_loops);

typedef struct {
    double spacing;      /* distance between the planes, mm (default 5) */
    double margin;       /* first plane this far above the lowest node, last this far below the
                            highest (default spacing / 10) */
    double densify;      /* insert points so that no loop segment is longer than this, mm
                            (0 = keep the crossing points only; default spacing / 2) */
    double node_spacing; /* written as the contour file's `spacing` (default: spacing) */
    int axis;            /* the planes are perpendicular to this axis, 0 x, 1 y, 2 z (default 2). For x
                            and y the model is turned first, (x, y, z) -> (y, z, x) or (z, x, y): a
                            rotation (orientation kept), so the contours' layer coordinate is that
                            axis; the frame is turned with it (issue 24: every axis of a torso) */
} thx_slice_opts;

void thx_slice_opts_default(thx_slice_opts *o);

/* Slices every surface of the model (turned as o->axis says) with common planes spread evenly from zmin + margin to
 * zmax - margin (over all surfaces), at most `spacing` apart, and returns the cross-sections
 * as contours, surface names, roles and the model's frame kept, grid
 * caps. A surface whose cross-section is empty on a plane between two non-empty ones is an
 * error (it would vanish and reappear). Caller destroys *out. */
thx_status thx_model_slice(thx_ctx *ctx, const thx_model *m, const thx_slice_opts *o, thx_contours **out);

#ifdef __cplusplus
}
#endif
#endif
