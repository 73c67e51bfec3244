/* MetaImage (ITK's MetaIO): .mha with the data after the header (ElementDataFile = LOCAL), .mhd with
 * the data in the file ElementDataFile names (relative to the header). Read: ObjectType Image, NDims
 * 3 (2: one plane), DimSize, ElementSpacing (else ElementSize), Offset/Position/Origin,
 * TransformMatrix/Rotation/Orientation, ElementType MET_CHAR .. MET_DOUBLE, ElementByteOrderMSB /
 * BinaryDataByteOrderMSB, BinaryData (False: text voxels), ElementNumberOfChannels 1,
 * CompressedData (zlib) with CompressedDataSize, HeaderSize (detached data; -1: at the end).
 *
 * Frame: MetaIO's physical space is ITK's, LPS millimetres, whatever AnatomicalOrientation says (ITK
 * reads the geometry from Offset and TransformMatrix alone; AnatomicalOrientation is a label in ITK's
 * "from" letters, RAI for the identity); TransformMatrix lists the direction of index axis 0, then
 * axis 1, then axis 2 (ITK's direction matrix is its transpose). RAS = LPS with x and y negated.
 * Written: .mha, zlib-compressed, `Comment = thorax-image` first (MetaIO's own Comment field). */
#include "image/image_impl.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

static const struct {
    const char *name;
    thx_raw_type t;
} met_types[] = {
    {"MET_CHAR", THX_RAW_INT8},     {"MET_UCHAR", THX_RAW_UINT8},       {"MET_SHORT", THX_RAW_INT16},
    {"MET_USHORT", THX_RAW_UINT16}, {"MET_INT", THX_RAW_INT32},         {"MET_UINT", THX_RAW_UINT32},
    {"MET_LONG", THX_RAW_INT32},    {"MET_ULONG", THX_RAW_UINT32},      {"MET_LONG_LONG", THX_RAW_INT64},
    {"MET_ULONG_LONG", THX_RAW_UINT64}, {"MET_FLOAT", THX_RAW_FLOAT32}, {"MET_DOUBLE", THX_RAW_FLOAT64},
};

typedef struct {
    const char *path;
    int ndims;
    double dimsize[3];
    int have_dimsize, have_spacing, have_size, have_origin, have_matrix, have_type;
    double spacing[3], size[3], origin[3], matrix[9];
    thx_raw_type type;
    int msb, binary, compressed;
    double compressed_size; /* -1: not given */
    double header_size;     /* 0: none, -1: data at the end */
    char data_file[1024];
    char orientation[8];
} meta_header;

static int is_word(const char *s, const char *w) { return strcasecmp(s, w) == 0; }

static int read_numbers(const char *s, double *v, int want)
{
    for (int k = 0; k < want; k++) {
        char *end;
        v[k] = strtod(s, &end);
        if (end == s || !isfinite(v[k])) return -1;
        s = end;
    }
    while (*s == ' ' || *s == '\t') s++;
    return *s ? -1 : 0;
}

static int read_bool(const char *s, int *b)
{
    if (is_word(s, "True") || is_word(s, "1")) *b = 1;
    else if (is_word(s, "False") || is_word(s, "0")) *b = 0;
    else return -1;
    return 0;
}

