/* Image volumes: the in-memory form, its geometry and checks, and the read/write dispatch by name
 * (thorax/image/image.h). The formats are in nifti.c (and the other readers beside it). */
#include "image/image_impl.h"
#include "image/dicom.h"

#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include "thorax/core/sha256.h"

thx_status thx_image_alloc(thx_ctx *ctx, const size_t n[3], thx_image *img)
{
    memset(img, 0, sizeof *img);
    size_t count = 1;
    for (int c = 0; c < 3; c++) {
        if (n[c] == 0) return thx_error(ctx, THX_EINPUT, "image: dimension %d is 0", c + 1);
        if (count > SIZE_MAX / sizeof(float) / n[c])
            return thx_error(ctx, THX_EINPUT, "image: %zu x %zu x %zu voxels do not fit in memory", n[0], n[1], n[2]);
        count *= n[c];
    }
    img->v = calloc(count, sizeof *img->v);
    if (!img->v)
        return thx_error(ctx, THX_ENOMEM, "image: out of memory for %zu x %zu x %zu voxels (%.1f MB)", n[0], n[1], n[2],
                         (double)count * sizeof(float) / 1e6);
    for (int c = 0; c < 3; c++) {
        img->n[c] = n[c];
        img->spacing[c] = 1.0;
        img->dir[c * 3 + c] = 1.0;
    }
    img->integral = 1;
    return THX_OK;
}

void thx_image_free(thx_image *img)
{
    if (!img) return;
    free(img->v);
    memset(img, 0, sizeof *img);
}

size_t thx_image_count(const thx_image *img) { return img->n[0] * img->n[1] * img->n[2]; }

void thx_image_index_to_ras(const thx_image *img, const double ijk[3], double ras[3])
{
    for (int r = 0; r < 3; r++) {
        double s = img->origin[r];
        for (int c = 0; c < 3; c++) s += img->dir[r * 3 + c] * img->spacing[c] * ijk[c];
        ras[r] = s;
    }
}

void thx_image_ras_to_index(const thx_image *img, const double ras[3], double ijk[3])
{
    /* dir is orthonormal: its inverse is its transpose */
    double d[3] = {ras[0] - img->origin[0], ras[1] - img->origin[1], ras[2] - img->origin[2]};
    for (int c = 0; c < 3; c++) {
        double s = 0;
        for (int r = 0; r < 3; r++) s += img->dir[r * 3 + c] * d[r];
        ijk[c] = s / img->spacing[c];
    }
}

/* The index axis whose direction has the largest |component| along RAS axis `ras`, and its sign. */
static void nearest_axis(const thx_image *img, int ras, int exclude, int *axis, int *sign, double *cosine)
{
    int best = -1;
    double bv = -1;
    for (int c = 0; c < 3; c++) {
        if (c == exclude) continue;
        double v = fabs(img->dir[ras * 3 + c]);
        if (v > bv) {
            bv = v;
            best = c;
        }
    }
    *axis = best;
    *sign = img->dir[ras * 3 + best] >= 0 ? 1 : -1;
    if (cosine) *cosine = bv;
}

void thx_image_axes(const thx_image *img, int *sup_axis, int *sup_sign, int *ant_axis, int *ant_sign, double *cosine)
{
    int sa, ss, aa, as;
    nearest_axis(img, 2, -1, &sa, &ss, cosine);
    nearest_axis(img, 1, sa, &aa, &as, NULL);
    if (sup_axis) *sup_axis = sa;
    if (sup_sign) *sup_sign = ss;
    if (ant_axis) *ant_axis = aa;
    if (ant_sign) *ant_sign = as;
}

int thx_image_axis_aligned(const thx_image *img)
{
    for (int c = 0; c < 3; c++) {
        int big = 0;
        for (int r = 0; r < 3; r++) {
            double v = fabs(img->dir[r * 3 + c]);
            if (fabs(v - 1) <= 1e-6) big++;
            else if (v > 1e-6) return 0;
        }
        if (big != 1) return 0;
    }
    return 1;
}

