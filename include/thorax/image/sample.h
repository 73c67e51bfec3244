/*
 * thorax/image/sample.h — planes cut through an image volume (issue 25: the scan shown under the
 * model) and the grey-level window a scan is shown with.
 *
 * A plane is named as on the command line: "z=MM", "y=MM", "x=MM" (a RAS plane: axial, coronal,
 * sagittal, at that coordinate in millimetres) or "k=N", "j=N", "i=N" (the image's own plane of
 * index N along that index axis, 0-based; oblique in RAS when the image is).
 *
 * A RAS plane is sampled on a grid of the RAS axes in it (z: x then y; y: x then z; x: y then z)
 * whose step along each is the spacing of the index axis most nearly along it, placed so that for
 * an axis-aligned image the samples fall on voxel centres (a plane through voxel centres gives the
 * voxels' values exactly). An index plane is sampled at its voxel centres. Samples outside the
 * image (beyond half a voxel from the outer centres) are NaN.
 */
#ifndef THORAX_IMAGE_SAMPLE_H
#define THORAX_IMAGE_SAMPLE_H

#include "thorax/image/image.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    char axis;   /* 'x', 'y', 'z' (RAS, pos in mm) or 'i', 'j', 'k' (index axis, pos an index) */
    double pos;
} thx_image_plane_spec;

/* "z=-20.5", "k=12", ... -> *out; 0, or -1 when s is not such a plane (a finite number required). */
int thx_image_plane_parse(const char *s, thx_image_plane_spec *out);

/* The values of a plane and where each lies. */
typedef struct {
    size_t w, h;          /* samples along u (rows) and v */
    float *v;             /* w h values, row by row (sample (a, b) at v[a + w b]); NaN outside the image */
    double origin[3];     /* RAS mm of sample (0, 0)'s centre */
    double du[3], dv[3];  /* RAS mm from a sample to the next along u and along v */
    double normal[3];     /* unit normal (+x, +y, +z for RAS planes; the index axis' direction otherwise) */
    double step;          /* the distance to the image's next plane along the normal, in the spec's unit
                             (mm for RAS planes, 1 for index planes) */
    double lo, hi;        /* the positions the spec's axis may take inside the image (same unit) */
} thx_image_slice;

/* The range of positions along the spec's axis that lie inside the image (mm: the voxels' outer
 * faces along that RAS axis; index: 0 .. n - 1) and the step between its planes there. */
void thx_image_plane_range(const thx_image *img, char axis, double *lo, double *hi, double *step);

/* Samples the plane (trilinear between voxel centres, or the nearest voxel's value with nearest
 * = 1, for label maps). THX_EINPUT naming the image when the plane lies outside the image's extent
 * ("z=500 is outside IMG: z from -20 to 20 mm") or the axis is unknown. out->v malloc'd. */
thx_status thx_image_sample_plane(thx_ctx *ctx, const thx_image *img, const thx_image_plane_spec *spec, int nearest,
                                  thx_image_slice *out);
void thx_image_slice_free(thx_image_slice *s);

/* The value at RAS point p (trilinear, or nearest); NaN outside the image. */
double thx_image_sample_at(const thx_image *img, const double p[3], int nearest);

/* How an image is shown by default. */
typedef enum {
    THX_WINDOW_LABELS = 0, /* a label map (integral, >= 0, at most 256 distinct values): the full range */
    THX_WINDOW_CT,         /* values like Hounsfield units (min <= -500, max >= 200): soft tissue, 400 / 40 */
    THX_WINDOW_PERCENTILE  /* otherwise: the 1st to the 99th percentile */
} thx_window_kind;

/* The default window (width) and level (centre) of an image's grey levels: grey = (value - (level -
 * window / 2)) / window, clamped to [0, 1]. A window of zero width (a constant image) is widened
 * to 1. Returns the kind chosen. */
thx_window_kind thx_image_window_default(const thx_image *img, double *window, double *level);
/* "label map, full range", "Hounsfield units, soft tissue", "1st-99th percentile". */
const char *thx_window_kind_name(thx_window_kind k);

#ifdef __cplusplus
}
#endif
#endif
