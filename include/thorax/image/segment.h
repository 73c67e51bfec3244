/*
 * thorax/image/segment.h — a label map from a scan by thresholds, with the clean-up a tissue
 * boundary needs before it is traced (paper 3.1 digitized each boundary as one closed loop per
 * plane: a threshold gives speckle, cavities and objects that are not the subject, such as a CT
 * table or a head holder).
 *
 * Tissues are nested, outer first (skin, then bone; torso, then lungs...): tissue t's region is
 * the voxels inside its value range, together with every later tissue's, kept inside the
 * previous tissue's final region less its boundary voxels (the 3 x 3 x 3 erosion: an inner
 * boundary never meets the outer one, and never reaches the image's faces, so the surfaces traced
 * from the map never touch). Each region in turn is
 *   1. closed morphologically with a ball of the tissue's `close_mm` (gaps narrower than 2 * close_mm
 *      bridged; exact Euclidean distances in mm, anisotropic voxels handled: a thin skull wall broken
 *      by partial volume wants several mm, a scalp with ears and a head holder beside it wants little);
 *   2. cut to its largest 6-connected component (when `largest`);
 *   3. filled plane by plane along the image's superior axis (when `fill_planes`): every part of
 *      a plane not 4-connected to the plane's border through the outside of the region closed in
 *      the plane by a disc of `close_mm` joins the region, so each plane holds no holes (a skull
 *      becomes its outer surface's inside even where partial volume broke its wall wider than the
 *      3-D closing bridges; sinuses and airways join the head);
 * and the output voxel is the label of the innermost tissue whose region holds it, 0 outside.
 */
#ifndef THORAX_IMAGE_SEGMENT_H
#define THORAX_IMAGE_SEGMENT_H

#include "thorax/image/image.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    double lo, hi;   /* value range, inclusive (after the image's rescale: Hounsfield units for CT) */
    int label;       /* label written (1..65535) */
    double close_mm; /* closing radius of this tissue's region, mm (0: none) */
} thx_threshold;

typedef struct {
    const thx_threshold *tissues;  /* outer first */
    size_t n_tissues;
    int largest;                   /* keep the largest 6-connected component of each region */
    int fill_planes;               /* fill each plane's holes along the superior axis */
} thx_segment_opts;

typedef struct {
    size_t voxels[16];             /* final voxel count of each tissue (first 16) */
    size_t dropped[16];            /* voxels of each region outside its largest component */
    size_t filled[16];             /* voxels added by the plane filling */
} thx_segment_report;

/* Writes the label map into *out (allocated here, the input's geometry, integral, format ""). THX_EINPUT
 * when a range is empty or reversed, a label is out of 1..65535, a closing radius is negative, or there are no tissues; rep may be NULL. */
thx_status thx_image_segment(thx_ctx *ctx, const thx_image *in, const thx_segment_opts *opts, thx_image *out,
                             thx_segment_report *rep);

/* Squared Euclidean distance in mm^2 from every voxel to the nearest voxel where mask[q] != 0 (0 in the
 * mask; INFINITY everywhere when the mask is empty), exact (Felzenszwalb and Huttenlocher's separable
 * lower envelope), for a grid of n voxels spaced `spacing` mm. d has n[0]*n[1]*n[2] entries. */
thx_status thx_distance_squared(thx_ctx *ctx, const size_t n[3], const double spacing[3], const unsigned char *mask,
                                float *d);

#ifdef __cplusplus
}
#endif

#endif