thx_status thx_image_validate(thx_ctx *ctx, const thx_image *img, const char *what)
{
    if (!img->v) return thx_error(ctx, THX_EINPUT, "%s: image holds no voxels", what);
    for (int c = 0; c < 3; c++) {
        if (img->n[c] == 0) return thx_error(ctx, THX_EINPUT, "%s: dimension %d is 0", what, c + 1);
        if (!isfinite(img->spacing[c]) || img->spacing[c] <= 0)
            return thx_error(ctx, THX_EINPUT, "%s: voxel spacing along axis %d is %g mm (must be finite and > 0)", what,
                             c + 1, img->spacing[c]);
        if (!isfinite(img->origin[c]))
            return thx_error(ctx, THX_EINPUT, "%s: origin coordinate %d is not finite", what, c + 1);
    }
    /* dir orthonormal: D^T D = I to 1e-4 */
    for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++) {
            double s = 0;
            for (int r = 0; r < 3; r++) s += img->dir[r * 3 + a] * img->dir[r * 3 + b];
            double want = a == b ? 1.0 : 0.0;
            if (!isfinite(s) || fabs(s - want) > 1e-4)
                return thx_error(ctx, THX_EINPUT,
                                 "%s: the direction matrix [%g %g %g; %g %g %g; %g %g %g] is not orthonormal (columns %d "
                                 "and %d: dot product %g, should be %g): a skewed or scaled voxel grid is not supported",
                                 what, img->dir[0], img->dir[1], img->dir[2], img->dir[3], img->dir[4], img->dir[5],
                                 img->dir[6], img->dir[7], img->dir[8], a + 1, b + 1, s, want);
        }
    size_t count = thx_image_count(img);
    for (size_t q = 0; q < count; q++)
        if (!isfinite(img->v[q])) {
            size_t i = q % img->n[0], j = (q / img->n[0]) % img->n[1], k = q / (img->n[0] * img->n[1]);
            return thx_error(ctx, THX_EINPUT, "%s: voxel (%zu, %zu, %zu) is %s (every value must be finite)", what, i,
                             j, k, isnan(img->v[q]) ? "NaN" : "infinite");
        }
    return THX_OK;
}

void thx_image_range(const thx_image *img, float *lo, float *hi)
{
    size_t count = thx_image_count(img);
    float a = count ? img->v[0] : 0, b = a;
    for (size_t q = 1; q < count; q++) {
        if (img->v[q] < a) a = img->v[q];
        if (img->v[q] > b) b = img->v[q];
    }
    *lo = a;
    *hi = b;
}

int thx_image_has_suffix(const char *path, const char *suffix)
{
    size_t n = strlen(path), m = strlen(suffix);
    return n >= m && strcasecmp(path + n - m, suffix) == 0;
}

const char *thx_voxel_type_name(thx_voxel_type t)
{
    switch (t) {
    case THX_VOXEL_UINT8: return "uint8";
    case THX_VOXEL_INT16: return "int16";
    case THX_VOXEL_UINT16: return "uint16";
    case THX_VOXEL_INT32: return "int32";
    case THX_VOXEL_FLOAT32: return "float32";
    }
    return "?";
}

