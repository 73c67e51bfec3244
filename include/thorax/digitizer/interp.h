/*
 * thorax/digitizer/interp.h — loops interpolated between two digitized planes (issue 26 item 2), by
 * shape-based interpolation (Raya & Udupa 1990; Herman, Zheng & Bucholtz 1992): each loop's region
 * becomes its signed distance (positive inside, the exact distance to the loop's edges, within a
 * band), the two are mixed linearly, (1 - t) dA + t dB, and the zero level is traced (marching
 * squares) as the loop at t. Unlike pairing the loops' points, this needs no correspondence and
 * follows a shape that shifts, grows or changes between the planes; two circles of radii rA and rB
 * with the same centre give the circle of radius (1 - t) rA + t rB exactly (up to the grid).
 *
 * Loops are 2D, in the planes' common in-plane coordinates (for axial planes of an axis-aligned image,
 * RAS x and y in mm): the caller maps the planes' points; any start, any direction.
 */
#ifndef THORAX_DIGITIZER_INTERP_H
#define THORAX_DIGITIZER_INTERP_H

#include "thorax/core/core.h"
#include "thorax/core/vec.h"

#ifdef __cplusplus
extern "C" {
#endif

/*
 * The loop at t (0 < t < 1: 0 is a's plane, 1 b's) between the closed loops a[0..na-1] and
 * b[0..nb-1], traced on a grid of `step` (same unit; e.g. half the pixel size): *out (malloc'd, the
 * caller frees) *n points, counterclockwise, about `step` apart; the largest loop when the mix has
 * several. THX_EINPUT for a loop of fewer than 3 points, t outside [0, 1], step <= 0 or one giving
 * more than 2^26 grid cells; THX_EGEOM when the mix is empty (two loops too far apart to overlap at t).
 */
thx_status thx_loop_interpolate(thx_ctx *ctx, const thx_vec2 *a, size_t na, const thx_vec2 *b, size_t nb, double t,
                                double step, thx_vec2 **out, size_t *n);

#ifdef __cplusplus
}
#endif
#endif
