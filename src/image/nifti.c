/* NIfTI-1 and NIfTI-2 (.nii, .nii.gz) through Debian's libnifti2 (nifti2_io reads both versions
 * and gzip). The geometry follows the standard's order, as nibabel does: the sform when
 * sform_code > 0, else the qform when qform_code > 0, else the pixdims alone. Writing stores
 * NIfTI-1 with the same matrix as sform and qform (codes "scanner"), units mm. */
#include "image/image_impl.h"

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <nifti2_io.h>

static const char *xform_name(int code)
{
    switch (code) {
    case NIFTI_XFORM_SCANNER_ANAT: return "scanner";
    case NIFTI_XFORM_ALIGNED_ANAT: return "aligned";
    case NIFTI_XFORM_TALAIRACH: return "talairach";
    case NIFTI_XFORM_MNI_152: return "mni152";
    case NIFTI_XFORM_TEMPLATE_OTHER: return "template";
    default: return "unknown";
    }
}

/* One stored value as double; *integral cleared for a non-integer type. */
static double stored(const void *data, int dt, size_t q)
{
    switch (dt) {
    case DT_UINT8: return ((const uint8_t *)data)[q];
    case DT_INT8: return ((const int8_t *)data)[q];
    case DT_INT16: return ((const int16_t *)data)[q];
    case DT_UINT16: return ((const uint16_t *)data)[q];
    case DT_INT32: return ((const int32_t *)data)[q];
    case DT_UINT32: return ((const uint32_t *)data)[q];
    case DT_INT64: return (double)((const int64_t *)data)[q];
    case DT_UINT64: return (double)((const uint64_t *)data)[q];
    case DT_FLOAT32: return ((const float *)data)[q];
    case DT_FLOAT64: return ((const double *)data)[q];
    default: return NAN;
    }
}

static const char *type_name(int dt)
{
    switch (dt) {
    case DT_UINT8: return "uint8";
    case DT_INT8: return "int8";
    case DT_INT16: return "int16";
    case DT_UINT16: return "uint16";
    case DT_INT32: return "int32";
    case DT_UINT32: return "uint32";
    case DT_INT64: return "int64";
    case DT_UINT64: return "uint64";
    case DT_FLOAT32: return "float32";
    case DT_FLOAT64: return "float64";
    default: return NULL;
    }
}

/* Whether the file (gzipped or not) begins with a NIfTI-2 header: sizeof_hdr 540 in either byte order
 * and the magic "n+2" or "ni2". Debian's libnifti2 2.1 reads such files but its is_nifti_file()
 * answers -1 for them (and nifti_type says NIfTI-1), so the version is told here. */
static int nifti2_magic(const char *path)
{
    gzFile g = gzopen(path, "rb");
    if (!g) return 0;
    unsigned char b[8];
    int n = gzread(g, b, sizeof b);
    gzclose(g);
    if (n != (int)sizeof b) return 0;
    int le = b[0] == 0x1c && b[1] == 0x02 && !b[2] && !b[3], be = !b[0] && !b[1] && b[2] == 0x02 && b[3] == 0x1c;
    return (le || be) && (!memcmp(b + 4, "n+2", 4) || !memcmp(b + 4, "ni2", 4));
}

/* libnifti replaces NaN and infinite float voxels by 0 as it loads them, silently: the file's own
 * float data are read here first and a non-finite value is refused (index q; *bad = 1). */