thx_status thx_image_choose_type(thx_ctx *ctx, const thx_image *img, const char *name, const char *path,
                                 thx_voxel_type *type)
{
    float lo, hi;
    thx_image_range(img, &lo, &hi);
    thx_voxel_type t;
    if (name) {
        static const thx_voxel_type all[] = {THX_VOXEL_UINT8, THX_VOXEL_INT16, THX_VOXEL_UINT16, THX_VOXEL_INT32,
                                             THX_VOXEL_FLOAT32};
        size_t k = 0;
        while (k < sizeof all / sizeof all[0] && strcmp(thx_voxel_type_name(all[k]), name) != 0) k++;
        if (k == sizeof all / sizeof all[0])
            return thx_error(ctx, THX_EINPUT, "%s: unknown voxel type \"%s\" (uint8, int16, uint16, int32, float32)",
                             path, name);
        t = all[k];
    } else if (!img->integral) {
        t = THX_VOXEL_FLOAT32;
    } else if (lo >= 0 && hi <= 255) {
        t = THX_VOXEL_UINT8;
    } else if (lo >= -32768 && hi <= 32767) {
        t = THX_VOXEL_INT16;
    } else if (lo >= -16777216.0f && hi <= 16777216.0f) {
        t = THX_VOXEL_INT32;
    } else {
        t = THX_VOXEL_FLOAT32;
    }
    if (t == THX_VOXEL_FLOAT32) {
        *type = t;
        return THX_OK;
    }
    double tlo = t == THX_VOXEL_UINT8 ? 0 : t == THX_VOXEL_INT16 ? -32768 : t == THX_VOXEL_UINT16 ? 0 : -2147483648.0;
    double thi = t == THX_VOXEL_UINT8 ? 255 : t == THX_VOXEL_INT16 ? 32767 : t == THX_VOXEL_UINT16 ? 65535 : 2147483647.0;
    size_t count = thx_image_count(img);
    for (size_t q = 0; q < count; q++) {
        double v = img->v[q];
        if (v != floor(v) || v < tlo || v > thi) {
            size_t i = q % img->n[0], j = (q / img->n[0]) % img->n[1], k = q / (img->n[0] * img->n[1]);
            return thx_error(ctx, THX_EINPUT, "%s: voxel (%zu, %zu, %zu) = %g cannot be stored exactly as %s", path, i, j,
                             k, v, thx_voxel_type_name(t));
        }
    }
    *type = t;
    return THX_OK;
}

thx_status thx_image_temp_beside(thx_ctx *ctx, const thx_atomic_file *af, const char *suffix, char *tmp, size_t size)
{
    int n = snprintf(tmp, size, "%s.tmpXXXXXX%s", af->path, suffix);
    if (n < 0 || (size_t)n >= size) return thx_error(ctx, THX_EIO, "%s: path too long", af->path);
    int fd = mkstemps(tmp, (int)strlen(suffix));
    if (fd < 0) {
        int e = errno;
        tmp[0] = '\0';
        return thx_error(ctx, THX_EIO, "%s: cannot create a temporary file beside it: %s", af->path, strerror(e));
    }
    fchmod(fd, 0644);
    close(fd);
    return THX_OK;
}

/* What a file's first bytes say it is ("NRRD", "NIfTI-1", "NIfTI-2", "MetaImage", "DICOM", "gzip"),
 * or NULL: the check that a file is what its name says, so that a misnamed file gets a message that
 * says what it is rather than a reader's complaint about a header it was never meant to read. */
static const char *sniff(const char *path)
{
    unsigned char b[600];
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    size_t n = fread(b, 1, sizeof b, f);
    fclose(f);
    if (n >= 7 && !memcmp(b, "NRRD000", 7)) return "NRRD";
    if (n >= 2 && b[0] == 0x1f && b[1] == 0x8b) return "gzip";
    if (n >= 348 && (!memcmp(b + 344, "n+1", 4) || !memcmp(b + 344, "ni1", 4))) return "NIfTI-1";
    if (n >= 12 && (!memcmp(b + 4, "n+2", 4) || !memcmp(b + 4, "ni2", 4))) return "NIfTI-2";
    if (n >= 132 && !memcmp(b + 128, "DICM", 4)) return "DICOM";
    /* MetaImage: a first line "Key = Value" with a MetaIO key */
    static const char *const keys[] = {"ObjectType", "NDims", "Comment", "ObjectSubType", "Name"};
    for (size_t k = 0; k < sizeof keys / sizeof keys[0]; k++) {
        size_t m = strlen(keys[k]);
        if (n > m && !memcmp(b, keys[k], m) && (b[m] == ' ' || b[m] == '=')) return "MetaImage";
    }
    return NULL;
}

