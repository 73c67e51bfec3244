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

/* NRRD (.nrrd attached, .nhdr detached; reading both, writing .nrrd): src/image/nrrd.c. */
thx_status thx_image_read_nrrd(thx_ctx *ctx, const char *path, thx_image *img);
thx_status thx_image_write_nrrd(thx_ctx *ctx, const thx_image *img, thx_voxel_type type, thx_atomic_file *af);
/* MetaImage (.mha with LOCAL data, .mhd with a detached file; reading both, writing .mha):
 * src/image/metaimage.c. */
thx_status thx_image_read_metaimage(thx_ctx *ctx, const char *path, thx_image *img);
thx_status thx_image_write_metaimage(thx_ctx *ctx, const thx_image *img, thx_voxel_type type, thx_atomic_file *af);

/* Voxel bytes as files store them (src/image/voxels.c, shared by the NRRD and MetaImage code). */
typedef enum {
    THX_RAW_INT8, THX_RAW_UINT8, THX_RAW_INT16, THX_RAW_UINT16, THX_RAW_INT32, THX_RAW_UINT32,
    THX_RAW_INT64, THX_RAW_UINT64, THX_RAW_FLOAT32, THX_RAW_FLOAT64
} thx_raw_type;
/* Bytes per value, and the name image.h's stored_type uses ("int8", ..., "float64"). */
size_t thx_raw_size(thx_raw_type t);
const char *thx_raw_name(thx_raw_type t);
/* The stored type of a writer's voxel type. */
thx_raw_type thx_raw_of_voxel(thx_voxel_type t);
/* img->v from thx_image_count(img) values of type t at bytes (big_endian: most significant byte
 * first); sets stored_type and integral. */
void thx_image_decode(thx_image *img, const unsigned char *bytes, thx_raw_type t, int big_endian);
/* img->v from exactly thx_image_count(img) numbers written as text (blanks, commas or newlines between
 * them) in text[0..len); fewer ("truncated") or more are refused naming `what`. */
thx_status thx_image_decode_ascii(thx_ctx *ctx, thx_image *img, const char *text, size_t len, thx_raw_type t,
                                  const char *what);
/* Inflates the zlib or gzip stream src[0..n) into exactly `need` bytes at dst: a stream that ends
 * sooner ("truncated"), is corrupt, or holds more (or bytes after it) is refused naming `what`. */
thx_status thx_image_inflate(thx_ctx *ctx, const unsigned char *src, size_t n, unsigned char *dst, size_t need,
                             const char *what);
/* Inflates the whole zlib or gzip stream src[0..n) into a new buffer (*out, *len bytes; caller frees), at
 * most thx_image_inflate_bound(n) bytes; corrupt, unfinished or followed by other bytes: refused. */
thx_status thx_image_inflate_all(thx_ctx *ctx, const unsigned char *src, size_t n, unsigned char **out, size_t *len,
                                 const char *what);
/* The most a deflate stream of n bytes can inflate to (zlib's limit, about 1032:1, with slack): a
 * header claiming more voxels than that is refused before anything is allocated. */
double thx_image_inflate_bound(size_t n);
/* The voxels as type t, little-endian, in a new buffer (*len bytes; caller frees). */
thx_status thx_image_encode(thx_ctx *ctx, const thx_image *img, thx_voxel_type t, unsigned char **out, size_t *len);
/* Deflates src[0..n): gzip (with THX_IMAGE_MARKER as the gzip comment) or zlib; caller frees *out. */
thx_status thx_image_deflate(thx_ctx *ctx, const unsigned char *src, size_t n, int gzip, unsigned char **out,
                             size_t *len, const char *what);
/* Writes head[0..nh) then data[0..nd) to a temporary file beside af->path and moves it into place
 * under the claim (thx_output_place): the whole file or nothing. */
thx_status thx_image_place_bytes(thx_ctx *ctx, thx_atomic_file *af, const char *head, size_t nh,
                                 const unsigned char *data, size_t nd);
/* The file a detached header names: `name` as is when absolute, else beside `header`. */
void thx_image_beside(const char *header, const char *name, char *out, size_t size);

#endif