static thx_status nonfinite_voxel(thx_ctx *ctx, const nifti_image *nim, const char *path, size_t *q, int *bad)
{
    *bad = 0;
    if (nim->datatype != DT_FLOAT32 && nim->datatype != DT_FLOAT64) return THX_OK;
    const char *data_file = nim->iname ? nim->iname : path;
    gzFile g = gzopen(data_file, "rb");
    if (!g) return thx_error(ctx, THX_EIO, "%s: cannot open its data", path);
    thx_status st = THX_OK;
    int swap = nim->byteorder != nifti_short_order();
    size_t size = (size_t)nim->nbyper, count = (size_t)nim->nvox, done = 0;
    if (gzseek(g, (z_off_t)nim->iname_offset, SEEK_SET) < 0) {
        gzclose(g);
        return thx_error(ctx, THX_EINPUT, "%s: the voxel data are missing: truncated", path);
    }
    unsigned char buf[1 << 16];
    while (done < count && !*bad) {
        size_t want = (count - done) * size < sizeof buf ? (count - done) * size : sizeof buf;
        int got = gzread(g, buf, (unsigned)want);
        if (got <= 0 || (size_t)got % size) break; /* short: nifti_image_load reports it */
        for (size_t k = 0; k < (size_t)got / size; k++) {
            unsigned char v[8];
            for (size_t b = 0; b < size; b++) v[b] = buf[k * size + (swap ? size - 1 - b : b)];
            double x;
            if (size == 4) {
                float f;
                memcpy(&f, v, 4);
                x = f;
            } else {
                memcpy(&x, v, 8);
            }
            if (!isfinite(x)) {
                *q = done + k;
                *bad = isnan(x) ? 1 : 2;
                break;
            }
        }
        done += (size_t)got / size;
    }
    gzclose(g);
    return st;
}