/* The format a name says, or NULL. */
static const char *named(const char *path)
{
    if (thx_image_has_suffix(path, ".nii") || thx_image_has_suffix(path, ".nii.gz")) return "NIfTI";
    if (thx_image_has_suffix(path, ".nrrd") || thx_image_has_suffix(path, ".nhdr")) return "NRRD";
    if (thx_image_has_suffix(path, ".mha") || thx_image_has_suffix(path, ".mhd")) return "MetaImage";
    return NULL;
}

static const char *suffix_of(const char *kind)
{
    return !strcmp(kind, "NRRD") ? ".nrrd" : !strcmp(kind, "MetaImage") ? ".mha" : !strcmp(kind, "DICOM") ? ".dcm"
                                                                                                             : ".nii";
}

thx_status thx_image_read(thx_ctx *ctx, const char *path, const thx_image_read_opts *opts, thx_image *img)
{
    memset(img, 0, sizeof *img);
    struct stat st;
    if (stat(path, &st) != 0) return thx_error(ctx, THX_EIO, "%s: cannot open: %s", path, strerror(errno));
    const char *name = named(path), *kind = S_ISREG(st.st_mode) ? sniff(path) : NULL;
    if (name && kind && strcmp(kind, "gzip") != 0 && strncmp(kind, name, strlen(name)) != 0)
        return thx_error(ctx, THX_EINPUT, "%s: named as %s but the file is a %s file (by its first bytes): rename it %s",
                         path, name, kind, suffix_of(kind));
    thx_status s;
    if (name && !strcmp(name, "NIfTI"))
        s = thx_image_read_nifti(ctx, path, img);
    else if (name && !strcmp(name, "NRRD"))
        s = thx_image_read_nrrd(ctx, path, img);
    else if (name && !strcmp(name, "MetaImage"))
        s = thx_image_read_metaimage(ctx, path, img);
    else if (S_ISDIR(st.st_mode) || thx_image_has_suffix(path, ".dcm") || thx_image_is_dicom_file(path))
        s = thx_image_read_dicom(ctx, path, opts ? opts->series : NULL, img);
    else if (kind)
        return thx_error(ctx, THX_EINPUT, "%s: not named as an image thorax reads, but it is %s file: rename it %s",
                         path, !strcmp(kind, "gzip") ? "a gzip" : kind, !strcmp(kind, "gzip") ? ".nii.gz" : suffix_of(kind));
    else
        return thx_error(ctx, THX_EINPUT,
                         "%s: not an image thorax reads (by its name: .nii or .nii.gz for NIfTI, .nrrd or .nhdr for "
                         "NRRD, .mha or .mhd for MetaImage; a folder or .dcm file for a DICOM series)",
                         path);
    if (s != THX_OK) {
        thx_image_free(img);
        return s;
    }
    snprintf(img->path, sizeof img->path, "%s", path);
    if (!img->sha256[0] && (s = thx_sha256_file(ctx, path, img->sha256)) != THX_OK) {
        thx_image_free(img);
        return s;
    }
    if ((s = thx_image_validate(ctx, img, path)) != THX_OK) thx_image_free(img);
    return s;
}

thx_status thx_image_write(thx_ctx *ctx, const thx_image *img, const char *path, const char *type_name)
{
    THX_CHECK(thx_image_validate(ctx, img, "image to write"));
    thx_voxel_type type;
    THX_CHECK(thx_image_choose_type(ctx, img, type_name, path, &type));
    const char *name = named(path);
    if (!name)
        return thx_error(ctx, THX_EINPUT,
                         "%s: thorax writes images as .nii or .nii.gz (NIfTI-1), .nrrd (NRRD) or .mha (MetaImage), by "
                         "the name given",
                         path);
    thx_atomic_file af;
    THX_CHECK(thx_output_claim(ctx, path, THX_IMAGE_MARKER, strlen(THX_IMAGE_MARKER), NULL, 0, &af));
    if (!strcmp(name, "NRRD")) return thx_image_write_nrrd(ctx, img, type, &af);
    if (!strcmp(name, "MetaImage")) return thx_image_write_metaimage(ctx, img, type, &af);
    return thx_image_write_nifti(ctx, img, type, &af);
}
