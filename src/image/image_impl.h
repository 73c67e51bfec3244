/*
 * Private pieces of the image module (src/image/): the per-format readers and writers that
 * thx_image_read and thx_image_write (src/image/image.c) dispatch to, and helpers they share.
 * Not installed; the entry points are in thorax/image/image.h.
 *
 * Every reader fills *img (allocated with thx_image_alloc) with the values after rescale and the
 * geometry in RAS, sets format, stored_type, source_frame and integral; the dispatcher then sets
 * path and sha256 and validates. On failure a reader frees what it allocated and names the file.
 * Every writer writes under the claim `af` (thx_output_claim done by the dispatcher with
 * THX_IMAGE_MARKER) and commits by thx_output_place, so nothing is left half-written.
 */
#ifndef THORAX_IMAGE_IMPL_H
#define THORAX_IMAGE_IMPL_H

#include "thorax/core/fileio.h"
#include "thorax/image/image.h"

/* The voxel types a writer stores. */
typedef enum { THX_VOXEL_UINT8, THX_VOXEL_INT16, THX_VOXEL_UINT16, THX_VOXEL_INT32, THX_VOXEL_FLOAT32 } thx_voxel_type;

/* NIfTI-1/-2 (.nii, .nii.gz) through libnifti2: src/image/nifti.c. */
thx_status thx_image_read_nifti(thx_ctx *ctx, const char *path, thx_image *img);
thx_status thx_image_write_nifti(thx_ctx *ctx, const thx_image *img, thx_voxel_type type, thx_atomic_file *af);

/* The voxel type named by `name` (NULL: chosen from the image's range, see thx_image_write) and the
 * check that every value fits it exactly; THX_EINPUT naming the first voxel that does not. */
thx_status thx_image_choose_type(thx_ctx *ctx, const thx_image *img, const char *name, const char *path,
                                 thx_voxel_type *type);
/* The name of a voxel type ("uint8", ...). */
const char *thx_voxel_type_name(thx_voxel_type t);
/* Whether `path` ends with `suffix`, ignoring case. */
int thx_image_has_suffix(const char *path, const char *suffix);
/* A temporary file name beside af->path ending in `suffix` (".nii", ".nii.gz", ...) for a writer that goes
 * through another library; THX_EIO when it cannot be made. The caller removes it (thx_output_place does). */
thx_status thx_image_temp_beside(thx_ctx *ctx, const thx_atomic_file *af, const char *suffix, char *tmp, size_t size);

#endif