thx_status thx_image_read_nifti(thx_ctx *ctx, const char *path, thx_image *img)
{
    nifti_set_debug_level(0);
    int v2 = nifti2_magic(path);
    int kind = v2 ? 1 : is_nifti_file(path);
    if (kind <= 0)
        return thx_error(ctx, THX_EINPUT, "%s: not a NIfTI-1 or NIfTI-2 file (no valid header%s)", path,
                         kind == 0 ? "; an ANALYZE 7.5 header, which carries no orientation" : "");
    nifti_image *nim = nifti_image_read(path, 0);
    if (!nim) return thx_error(ctx, THX_EINPUT, "%s: the NIfTI header cannot be read", path);
    thx_status st = THX_OK;
    const char *tn = type_name(nim->datatype);
    if (!tn) {
        st = thx_error(ctx, THX_EINPUT, "%s: voxel type %s is not a scalar type thorax reads", path,
                       nifti_datatype_to_string(nim->datatype));
        goto done;
    }
    for (int d = 1; d <= 7; d++) {
        if (nim->dim[d] < 0 && d <= nim->dim[0]) {
            st = thx_error(ctx, THX_EINPUT, "%s: dim[%d] = %lld is negative", path, d, (long long)nim->dim[d]);
            goto done;
        }
        if (d > 3 && d <= nim->dim[0] && nim->dim[d] > 1) {
            st = thx_error(ctx, THX_EINPUT, "%s: a %d-D image (dim[%d] = %lld): thorax reads one 3-D volume", path,
                           (int)nim->dim[0], d, (long long)nim->dim[d]);
            goto done;
        }
    }
    size_t n[3] = {(size_t)(nim->nx > 0 ? nim->nx : 1), (size_t)(nim->ny > 0 ? nim->ny : 1),
                   (size_t)(nim->nz > 0 ? nim->nz : 1)};
    /* the data must all be there: an uncompressed file's size against the header's claim */
    if (!thx_image_has_suffix(path, ".gz")) {
        struct stat sb;
        double need = (double)nim->iname_offset + (double)nim->nvox * nim->nbyper;
        const char *data_file = nim->iname ? nim->iname : path;
        if (stat(data_file, &sb) == 0 && (double)sb.st_size < need) {
            st = thx_error(ctx, THX_EINPUT,
                           "%s: the header claims %zu x %zu x %zu %s voxels (%.0f bytes from offset %lld) but the file "
                           "holds %lld bytes: truncated",
                           path, n[0], n[1], n[2], tn, need - (double)nim->iname_offset, (long long)nim->iname_offset,
                           (long long)sb.st_size);
            goto done;
        }
    } else {
        /* a compressed file: no more voxels than its bytes can inflate to (checked before allocating) */
        struct stat sb;
        double need = (double)nim->iname_offset + (double)nim->nvox * nim->nbyper;
        if (stat(path, &sb) == 0 && need > thx_image_inflate_bound((size_t)sb.st_size)) {
            st = thx_error(ctx, THX_EINPUT,
                           "%s: the header claims %zu x %zu x %zu %s voxels but %lld compressed bytes cannot hold them: "
                           "truncated",
                           path, n[0], n[1], n[2], tn, (long long)sb.st_size);
            goto done;
        }
    }
    if ((st = thx_image_alloc(ctx, n, img)) != THX_OK) goto done;
    size_t badq = 0;
    int bad = 0;
    if ((st = nonfinite_voxel(ctx, nim, path, &badq, &bad)) != THX_OK) goto done;
    if (bad) {
        st = thx_error(ctx, THX_EINPUT, "%s: voxel (%zu, %zu, %zu) is %s (every value must be finite)", path,
                       badq % n[0], (badq / n[0]) % n[1], badq / (n[0] * n[1]), bad == 1 ? "NaN" : "infinite");
        goto done;
    }
    if (nifti_image_load(nim) != 0 || !nim->data) {
        st = thx_error(ctx, THX_EINPUT, "%s: the voxel data are shorter than the header claims (%zu x %zu x %zu %s): truncated",
                       path, n[0], n[1], n[2], tn);
        goto done;
    }
    double slope = nim->scl_slope, inter = nim->scl_inter;
    int rescale = isfinite(slope) && slope != 0 && isfinite(inter) && !(slope == 1 && inter == 0);
    int integer_type = nim->datatype != DT_FLOAT32 && nim->datatype != DT_FLOAT64;
    img->integral = integer_type && (!rescale || (slope == floor(slope) && inter == floor(inter)));
    size_t count = thx_image_count(img);
    /* the common label map types without rescale converted straight (exact in float, the same values
       as through double); every type in parallel, each voxel on its own */
    const void *data = nim->data;
    float *out = img->v;
    if (!rescale && nim->datatype == DT_UINT8) {
#pragma omp parallel for schedule(static)
        for (long q = 0; q < (long)count; q++) out[q] = ((const uint8_t *)data)[q];
    } else if (!rescale && nim->datatype == DT_INT16) {
#pragma omp parallel for schedule(static)
        for (long q = 0; q < (long)count; q++) out[q] = ((const int16_t *)data)[q];
    } else if (!rescale && nim->datatype == DT_UINT16) {
#pragma omp parallel for schedule(static)
        for (long q = 0; q < (long)count; q++) out[q] = ((const uint16_t *)data)[q];
    } else {
        int dt = nim->datatype;
#pragma omp parallel for schedule(static)
        for (long q = 0; q < (long)count; q++) {
            double v = stored(data, dt, (size_t)q);
            out[q] = (float)(rescale ? slope * v + inter : v);
        }
    }
    snprintf(img->stored_type, sizeof img->stored_type, "%s", tn);
    snprintf(img->format, sizeof img->format, "%s",
             v2 || nim->nifti_type == NIFTI_FTYPE_NIFTI2_1 || nim->nifti_type == NIFTI_FTYPE_NIFTI2_2 ? "nifti2"
                                                                                                 : "nifti1");
    /* geometry: 4x4 index -> world */
    double m[3][4];
    if (nim->sform_code > 0 || nim->qform_code > 0) {
        const nifti_dmat44 *a = nim->sform_code > 0 ? &nim->sto_xyz : &nim->qto_xyz;
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < 4; c++) m[r][c] = a->m[r][c];
        snprintf(img->source_frame, sizeof img->source_frame, "RAS (%s %s)", nim->sform_code > 0 ? "sform" : "qform",
                 xform_name(nim->sform_code > 0 ? nim->sform_code : nim->qform_code));
    } else {
        memset(m, 0, sizeof m);
        m[0][0] = nim->dx;
        m[1][1] = nim->ny > 1 || nim->dy != 0 ? nim->dy : 1;
        m[2][2] = nim->nz > 1 || nim->dz != 0 ? nim->dz : 1;
        snprintf(img->source_frame, sizeof img->source_frame, "pixdim (no sform or qform)");
    }
    double unit = nim->xyz_units == NIFTI_UNITS_METER ? 1000.0 : nim->xyz_units == NIFTI_UNITS_MICRON ? 0.001 : 1.0;
    for (int c = 0; c < 3; c++) {
        double len = sqrt(m[0][c] * m[0][c] + m[1][c] * m[1][c] + m[2][c] * m[2][c]);
        img->spacing[c] = len * unit;
        for (int r = 0; r < 3; r++) img->dir[r * 3 + c] = len > 0 ? m[r][c] / len : 0;
        img->origin[c] = m[c][3] * unit;
    }
