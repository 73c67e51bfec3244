/*
 * Point location against a closed surface, accelerated by a bounding-volume
 * tree (internal to src/mesh). The volume mesher asks millions of these.
 *
 *  - inside: parity of the crossings of a ray with the triangles, decided
 *    with exact orientation tests; a ray that grazes an edge or a vertex
 *    (some orientation exactly zero) is discarded and another direction
 *    tried, so the answer is exact for points not on the surface.
 *  - near: is any triangle closer than r to the point?
 */
#ifndef THORAX_MESH_LOCATE_H
#define THORAX_MESH_LOCATE_H

#include "thorax/model/surface.h"
#include "thorax/geom/spatial.h"
typedef struct {
    const thx_surface *s;
    thx_bvh *bvh;
    double reach; /* length of the rays: beyond the surface's bounding box */
    /* Voxel cache (built by locator_init, read-only afterwards; vox == NULL:
     * none, every query casts rays). Voxels no triangle's bounding box touches
     * hold no surface point; connected sets of them share one side of the
     * (closed) surface, found by one exact ray each. A point in a touched
     * voxel casts a short segment to the centre of a nearby labelled voxel
     * (ref) and flips that label per crossing, or the long rays if the
     * segment grazes anything. */
    double lo[3], hi[3], inv_h[3], h[3];
    int n[3];
    unsigned char *vox; /* per voxel: 0 touched (no label), 1 inside, 2 outside */
    int32_t *ref;       /* per voxel: a labelled voxel whose centre is its own, or -1 */
    double volume;      /* the volume the surface encloses (set by the mesher) */
} locator;

thx_status locator_init(thx_ctx *ctx, locator *l, const thx_surface *s);
void locator_free(locator *l);
/* 1 inside, 0 outside (points on the surface: either). Thread-safe. */
int locator_inside(const locator *l, thx_vec3 p);
/* 1 if some triangle of the surface lies within distance r of p. Thread-safe. */
int locator_near(const locator *l, thx_vec3 p, double r);

#endif
