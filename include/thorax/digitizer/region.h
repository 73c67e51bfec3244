/*
 * thorax/digitizer/region.h — the threshold tool (issue 26 item 2: "threshold plus a seed click fills
 * a connected region and takes its boundary as the loop"), on one plane (thorax/digitizer/livewire.h
 * for planes and pixel coordinates).
 *
 * The region: the pixels with lo <= value <= hi connected to the seed's pixel (4- or 8-connected;
 * NaN samples are outside). Its boundary: the zero level of m(p) = min(value - lo, hi - value) on the
 * region's pixels and -|m| (or a tiny negative where the value is in the window but the pixel not in
 * the region) elsewhere, by marching squares with linear interpolation on the cell edges (saddles
 * resolved by the same connectivity): the place where the interpolated image crosses the window's
 * bound between a pixel of the region and one outside, so sub-voxel where the image is smooth. Holes
 * are filled: the loop is the outer boundary, counterclockwise in (a, b) (for an axial RAS plane,
 * counterclockwise seen from +z).
 */
#ifndef THORAX_DIGITIZER_REGION_H
#define THORAX_DIGITIZER_REGION_H

#include "thorax/image/sample.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    size_t n_pixels; /* pixels of the region */
    size_t n_holes;  /* loops of its boundary other than the outer one (filled) */
    double area;     /* area enclosed by the loop, mm^2 */
} thx_region_info;

/*
 * The loop round the region of [lo, hi] holding the pixel nearest the RAS point `seed`: *xyz
 * (malloc'd, the caller frees) holds *n RAS points. conn8: 1 for 8-connectivity, 0 for 4. info may
 * be NULL. THX_EINPUT when lo > hi, the seed lies outside the plane, or its value is outside the
 * window (the message gives the value).
 */
thx_status thx_region_loop(thx_ctx *ctx, const thx_image_slice *plane, double lo, double hi, const double seed[3],
                           int conn8, double **xyz, size_t *n, thx_region_info *info);

#ifdef __cplusplus
}
#endif
#endif