done:
    nifti_image_free(nim);
    if (st != THX_OK) thx_image_free(img);
    return st;
}

/* gzip `src` into `dst` with THX_IMAGE_MARKER as the gzip header's comment (so the claim rule finds it
 * in the first bytes of a .nii.gz thorax wrote). */
static thx_status gzip_file(thx_ctx *ctx, const char *src, const char *dst, const char *what)
{
    FILE *in = fopen(src, "rb"), *out = fopen(dst, "wb");
    thx_status st = THX_OK;
    z_stream z;
    memset(&z, 0, sizeof z);
    int zinit = 0;
    unsigned char ibuf[1 << 16], obuf[1 << 16];
    if (!in || !out) {
        st = thx_error(ctx, THX_EIO, "%s: cannot write the compressed image", what);
        goto done;
    }
    if (deflateInit2(&z, 6, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY) != Z_OK) {
        st = thx_error(ctx, THX_ENOMEM, "%s: zlib cannot start", what);
        goto done;
    }
    zinit = 1;
    gz_header h;
    memset(&h, 0, sizeof h);
    h.comment = (Bytef *)THX_IMAGE_MARKER;
    h.os = 3;
    deflateSetHeader(&z, &h);
    int flush;
    do {
        size_t got = fread(ibuf, 1, sizeof ibuf, in);
        if (ferror(in)) {
            st = thx_error(ctx, THX_EIO, "%s: cannot read back the image written", what);
            goto done;
        }
        flush = feof(in) ? Z_FINISH : Z_NO_FLUSH;
        z.next_in = ibuf;
        z.avail_in = (uInt)got;
        do {
            z.next_out = obuf;
            z.avail_out = sizeof obuf;
            deflate(&z, flush);
            size_t have = sizeof obuf - z.avail_out;
            if (fwrite(obuf, 1, have, out) != have) {
                st = thx_error(ctx, THX_EIO, "%s: write failed (disk full?)", what);
                goto done;
            }
        } while (z.avail_out == 0);
    } while (flush != Z_FINISH);
done:
    if (zinit) deflateEnd(&z);
    if (in) fclose(in);
    if (out && fclose(out) != 0 && st == THX_OK) st = thx_error(ctx, THX_EIO, "%s: write failed (disk full?)", what);
    return st;
}

