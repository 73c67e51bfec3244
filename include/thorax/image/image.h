/*
 * thorax/image/image.h — image volumes (scans and label maps): the pipeline's first input
 * (paper 3.1: the model begins with MRI planes). One in-memory form for every format.
 *
 * Coordinates: thorax's patient frame is RAS millimetres, as NIfTI's and thorax's own models
 * (thorax/model/frame.h): +x toward the subject's right, +y anterior, +z superior. DICOM's LPS
 * (+x toward the subject's left, +y posterior) becomes RAS by negating x and y.
 *
 * A voxel (i, j, k) (0-based, i fastest in memory) has its centre at
 *     x = origin + dir * diag(spacing) * (i, j, k)
 * where dir is a rotation (orthonormal to 1e-4, determinant +1 or -1: a left-handed voxel
 * order is allowed, it is the file's business) whose column c is the RAS unit vector of index
 * axis c. Values are float after the file's rescale (NIfTI scl_slope/scl_inter, DICOM
 * RescaleSlope/RescaleIntercept); `integral` says every value is an exact integer of the
 * stored integer type (a label map candidate; integers up to 2^24 are exact in float).
 *
 * Invariants after a successful read (thx_image_validate): n[c] >= 1, n0*n1*n2 voxels held,
 * spacing finite and > 0, origin finite, dir orthonormal, every value finite.
 */
#ifndef THORAX_IMAGE_IMAGE_H
#define THORAX_IMAGE_IMAGE_H

#include <stddef.h>

#include "thorax/core/core.h"
#include "thorax/model/frame.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The marker every image thorax writes carries in its first bytes (the NIfTI descrip field, the
 * gzip header's comment, the NRRD/MetaImage header): thorax replaces only its own images. */
#define THX_IMAGE_MARKER "thorax-image"

typedef struct thx_image {
    size_t n[3];            /* voxels along index axes i, j, k */
    float *v;               /* n[0]*n[1]*n[2] values, i fastest, then j, then k */
    double spacing[3];      /* mm between voxel centres along each index axis, > 0 */
    double origin[3];       /* RAS mm of voxel (0, 0, 0)'s centre */
    double dir[9];          /* row-major 3x3; column c (dir[0*3+c], dir[1*3+c], dir[2*3+c]) = RAS unit vector of axis c */
    int integral;           /* stored as integers (and rescaled by integers): labels possible */
    char stored_type[16];   /* the file's voxel type: "uint8", "int16", "uint16", "int32", "float32", "float64", ... */
    char format[16];        /* "nifti1", "nifti2", "nrrd", "metaimage", "dicom", "" (built in memory) */
    char source_frame[32];  /* the frame the file declared: "RAS", "LPS", "scanner", "aligned", "pixdim", ... */
    char path[1024];        /* file (or DICOM folder) read, "" if built in memory */
    char sha256[65];        /* SHA-256 of the file read (DICOM: of the sorted slice files' hashes), "" if none */
} thx_image;

/* Options of thx_image_read. Zero-initialized means the defaults. */
typedef struct {
    const char *series;     /* DICOM: series to read when a folder holds several (UID, or 1-based number
                               as `thorax image info` lists them); NULL: the folder must hold one */
} thx_image_read_opts;

/* Allocates img->v for n[0]*n[1]*n[2] voxels (zeroed) and sets identity geometry (spacing 1, origin 0,
 * dir I); every other field cleared. THX_EINPUT when a dimension is 0 or the product overflows. */
thx_status thx_image_alloc(thx_ctx *ctx, const size_t n[3], thx_image *img);
/* Frees img->v and clears *img (NULL accepted). */
void thx_image_free(thx_image *img);

/* Number of voxels n0*n1*n2. */
size_t thx_image_count(const thx_image *img);
/* Linear index of voxel (i, j, k). */
static inline size_t thx_image_at(const thx_image *img, size_t i, size_t j, size_t k)
{
    return i + img->n[0] * (j + img->n[1] * k);
}
/* Continuous index (i, j, k) -> RAS mm, and back. */
void thx_image_index_to_ras(const thx_image *img, const double ijk[3], double ras[3]);
void thx_image_ras_to_index(const thx_image *img, const double ras[3], double ijk[3]);

/* The index axis that points most nearly superior (+z in RAS) and the sign along it (+1: index
 * increasing goes up); likewise anterior (+y). *cosine (may be NULL) is the |cosine| of the superior
 * axis with RAS +z: 1 for an axial image, below 1 for an oblique one. */
void thx_image_axes(const thx_image *img, int *sup_axis, int *sup_sign, int *ant_axis, int *ant_sign,
                    double *cosine);
/* Whether dir is a signed permutation (every column along one RAS axis to 1e-6): an image whose
 * planes are RAS planes. */
int thx_image_axis_aligned(const thx_image *img);

/* Checks the invariants above; messages name `what` (the file) and the offending field, voxel
 * (i, j, k) or matrix. THX_EINPUT when they fail. */
thx_status thx_image_validate(thx_ctx *ctx, const thx_image *img, const char *what);

/* Reads an image, choosing the reader by name: .nii/.nii.gz (NIfTI-1 or -2), .nrrd/.nhdr, .mha/.mhd,
 * a folder or a .dcm file (DICOM series). Every value finite and the geometry valid or THX_EINPUT
 * naming the file; a file shorter than its header claims is refused (never half-read). Fills
 * path, format, sha256. On failure *img is cleared. */
thx_status thx_image_read(thx_ctx *ctx, const char *path, const thx_image_read_opts *opts, thx_image *img);

/* Writes an image, the format chosen by name (.nii, .nii.gz, .nrrd, .nhdr, .mha, .mhd). `type` is the
 * voxel type to store ("uint8", "int16", "uint16", "int32", "float32"; NULL: int16/uint8/int32 for an
 * integral image as its range needs, else float32); values that the type cannot hold exactly are
 * refused (THX_EINPUT naming the voxel). Atomic, and only over thorax's own images
 * (THX_IMAGE_MARKER; thorax/core/fileio.h rules). */
thx_status thx_image_write(thx_ctx *ctx, const thx_image *img, const char *path, const char *type);

/* Minimum and maximum value. */
void thx_image_range(const thx_image *img, float *lo, float *hi);

#ifdef __cplusplus
}
#endif

#endif
