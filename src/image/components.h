/*
 * 6-connected components of a byte mask (src/image/components.c): the one flood fill that the
 * tracer's cleaning (trace.c: small components and cavities) and the segmentation's largest
 * component (segment.c) share. Private to the image module.
 */
#ifndef THORAX_IMAGE_COMPONENTS_H
#define THORAX_IMAGE_COMPONENTS_H

#include <stddef.h>
#include "thorax/core/core.h"

/* Called once per component: its voxel count, whether it touches a face of the box, and its
 * ordinal (0, 1, ... in the order of its first voxel in memory order, k then j then i); returns the
 * value (0 or 1) its voxels get. */
typedef unsigned char (*thx_cc_decide)(void *user, size_t size, int touches_box, size_t ordinal);

/* Visits the 6-connected components of the voxels equal to `val` (0 or 1) of the n[0] x n[1] x n[2]
 * mask (i fastest) inside the box lo <= index < hi per axis, in the order of their first voxel, and
 * sets each component's voxels to decide()'s answer. The mask holds 0 and 1 outside and inside the
 * box and on return (bits 1 and 2 mark visited voxels while it runs). Scanline fill: runs along i,
 * seeded into the four neighbouring rows; memory is the runs, not the voxels. Returns the number
 * of components through *n_components (may be NULL). */
thx_status thx_components6(thx_ctx *ctx, unsigned char *mask, const size_t n[3], const size_t lo[3], const size_t hi[3],
                           unsigned char val, thx_cc_decide decide, void *user, size_t *n_components);

#endif