thx_status thx_image_write_nifti(thx_ctx *ctx, const thx_image *img, thx_voxel_type type, thx_atomic_file *af)
{
    static const int dt_of[] = {DT_UINT8, DT_INT16, DT_UINT16, DT_INT32, DT_FLOAT32};
    nifti_set_debug_level(0);
    int gz = thx_image_has_suffix(af->path, ".gz");
    /* NIfTI-1 keeps the geometry in float32: a spacing or coordinate beyond its range (or a spacing
       that would round to 0) cannot be written */
    for (int c = 0; c < 3; c++)
        if (img->spacing[c] > FLT_MAX || img->spacing[c] < FLT_MIN || fabs(img->origin[c]) > FLT_MAX)
            return thx_error(ctx, THX_EINPUT,
                             "%s: spacing %g or origin %g (axis %d) is beyond the float32 range of a NIfTI-1 header",
                             af->path, img->spacing[c], img->origin[c], c + 1);
    char tmp[1200] = "", tmpgz[1200] = "";
    thx_status st = THX_OK;
    int64_t dims[8] = {3, (int64_t)img->n[0], (int64_t)img->n[1], (int64_t)img->n[2], 1, 1, 1, 1};
    nifti_image *nim = nifti_make_new_nim(dims, dt_of[type], 0);
    if (!nim) return thx_error(ctx, THX_ENOMEM, "%s: cannot make the NIfTI header", af->path);
    size_t count = thx_image_count(img);
    nim->data = malloc(count * (size_t)nim->nbyper);
    if (!nim->data) {
        st = thx_error(ctx, THX_ENOMEM, "%s: out of memory", af->path);
        goto done;
    }
    for (size_t q = 0; q < count; q++) {
        float v = img->v[q];
        switch (type) {
        case THX_VOXEL_UINT8: ((uint8_t *)nim->data)[q] = (uint8_t)v; break;
        case THX_VOXEL_INT16: ((int16_t *)nim->data)[q] = (int16_t)v; break;
        case THX_VOXEL_UINT16: ((uint16_t *)nim->data)[q] = (uint16_t)v; break;
        case THX_VOXEL_INT32: ((int32_t *)nim->data)[q] = (int32_t)v; break;
        case THX_VOXEL_FLOAT32: ((float *)nim->data)[q] = v; break;
        }
    }
    nim->nifti_type = NIFTI_FTYPE_NIFTI1_1;
    nim->xyz_units = NIFTI_UNITS_MM;
    nim->scl_slope = 1;
    nim->scl_inter = 0;
    nim->dx = nim->pixdim[1] = img->spacing[0];
    nim->dy = nim->pixdim[2] = img->spacing[1];
    nim->dz = nim->pixdim[3] = img->spacing[2];
    nifti_dmat44 m;
    memset(&m, 0, sizeof m);
    for (int r = 0; r < 3; r++) {
        for (int c = 0; c < 3; c++) m.m[r][c] = img->dir[r * 3 + c] * img->spacing[c];
        m.m[r][3] = img->origin[r];
    }
    m.m[3][3] = 1;
    nim->sform_code = nim->qform_code = NIFTI_XFORM_SCANNER_ANAT;
    nim->sto_xyz = m;
    nim->sto_ijk = nifti_dmat44_inverse(m);
    double dx, dy, dz;
    nifti_dmat44_to_quatern(m, &nim->quatern_b, &nim->quatern_c, &nim->quatern_d, &nim->qoffset_x, &nim->qoffset_y,
                            &nim->qoffset_z, &dx, &dy, &dz, &nim->qfac);
    nim->qto_xyz = nifti_quatern_to_dmat44(nim->quatern_b, nim->quatern_c, nim->quatern_d, nim->qoffset_x,
                                           nim->qoffset_y, nim->qoffset_z, nim->dx, nim->dy, nim->dz, nim->qfac);
    nim->qto_ijk = nifti_dmat44_inverse(nim->qto_xyz);
    snprintf(nim->descrip, sizeof nim->descrip, "%s", THX_IMAGE_MARKER);
    if ((st = thx_image_temp_beside(ctx, af, ".nii", tmp, sizeof tmp)) != THX_OK) goto done;
    if (nifti_set_filenames(nim, tmp, 0, 1) != 0) {
        st = thx_error(ctx, THX_EIO, "%s: cannot name the NIfTI output", af->path);
        goto done;
    }
    nifti_image_write(nim);
    /* nifti_image_write reports nothing: the file on disk must be the whole header and data */
    struct stat sb;
    double want = 352.0 + (double)count * nim->nbyper;
    if (stat(tmp, &sb) != 0 || (double)sb.st_size != want) {
        st = thx_error(ctx, THX_EIO, "%s: the NIfTI file was not written whole (disk full?): nothing was written",
                       af->path);
        goto done;
    }
    if (gz) {
        if ((st = thx_image_temp_beside(ctx, af, ".nii.gz", tmpgz, sizeof tmpgz)) != THX_OK) goto done;
        if ((st = gzip_file(ctx, tmp, tmpgz, af->path)) != THX_OK) goto done;
        st = thx_output_place(ctx, af, tmpgz);
        tmpgz[0] = '\0';
    } else {
        st = thx_output_place(ctx, af, tmp);
        tmp[0] = '\0';
    }
done:
    if (tmp[0]) unlink(tmp);
    if (tmpgz[0]) unlink(tmpgz);
    nifti_image_free(nim);
    return st;
}