/* One "Key = Value" line (line ln). */
static thx_status field(thx_ctx *ctx, meta_header *h, int ln, const char *key, const char *value)
{
    const char *path = h->path;
    if (is_word(key, "ObjectType")) {
        if (!is_word(value, "Image"))
            return thx_error(ctx, THX_EINPUT, "%s:%d: ObjectType %s: thorax reads MetaImage images (ObjectType = Image)",
                             path, ln, value);
        return THX_OK;
    }
    if (is_word(key, "NDims")) {
        if (!strcmp(value, "2")) h->ndims = 2;
        else if (!strcmp(value, "3")) h->ndims = 3;
        else
            return thx_error(ctx, THX_EINPUT,
                             "%s:%d: NDims %s: thorax reads 3-D volumes (and 2-D images as one plane)", path, ln, value);
        return THX_OK;
    }
    const int vec = is_word(key, "DimSize") || is_word(key, "ElementSpacing") || is_word(key, "ElementSize") ||
                    is_word(key, "Offset") || is_word(key, "Position") || is_word(key, "Origin") ||
                    is_word(key, "TransformMatrix") || is_word(key, "Rotation") || is_word(key, "Orientation");
    if (vec && !h->ndims) return thx_error(ctx, THX_EINPUT, "%s:%d: %s before NDims", path, ln, key);
    int nd = h->ndims;
    if (is_word(key, "DimSize")) {
        if (read_numbers(value, h->dimsize, nd) != 0)
            return thx_error(ctx, THX_EINPUT, "%s:%d: DimSize \"%s\" is not %d whole numbers", path, ln, value, nd);
        for (int c = 0; c < nd; c++)
            if (!(h->dimsize[c] >= 1) || h->dimsize[c] != floor(h->dimsize[c]) || h->dimsize[c] > 1e12)
                return thx_error(ctx, THX_EINPUT, "%s:%d: DimSize %d is %g (must be a whole number >= 1)", path, ln,
                                 c + 1, h->dimsize[c]);
        h->have_dimsize = 1;
        return THX_OK;
    }
    if (is_word(key, "ElementSpacing") || is_word(key, "ElementSize")) {
        int spacing = is_word(key, "ElementSpacing");
        if (read_numbers(value, spacing ? h->spacing : h->size, nd) != 0)
            return thx_error(ctx, THX_EINPUT, "%s:%d: %s \"%s\" is not %d numbers", path, ln, key, value, nd);
        if (spacing) h->have_spacing = 1;
        else h->have_size = 1;
        return THX_OK;
    }
    if (is_word(key, "Offset") || is_word(key, "Position") || is_word(key, "Origin")) {
        if (read_numbers(value, h->origin, nd) != 0)
            return thx_error(ctx, THX_EINPUT, "%s:%d: %s \"%s\" is not %d numbers", path, ln, key, value, nd);
        h->have_origin = 1;
        return THX_OK;
    }
    if (is_word(key, "TransformMatrix") || is_word(key, "Rotation") || is_word(key, "Orientation")) {
        if (read_numbers(value, h->matrix, nd * nd) != 0)
            return thx_error(ctx, THX_EINPUT, "%s:%d: %s \"%s\" is not %d numbers", path, ln, key, value, nd * nd);
        h->have_matrix = 1;
        return THX_OK;
    }
    if (is_word(key, "ElementType")) {
        for (size_t k = 0; k < sizeof met_types / sizeof met_types[0]; k++)
            if (is_word(value, met_types[k].name)) {
                h->type = met_types[k].t;
                h->have_type = 1;
                return THX_OK;
            }
        return thx_error(ctx, THX_EINPUT, "%s:%d: ElementType %s is not a scalar type thorax reads", path, ln, value);
    }
    if (is_word(key, "ElementByteOrderMSB") || is_word(key, "BinaryDataByteOrderMSB") || is_word(key, "BinaryData") ||
        is_word(key, "CompressedData")) {
        int b;
        if (read_bool(value, &b) != 0)
            return thx_error(ctx, THX_EINPUT, "%s:%d: %s \"%s\" is neither True nor False", path, ln, key, value);
        if (is_word(key, "BinaryData")) h->binary = b;
        else if (is_word(key, "CompressedData")) h->compressed = b;
        else h->msb = b;
        return THX_OK;
    }
    if (is_word(key, "ElementNumberOfChannels")) {
        if (strcmp(value, "1") != 0)
            return thx_error(ctx, THX_EINPUT,
                             "%s:%d: ElementNumberOfChannels %s: thorax reads scalar volumes (one channel)", path, ln,
                             value);
        return THX_OK;
    }
    if (is_word(key, "CompressedDataSize") || is_word(key, "HeaderSize")) {
        double v;
        if (read_numbers(value, &v, 1) != 0 || v != floor(v) || v < -1)
            return thx_error(ctx, THX_EINPUT, "%s:%d: %s \"%s\" is not a byte count", path, ln, key, value);
        if (is_word(key, "HeaderSize")) h->header_size = v;
        else h->compressed_size = v;
        return THX_OK;
    }
    if (is_word(key, "AnatomicalOrientation")) {
        snprintf(h->orientation, sizeof h->orientation, "%.7s", value);
        return THX_OK;
    }
    if (is_word(key, "ElementDataFile")) {
        if (!strncmp(value, "LIST", 4) || strchr(value, '%') || strchr(value, ' '))
            return thx_error(ctx, THX_EINPUT,
                             "%s:%d: ElementDataFile \"%s\": a list or numbered set of data files is not supported (one "
                             "data file, or LOCAL)",
                             path, ln, value);
        if (!value[0]) return thx_error(ctx, THX_EINPUT, "%s:%d: ElementDataFile is empty", path, ln);
        snprintf(h->data_file, sizeof h->data_file, "%s", value);
        return THX_OK;
    }
    /* Comment, Name, ID, CenterOfRotation, ElementMin/Max, Modality, ...: nothing the voxels or their
       geometry depend on */
    return THX_OK;
}

