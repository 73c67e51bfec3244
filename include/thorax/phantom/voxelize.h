/*
 * thorax/phantom/voxelize.h — closed surfaces and the phantom as images: label maps and
 * simulated scans (issue 25 item 4; docs/design/image.md, "The phantom as a scan, and voxelizing
 * a model").
 *
 * Regions. Every point of space has one region: 0 outside every surface, else 1 + the index of
 * the innermost surface that holds it. For a model's surfaces "innermost" is the one of smallest
 * enclosed volume among those holding the point (nested shells: the inner one; disjoint organs:
 * their own); for the phantom it is its anatomy's nesting (thorax/phantom/phantom.h). Region r's
 * label value is r.
 *
 * Partial volume. Each voxel's region fractions come from sub-samples: thx_voxelize casts n x n
 * rays per voxel along the image's third index axis and measures exactly how much of each ray's
 * length inside the voxel lies in each region (crossings with the triangles by exact orientation
 * predicates and a symbolic perturbation of the ray: a ray through an edge or a vertex crosses a
 * closed surface the right number of times); thx_phantom_voxelize evaluates the analytic point
 * test at n x n x n points per voxel wherever the voxel's eight corners are not all in one region
 * (elsewhere the voxel is that region whole). The label of a voxel is the region of the largest
 * fraction (the plurality). Ties: for the phantom the region at the voxel's centre decides a tie
 * it is part of (else the higher region); for surfaces, whose fractions are exact, a tie is a
 * boundary through the voxel's centre and goes to the higher region when i + j + k is even, to the
 * lower when odd (a layer of such voxels keeps its volume). A scan mixes the tissues' intensities by
 * the fractions.
 */
#ifndef THORAX_PHANTOM_VOXELIZE_H
#define THORAX_PHANTOM_VOXELIZE_H

#include "thorax/image/image.h"
#include "thorax/model/surface.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Tissues of the simulated scans. */
typedef enum {
    THX_TISSUE_AIR = 0,
    THX_TISSUE_FAT,
    THX_TISSUE_MUSCLE,
    THX_TISSUE_SOFT,  /* soft tissue, mediastinum, everything inside the body not named otherwise */
    THX_TISSUE_LUNG,
    THX_TISSUE_HEART, /* myocardium and blood inside the epicardium */
    THX_TISSUE_COUNT
} thx_tissue;

typedef enum { THX_MODALITY_LABELS = 0, THX_MODALITY_CT, THX_MODALITY_MR } thx_modality;

const char *thx_tissue_name(thx_tissue t);
/* The tissue's intensity: CT in Hounsfield units, MR a T1-weighted-like value (arbitrary units,
 * 0..1000); labels: -1. */
double thx_tissue_value(thx_modality m, thx_tissue t);

/* The tissue of the region inside a surface of this role: outer -> fat when the model has a
 * surface of role fat (the subcutaneous layer), else soft tissue; fat (the fat/muscle interface)
 * -> muscle; muscle (its inner border) -> soft tissue; lung -> lung; heart -> heart; other ->
 * soft tissue. */
thx_tissue thx_tissue_of_role(thx_role role, int model_has_fat);

/* An axis-aligned grid (dir = I) covering the box lo..hi with `margin` voxels more on every side,
 * voxel faces on multiples of h (so that planes at multiples of h, the phantom's caps, fall on
 * faces), voxel centres at origin + h (i, j, k). Allocates img (values 0). */
thx_status thx_voxel_grid(thx_ctx *ctx, const double lo[3], const double hi[3], double h, int margin, thx_image *img);

typedef struct {
    int sub;               /* sub-samples per voxel side (n; default 4, 1..16) */
    const double *values;  /* value per region (n_regions entries) for `mix`; NULL: no mix */
} thx_voxelize_opts;

void thx_voxelize_opts_default(thx_voxelize_opts *o);

/* Voxelizes closed surfaces s[0..ns-1] (each closed and consistently oriented, either way round)
 * on the grid of `labels` (allocated by the caller; its geometry is used, its values replaced by
 * region numbers) and, when mix is not NULL (same geometry) and o->values is set, mix = sum over
 * regions of fraction * value. Regions: above (innermost by enclosed volume). THX_EINPUT when a
 * surface is not closed (a ray leaves it inside: its name and the ray), or ns exceeds 254. */
thx_status thx_voxelize(thx_ctx *ctx, const thx_surface *const *s, size_t ns, const thx_voxelize_opts *o,
                        thx_image *labels, thx_image *mix);

/* The phantom's analytic anatomy (thorax/phantom/phantom.h, regions 0..6) on the grid of labels,
 * likewise; *mixed (may be NULL) is the number of voxels that were sub-sampled. */
thx_status thx_phantom_voxelize(thx_ctx *ctx, const thx_voxelize_opts *o, thx_image *labels, thx_image *mix,
                                size_t *mixed);

/* Noise and bias of a simulated scan, applied in place to img (the mixed intensities).
 * bias: the multiplicative field b = 1 + bias * q(u, v, w), with u, v, w in -1..1 across the
 * grid's extent along its index axes and q = 0.5 u + 0.3 v + 0.2 (2 w^2 - 1) (|q| <= 1): smooth,
 * low order. For CT it multiplies the attenuation, HU + 1000, not the HU.
 * noise: standard deviation sigma, Gaussian (v + sigma n1) or Rician (|v + sigma n1 + i sigma n2|,
 * the magnitude of a complex MR signal; MR only), n1, n2 standard normal drawn per voxel from
 * (seed, voxel index): the same seed gives the same image, whatever the order of computation. */
typedef enum { THX_NOISE_GAUSSIAN = 0, THX_NOISE_RICIAN } thx_noise_kind;
thx_status thx_scan_degrade(thx_ctx *ctx, thx_image *img, thx_modality m, double bias, double sigma,
                            thx_noise_kind kind, unsigned long seed);

#ifdef __cplusplus
}
#endif
#endif