thx_status thx_image_read_metaimage(thx_ctx *ctx, const char *path, thx_image *img)
{
    char *buf = NULL, *data_buf = NULL;
    size_t len = 0;
    THX_CHECK(thx_read_file(ctx, path, &buf, &len));
    thx_status st = THX_OK;
    meta_header h;
    memset(&h, 0, sizeof h);
    h.path = path;
    h.binary = 1;
    h.compressed_size = -1;
    size_t pos = 0;
    int ln = 0;
    while (pos < len && !h.data_file[0]) {
        size_t eol = pos;
        while (eol < len && buf[eol] != '\n') eol++;
        ln++;
        char line[4096];
        size_t n = eol - pos;
        if (n >= sizeof line) {
            st = thx_error(ctx, THX_EINPUT, "%s:%d: header line longer than %zu bytes (not a MetaImage header?)", path,
                           ln, sizeof line - 1);
            goto done;
        }
        memcpy(line, buf + pos, n);
        line[n] = '\0';
        if (n && line[n - 1] == '\r') line[--n] = '\0';
        pos = eol < len ? eol + 1 : len;
        if (memchr(line, '\0', n)) {
            st = thx_error(ctx, THX_EINPUT, "%s:%d: a NUL byte in the header", path, ln);
            goto done;
        }
        char *s = line;
        while (*s == ' ' || *s == '\t') s++;
        if (!*s) continue;
        char *eq = strchr(s, '=');
        if (!eq) {
            st = thx_error(ctx, THX_EINPUT, "%s:%d: \"%.60s\" is not \"Key = Value\"", path, ln, s);
            goto done;
        }
        char *ke = eq;
        while (ke > s && (ke[-1] == ' ' || ke[-1] == '\t')) ke--;
        *ke = '\0';
        char *value = eq + 1;
        while (*value == ' ' || *value == '\t') value++;
        size_t vn = strlen(value);
        while (vn && (value[vn - 1] == ' ' || value[vn - 1] == '\t')) value[--vn] = '\0';
        if ((st = field(ctx, &h, ln, s, value)) != THX_OK) goto done;
    }
    if (!h.data_file[0]) {
        st = thx_error(ctx, THX_EINPUT, "%s: no ElementDataFile line (the header's last line, before the data)", path);
        goto done;
    }
    if (!h.ndims || !h.have_dimsize || !h.have_type) {
        st = thx_error(ctx, THX_EINPUT, "%s: the header lacks %s (NDims, DimSize and ElementType are required)", path,
                       !h.ndims ? "NDims" : !h.have_dimsize ? "DimSize" : "ElementType");
        goto done;
    }
    size_t n[3] = {(size_t)h.dimsize[0], (size_t)h.dimsize[1], h.ndims == 3 ? (size_t)h.dimsize[2] : 1};
    for (int c = 0; c < 3; c++)
        if (!n[c]) {
            st = thx_error(ctx, THX_EINPUT, "%s: DimSize gives fewer than NDims = %d sizes (NDims after DimSize?)", path,
                           h.ndims);
            goto done;
        }
    size_t vsize = thx_raw_size(h.type), need = vsize;
    for (int c = 0; c < 3; c++) {
        if (need > SIZE_MAX / n[c]) {
            st = thx_error(ctx, THX_EINPUT, "%s: %zu x %zu x %zu voxels do not fit in memory", path, n[0], n[1], n[2]);
            goto done;
        }
        need *= n[c];
    }
    const char *data = buf + pos, *what = path;
    size_t avail = len - pos;
    char data_path[2100];
    if (!is_word(h.data_file, "LOCAL")) {
        thx_image_beside(path, h.data_file, data_path, sizeof data_path);
        size_t dl = 0;
        if ((st = thx_read_file(ctx, data_path, &data_buf, &dl)) != THX_OK) goto done;
        data = data_buf;
        avail = dl;
        what = data_path;
        if (h.header_size > 0) {
            if (h.header_size > (double)avail) goto short_data;
            data += (size_t)h.header_size;
            avail -= (size_t)h.header_size;
        }
    } else if (h.header_size > 0) {
        st = thx_error(ctx, THX_EINPUT, "%s: HeaderSize with LOCAL data is not supported", path);
        goto done;
    }
    if (h.header_size == -1) {
        if (h.compressed || !h.binary) {
            st = thx_error(ctx, THX_EINPUT, "%s: HeaderSize = -1 goes only with uncompressed binary data", path);
            goto done;
        }
        if (avail < need) goto short_data;
        data += avail - need;
        avail = need;
    }
    if (h.compressed) {
        if (h.compressed_size >= 0) {
            if (h.compressed_size > (double)avail) {
                st = thx_error(ctx, THX_EINPUT,
                               "%s: CompressedDataSize is %.0f bytes but the file holds %zu after the header: truncated",
                               what, h.compressed_size, avail);
                goto done;
            }
            if (h.compressed_size < (double)avail) {
                st = thx_error(ctx, THX_EINPUT, "%s: %zu bytes follow the CompressedDataSize = %.0f bytes of data", what,
                               avail - (size_t)h.compressed_size, h.compressed_size);
                goto done;
            }
        }
        if ((double)need > thx_image_inflate_bound(avail)) goto short_data;
    } else if (!h.binary) {
        if (need / vsize > avail / 2 + 1) goto short_data;
    } else if (avail != need) {
        if (avail < need) goto short_data;
        st = thx_error(ctx, THX_EINPUT,
                       "%s: the data hold %zu bytes more than the header's %zu x %zu x %zu %s voxels (%zu bytes): wrong "
                       "DimSize or ElementType?",
                       what, avail - need, n[0], n[1], n[2], thx_raw_name(h.type), need);
        goto done;
    }
    if ((st = thx_image_alloc(ctx, n, img)) != THX_OK) goto done;
    if (h.compressed) {
        unsigned char *raw = malloc(need ? need : 1);
        if (!raw) {
            st = thx_error(ctx, THX_ENOMEM, "%s: out of memory for %zu bytes of voxels", path, need);
            goto done;
        }
        st = thx_image_inflate(ctx, (const unsigned char *)data, avail, raw, need, what);
        if (st == THX_OK) thx_image_decode(img, raw, h.type, h.msb);
        free(raw);
        if (st != THX_OK) goto done;
    } else if (!h.binary) {
        if ((st = thx_image_decode_ascii(ctx, img, data, avail, h.type, what)) != THX_OK) goto done;
    } else {
        thx_image_decode(img, (const unsigned char *)data, h.type, h.msb);
    }
    snprintf(img->format, sizeof img->format, "metaimage");
    snprintf(img->source_frame, sizeof img->source_frame, "LPS%s%s%s", h.orientation[0] ? " (labelled " : "",
             h.orientation, h.orientation[0] ? ")" : "");
    /* geometry in LPS: D[r][c] = matrix[c * nd + r] (row c of the file's matrix is axis c) */
    double D[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, o[3] = {0, 0, 0}, sp[3] = {1, 1, 1};
    int nd = h.ndims;
    for (int c = 0; c < nd; c++) {
        if (h.have_matrix)
            for (int r = 0; r < nd; r++) D[r][c] = h.matrix[c * nd + r];
        if (h.have_origin) o[c] = h.origin[c];
        sp[c] = h.have_spacing ? h.spacing[c] : h.have_size ? h.size[c] : 1.0;
    }
    for (int c = 0; c < 3; c++) {
        /* a column of the matrix need not be unit length in the file: its length is not spacing in
           ITK (it normalizes nothing; a scaled matrix is refused by validation) */
        img->spacing[c] = sp[c];
        img->dir[0 * 3 + c] = -D[0][c] + 0.0; /* + 0.0: no -0 */
        img->dir[1 * 3 + c] = -D[1][c] + 0.0;
        img->dir[2 * 3 + c] = D[2][c];
    }
    img->origin[0] = -o[0] + 0.0;
    img->origin[1] = -o[1] + 0.0;
    img->origin[2] = o[2];
    goto done;
short_data:
    st = thx_error(ctx, THX_EINPUT,
                   "%s: the header claims %zu x %zu x %zu %s voxels (%zu bytes) but the %sdata hold %zu bytes: truncated",
                   what, n[0], n[1], n[2], thx_raw_name(h.type), need,
                   h.compressed ? "compressed " : !h.binary ? "text " : "", avail);
done:
    free(buf);
    free(data_buf);
    if (st != THX_OK) thx_image_free(img);
    return st;
}

/* ITK's AnatomicalOrientation letters for an LPS direction column: where the axis comes FROM. */
static char from_letter(const double v[3])
{
    int k = 0;
    for (int r = 1; r < 3; r++)
        if (fabs(v[r]) > fabs(v[k])) k = r;
    static const char pos[] = "RAI", neg[] = "LPS"; /* +L comes from R, +P from A, +S from I */
    return v[k] >= 0 ? pos[k] : neg[k];
}

thx_status thx_image_write_metaimage(thx_ctx *ctx, const thx_image *img, thx_voxel_type type, thx_atomic_file *af)
{
    static const char *const met_name[] = {"MET_UCHAR", "MET_SHORT", "MET_USHORT", "MET_INT", "MET_FLOAT"};
    if (thx_image_has_suffix(af->path, ".mhd"))
        return thx_error(ctx, THX_EINPUT,
                         "%s: thorax writes MetaImage as one file (.mha): a detached header and its data file cannot be "
                         "replaced together atomically",
                         af->path);
    unsigned char *raw = NULL, *z = NULL;
    size_t nraw = 0, nz = 0;
    THX_CHECK(thx_image_encode(ctx, img, type, &raw, &nraw));
    thx_status st = thx_image_deflate(ctx, raw, nraw, 0, &z, &nz, af->path);
    free(raw);
    if (st != THX_OK) return st;
    /* LPS: x and y negated; the file's matrix row c is index axis c */
    double L[3][3];
    for (int c = 0; c < 3; c++) {
        L[c][0] = -img->dir[0 * 3 + c] + 0.0; /* + 0.0: no "-0" in the file */
        L[c][1] = -img->dir[1 * 3 + c] + 0.0;
        L[c][2] = img->dir[2 * 3 + c] + 0.0;
    }
    char head[4096];
    int m = snprintf(head, sizeof head,
                     "Comment = %s\nObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = False\n"
                     "CompressedData = True\nCompressedDataSize = %zu\nTransformMatrix =",
                     THX_IMAGE_MARKER, nz);
    for (int c = 0; c < 3; c++)
        for (int r = 0; r < 3; r++) m += snprintf(head + m, sizeof head - (size_t)m, " %.17g", L[c][r]);
    m += snprintf(head + m, sizeof head - (size_t)m,
                  "\nOffset = %.17g %.17g %.17g\nCenterOfRotation = 0 0 0\nAnatomicalOrientation = %c%c%c\n"
                  "ElementSpacing = %.17g %.17g %.17g\nDimSize = %zu %zu %zu\nElementType = %s\nElementDataFile = LOCAL\n",
                  -img->origin[0] + 0.0, -img->origin[1] + 0.0, img->origin[2] + 0.0, from_letter(L[0]), from_letter(L[1]),
                  from_letter(L[2]), img->spacing[0], img->spacing[1], img->spacing[2], img->n[0], img->n[1], img->n[2],
                  met_name[type]);
    st = thx_image_place_bytes(ctx, af, head, (size_t)m, z, nz);
    free(z);
    return st;
}
