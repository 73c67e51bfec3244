/* NRRD (teem's "nearly raw raster data", header versions NRRD0001..NRRD0005): .nrrd with the data
 * after the header's blank line, .nhdr with the data in the file its `data file:` field names
 * (relative to the header). Read: every scalar type and its aliases, encodings raw, gzip and ascii,
 * `endian`, dimension 3 (2: one plane), `sizes`, `space` (RAS, LAS, LPS and scanner-xyz, taken as
 * LPS as ITK does), `space directions` / `space origin` / `space units`, else `spacings`, `kinds`
 * (a non-spatial axis refused), `line skip`, `byte skip`; comments and key:=value lines skipped.
 * Written: NRRD0004, one file (.nrrd), gzip, space right-anterior-superior, the marker as the first
 * comment. docs/formats.md ("Images") says what is read; docs/design/image.md why. */
#include "image/image_impl.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

/* The header fields as read; n_dim 0 until `dimension` is seen. */
typedef struct {
    const char *path;
    int version;
    int n_dim;
    size_t sizes[3];
    int have_sizes, have_type, type;
    int encoding;        /* 0 raw, 1 gzip, 2 ascii */
    int endian;          /* -1 not given, 0 little, 1 big */
    int space;           /* -1 none, 0 RAS, 1 LAS, 2 LPS, 3 scanner-xyz */
    int space_dim;
    int have_dirs;
    double dirs[3][3];
    int have_origin;
    double origin[3];
    int have_spacings;
    double spacings[3];
    double unit;         /* mm per space unit */
    char data_file[1024];
    long line_skip;
    long byte_skip;
} nrrd_header;

static const struct {
    const char *name;
    thx_raw_type t;
} nrrd_types[] = {
    {"signed char", THX_RAW_INT8}, {"int8", THX_RAW_INT8}, {"int8_t", THX_RAW_INT8},
    {"uchar", THX_RAW_UINT8}, {"unsigned char", THX_RAW_UINT8}, {"uint8", THX_RAW_UINT8}, {"uint8_t", THX_RAW_UINT8},
    {"short", THX_RAW_INT16}, {"short int", THX_RAW_INT16}, {"signed short", THX_RAW_INT16},
    {"signed short int", THX_RAW_INT16}, {"int16", THX_RAW_INT16}, {"int16_t", THX_RAW_INT16},
    {"ushort", THX_RAW_UINT16}, {"unsigned short", THX_RAW_UINT16}, {"unsigned short int", THX_RAW_UINT16},
    {"uint16", THX_RAW_UINT16}, {"uint16_t", THX_RAW_UINT16},
    {"int", THX_RAW_INT32}, {"signed int", THX_RAW_INT32}, {"int32", THX_RAW_INT32}, {"int32_t", THX_RAW_INT32},
    {"uint", THX_RAW_UINT32}, {"unsigned int", THX_RAW_UINT32}, {"uint32", THX_RAW_UINT32},
    {"uint32_t", THX_RAW_UINT32},
    {"longlong", THX_RAW_INT64}, {"long long", THX_RAW_INT64}, {"long long int", THX_RAW_INT64},
    {"signed long long", THX_RAW_INT64}, {"signed long long int", THX_RAW_INT64}, {"int64", THX_RAW_INT64},
    {"int64_t", THX_RAW_INT64},
    {"ulonglong", THX_RAW_UINT64}, {"unsigned long long", THX_RAW_UINT64}, {"unsigned long long int", THX_RAW_UINT64},
    {"uint64", THX_RAW_UINT64}, {"uint64_t", THX_RAW_UINT64},
    {"float", THX_RAW_FLOAT32}, {"double", THX_RAW_FLOAT64},
};

/* Trims blanks at both ends in place. */
static char *trim(char *s)
{
    while (*s == ' ' || *s == '\t') s++;
    size_t n = strlen(s);
    while (n && (s[n - 1] == ' ' || s[n - 1] == '\t' || s[n - 1] == '\r')) s[--n] = '\0';
    return s;
}

/* Reads `want` numbers separated by blanks from s; 0 on success. A number may be "nan" (spacings
 * unknown): strtod reads it and the caller decides. */
static int read_numbers(const char *s, double *v, int want)
{
    for (int k = 0; k < want; k++) {
        char *end;
        v[k] = strtod(s, &end);
        if (end == s) return -1;
        s = end;
    }
    while (*s == ' ' || *s == '\t') s++;
    return *s ? -1 : 0;
}

/* A vector "(x,y,z)" of `dim` components at *s, advancing *s; "none" gives none = 1. 0 on success. */
static int read_vector(const char **s, int dim, double *v, int *none)
{
    const char *p = *s;
    while (*p == ' ' || *p == '\t') p++;
    *none = 0;
    if (!strncmp(p, "none", 4)) {
        *none = 1;
        *s = p + 4;
        return 0;
    }
    if (*p != '(') return -1;
    p++;
    for (int k = 0; k < dim; k++) {
        char *end;
        v[k] = strtod(p, &end);
        if (end == p) return -1;
        p = end;
        while (*p == ' ' || *p == '\t') p++;
        if (*p != (k + 1 < dim ? ',' : ')')) return -1;
        p++;
    }
    *s = p;
    return 0;
}

static int is_word(const char *s, const char *w) { return strcasecmp(s, w) == 0; }

/* One "field: value" line (line number ln). */
static thx_status field(thx_ctx *ctx, nrrd_header *h, int ln, char *name, char *value)
{
    const char *path = h->path;
    if (is_word(name, "dimension")) {
        char *end;
        long d = strtol(value, &end, 10);
        if (*end || end == value) return thx_error(ctx, THX_EINPUT, "%s:%d: dimension \"%s\" is not a number", path, ln, value);
        if (d < 2 || d > 3)
            return thx_error(ctx, THX_EINPUT,
                             "%s:%d: dimension %ld: thorax reads 3-D scalar volumes (and 2-D images as one plane); a "
                             "4-D, vector or time-series image is not supported",
                             path, ln, d);
        h->n_dim = (int)d;
        return THX_OK;
    }
    if (is_word(name, "type")) {
        for (size_t k = 0; k < sizeof nrrd_types / sizeof nrrd_types[0]; k++)
            if (is_word(value, nrrd_types[k].name)) {
                h->type = (int)nrrd_types[k].t;
                h->have_type = 1;
                return THX_OK;
            }
        return thx_error(ctx, THX_EINPUT, "%s:%d: type \"%s\" is not a scalar type thorax reads", path, ln, value);
    }
    if (is_word(name, "encoding")) {
        if (is_word(value, "raw")) h->encoding = 0;
        else if (is_word(value, "gzip") || is_word(value, "gz")) h->encoding = 1;
        else if (is_word(value, "ascii") || is_word(value, "text") || is_word(value, "txt")) h->encoding = 2;
        else
            return thx_error(ctx, THX_EINPUT,
                             "%s:%d: encoding \"%s\" is not supported (thorax reads raw, gzip and ascii NRRD data)",
                             path, ln, value);
        return THX_OK;
    }
    if (is_word(name, "endian")) {
        if (is_word(value, "little")) h->endian = 0;
        else if (is_word(value, "big")) h->endian = 1;
        else return thx_error(ctx, THX_EINPUT, "%s:%d: endian \"%s\" is neither little nor big", path, ln, value);
        return THX_OK;
    }
    if (!h->n_dim && (is_word(name, "sizes") || is_word(name, "spacings") || is_word(name, "kinds") ||
                      is_word(name, "space directions")))
        return thx_error(ctx, THX_EINPUT, "%s:%d: \"%s\" before \"dimension\"", path, ln, name);
    if (is_word(name, "sizes")) {
        double v[3];
        if (read_numbers(value, v, h->n_dim) != 0)
            return thx_error(ctx, THX_EINPUT, "%s:%d: sizes \"%s\" are not %d whole numbers", path, ln, value, h->n_dim);
        for (int c = 0; c < h->n_dim; c++) {
            if (!(v[c] >= 1) || v[c] != floor(v[c]) || v[c] > 1e12)
                return thx_error(ctx, THX_EINPUT, "%s:%d: size %d is %g (must be a whole number >= 1)", path, ln, c + 1,
                                 v[c]);
            h->sizes[c] = (size_t)v[c];
        }
        h->have_sizes = 1;
        return THX_OK;
    }
    if (is_word(name, "space")) {
        if (is_word(value, "right-anterior-superior") || is_word(value, "RAS")) h->space = 0;
        else if (is_word(value, "left-anterior-superior") || is_word(value, "LAS")) h->space = 1;
        else if (is_word(value, "left-posterior-superior") || is_word(value, "LPS")) h->space = 2;
        else if (is_word(value, "scanner-xyz")) h->space = 3;
        else
            return thx_error(ctx, THX_EINPUT,
                             "%s:%d: space \"%s\" is not an anatomical 3-D space thorax reads (right-anterior-superior, "
                             "left-anterior-superior, left-posterior-superior, scanner-xyz)",
                             path, ln, value);
        h->space_dim = 3;
        return THX_OK;
    }
    if (is_word(name, "space dimension")) {
        if (strcmp(value, "3") != 0)
            return thx_error(ctx, THX_EINPUT, "%s:%d: space dimension %s: thorax reads 3-D spaces", path, ln, value);
        return thx_error(ctx, THX_EINPUT,
                         "%s:%d: a space dimension without a named space has no anatomical axes: thorax needs \"space: "
                         "right-anterior-superior\" (or LPS, LAS, scanner-xyz)",
                         path, ln);
    }
    if (is_word(name, "space directions")) {
        if (h->space < 0)
            return thx_error(ctx, THX_EINPUT, "%s:%d: space directions before \"space\"", path, ln);
        const char *p = value;
        for (int c = 0; c < h->n_dim; c++) {
            int none;
            if (read_vector(&p, 3, h->dirs[c], &none) != 0)
                return thx_error(ctx, THX_EINPUT, "%s:%d: space direction %d is not \"(x,y,z)\" or \"none\"", path, ln,
                                 c + 1);
            if (none)
                return thx_error(ctx, THX_EINPUT,
                                 "%s:%d: axis %d has no space direction (\"none\"): a non-spatial axis (vector, list, "
                                 "time); thorax reads scalar volumes",
                                 path, ln, c + 1);
        }
        while (*p == ' ' || *p == '\t') p++;
        if (*p) return thx_error(ctx, THX_EINPUT, "%s:%d: more space directions than dimension %d", path, ln, h->n_dim);
        h->have_dirs = 1;
        return THX_OK;
    }
    if (is_word(name, "space origin")) {
        const char *p = value;
        int none;
        if (read_vector(&p, 3, h->origin, &none) != 0 || none)
            return thx_error(ctx, THX_EINPUT, "%s:%d: space origin \"%s\" is not \"(x,y,z)\"", path, ln, value);
        while (*p == ' ' || *p == '\t') p++;
        if (*p) return thx_error(ctx, THX_EINPUT, "%s:%d: space origin \"%s\" is not \"(x,y,z)\"", path, ln, value);
        h->have_origin = 1;
        return THX_OK;
    }
    if (is_word(name, "space units")) {
        /* three quoted words, all the same length unit */
        double unit = 0;
        const char *p = value;
        for (int c = 0; c < 3; c++) {
            while (*p == ' ' || *p == '\t') p++;
            if (*p != '"') return thx_error(ctx, THX_EINPUT, "%s:%d: space units \"%s\" are not 3 quoted words", path, ln, value);
            const char *q = strchr(p + 1, '"');
            if (!q) return thx_error(ctx, THX_EINPUT, "%s:%d: space units \"%s\" are not 3 quoted words", path, ln, value);
            char w[32];
            snprintf(w, sizeof w, "%.*s", (int)(q - p - 1 < 31 ? q - p - 1 : 31), p + 1);
            double u = is_word(w, "mm") || !w[0] ? 1 : is_word(w, "cm") ? 10 : is_word(w, "m") ? 1000
                     : is_word(w, "um") || is_word(w, "micron") ? 0.001 : 0;
            if (u == 0) return thx_error(ctx, THX_EINPUT, "%s:%d: space unit \"%s\" is not a length (mm, cm, m, um)", path, ln, w);
            if (c && u != unit) return thx_error(ctx, THX_EINPUT, "%s:%d: the space units differ between axes", path, ln);
            unit = u;
            p = q + 1;
        }
        h->unit = unit;
        return THX_OK;
    }
    if (is_word(name, "spacings")) {
        if (read_numbers(value, h->spacings, h->n_dim) != 0)
            return thx_error(ctx, THX_EINPUT, "%s:%d: spacings \"%s\" are not %d numbers", path, ln, value, h->n_dim);
        h->have_spacings = 1;
        return THX_OK;
    }
    if (is_word(name, "kinds")) {
        char *save = NULL, *w = strtok_r(value, " \t", &save);
        for (int c = 0; w; c++, w = strtok_r(NULL, " \t", &save)) {
            if (c >= h->n_dim) return thx_error(ctx, THX_EINPUT, "%s:%d: more kinds than dimension %d", path, ln, h->n_dim);
            if (!is_word(w, "domain") && !is_word(w, "space") && !is_word(w, "none") && !is_word(w, "???"))
                return thx_error(ctx, THX_EINPUT,
                                 "%s:%d: axis %d is of kind \"%s\": thorax reads scalar volumes (every axis a spatial "
                                 "domain axis)",
                                 path, ln, c + 1, w);
        }
        return THX_OK;
    }
    if (is_word(name, "data file") || is_word(name, "datafile")) {
        if (!strncmp(value, "LIST", 4) || strchr(value, '%') || strchr(value, ' '))
            return thx_error(ctx, THX_EINPUT,
                             "%s:%d: data file \"%s\": a list or numbered set of data files is not supported (one data "
                             "file only)",
                             path, ln, value);
        snprintf(h->data_file, sizeof h->data_file, "%s", value);
        return THX_OK;
    }
    if (is_word(name, "line skip") || is_word(name, "lineskip") || is_word(name, "byte skip") ||
        is_word(name, "byteskip")) {
        char *end;
        long v = strtol(value, &end, 10);
        int bytes = tolower((unsigned char)name[0]) == 'b';
        if (*end || end == value || v < (bytes ? -1 : 0))
            return thx_error(ctx, THX_EINPUT, "%s:%d: %s \"%s\" is not a count", path, ln, name, value);
        if (bytes) h->byte_skip = v;
        else h->line_skip = v;
        return THX_OK;
    }
    if (is_word(name, "block size") || is_word(name, "blocksize"))
        return thx_error(ctx, THX_EINPUT, "%s:%d: block data are not scalar voxels", path, ln);
    /* content, min, max, centers, labels, units, measurement frame, thicknesses, axis mins ...:
       nothing thorax's geometry or values depend on */
    return THX_OK;
}

/* Whether a voxel count * size fits in size_t. */
static int product(const size_t n[3], size_t size, size_t *bytes)
{
    size_t b = size;
    for (int c = 0; c < 3; c++) {
        if (n[c] && b > SIZE_MAX / n[c]) return -1;
        b *= n[c];
    }
    *bytes = b;
    return 0;
}

thx_status thx_image_read_nrrd(thx_ctx *ctx, const char *path, thx_image *img)
{
    char *buf = NULL, *data_buf = NULL;
    size_t len = 0, data_len = 0;
    THX_CHECK(thx_read_file(ctx, path, &buf, &len));
    thx_status st = THX_OK;
    nrrd_header h;
    memset(&h, 0, sizeof h);
    h.path = path;
    h.endian = -1;
    h.space = -1;
    h.unit = 1;
    if (len < 8 || strncmp(buf, "NRRD000", 7) != 0 || buf[7] < '1' || buf[7] > '5') {
        st = thx_error(ctx, THX_EINPUT, "%s:1: not an NRRD file (it must begin with NRRD0001 .. NRRD0005)", path);
        goto done;
    }
    h.version = buf[7] - '0';
    /* the header: lines up to a blank line (or the end of a detached header) */
    size_t pos = 0, data_off = len;
    int ln = 0;
    while (pos < len) {
        size_t eol = pos;
        while (eol < len && buf[eol] != '\n') eol++;
        ln++;
        char line[4096];
        size_t n = eol - pos;
        if (n >= sizeof line) {
            st = thx_error(ctx, THX_EINPUT, "%s:%d: header line longer than %zu bytes (or no header)", path, ln,
                           sizeof line - 1);
            goto done;
        }
        memcpy(line, buf + pos, n);
        line[n] = '\0';
        if (n && line[n - 1] == '\r') line[--n] = '\0';
        pos = eol < len ? eol + 1 : len;
        if (ln == 1) continue; /* the magic */
        if (n == 0) {
            data_off = pos;
            break;
        }
        if (memchr(line, '\0', n)) {
            st = thx_error(ctx, THX_EINPUT, "%s:%d: a NUL byte in the header (no blank line before the data?)", path, ln);
            goto done;
        }
        if (line[0] == '#') continue;
        char *sep = strstr(line, ": "), *kv = strstr(line, ":=");
        if (kv && (!sep || kv < sep)) continue; /* key:=value */
        if (!sep) {
            /* "field:" with an empty value ends in ':' */
            if (n && line[n - 1] == ':') sep = line + n - 1;
            else {
                st = thx_error(ctx, THX_EINPUT, "%s:%d: \"%.60s\" is not a field (\"name: value\"), a comment or key:=value",
                               path, ln, line);
                goto done;
            }
        }
        *sep = '\0';
        char *name = trim(line), *value = trim(sep[1] ? sep + 2 : sep + 1);
        if ((st = field(ctx, &h, ln, name, value)) != THX_OK) goto done;
    }
    if (!h.n_dim || !h.have_sizes || !h.have_type) {
        st = thx_error(ctx, THX_EINPUT, "%s: the header lacks \"%s\" (dimension, type, sizes and encoding are required)",
                       path, !h.n_dim ? "dimension" : !h.have_type ? "type" : "sizes");
        goto done;
    }
    thx_raw_type t = (thx_raw_type)h.type;
    size_t vsize = thx_raw_size(t);
    if (vsize > 1 && h.encoding != 2 && h.endian < 0) {
        st = thx_error(ctx, THX_EINPUT, "%s: no \"endian\" field (needed for %s voxels)", path, thx_raw_name(t));
        goto done;
    }
    size_t n[3] = {h.sizes[0], h.sizes[1], h.n_dim == 3 ? h.sizes[2] : 1}, need;
    if (product(n, vsize, &need) != 0) {
        st = thx_error(ctx, THX_EINPUT, "%s: %zu x %zu x %zu voxels do not fit in memory", path, n[0], n[1], n[2]);
        goto done;
    }
    /* the data: after the header, or in the data file */
    const char *data = buf + data_off, *what = path;
    size_t avail = len - data_off;
    char data_path[2100];
    if (h.data_file[0]) {
        thx_image_beside(path, h.data_file, data_path, sizeof data_path);
        if ((st = thx_read_file(ctx, data_path, &data_buf, &data_len)) != THX_OK) goto done;
        data = data_buf;
        avail = data_len;
        what = data_path;
    } else if (thx_image_has_suffix(path, ".nhdr")) {
        st = thx_error(ctx, THX_EINPUT, "%s: a detached header (.nhdr) without a \"data file\" field", path);
        goto done;
    }
    for (long s = 0; s < h.line_skip; s++) {
        const char *nl = memchr(data, '\n', avail);
        if (!nl) {
            st = thx_error(ctx, THX_EINPUT, "%s: line skip %ld: the data hold fewer lines: truncated", what, h.line_skip);
            goto done;
        }
        avail -= (size_t)(nl + 1 - data);
        data = nl + 1;
    }
    /* a gzip stream's byte skip counts decompressed bytes (teem's rule, pynrrd's too): applied below */
    if (h.encoding == 1) {
        /* gzip: the skip is applied after inflating */
    } else if (h.byte_skip == -1) {
        if (h.encoding != 0) {
            st = thx_error(ctx, THX_EINPUT, "%s: byte skip -1 goes only with raw or gzip encoding", path);
            goto done;
        }
        if (avail < need) goto short_data;
        data += avail - need;
        avail = need;
    } else if (h.byte_skip > 0) {
        if ((size_t)h.byte_skip > avail) goto short_data;
        data += h.byte_skip;
        avail -= (size_t)h.byte_skip;
    }
    if (h.encoding == 0 && avail != need) {
        if (avail < need) goto short_data;
        st = thx_error(ctx, THX_EINPUT,
                       "%s: the data hold %zu bytes more than the header's %zu x %zu x %zu %s voxels (%zu bytes): wrong "
                       "sizes or type?",
                       what, avail - need, n[0], n[1], n[2], thx_raw_name(t), need);
        goto done;
    }
    if (h.encoding == 1 && (double)need > thx_image_inflate_bound(avail)) goto short_data;
    if (h.encoding == 2 && need / vsize > avail / 2 + 1) goto short_data;
    if ((st = thx_image_alloc(ctx, n, img)) != THX_OK) goto done;
    if (h.encoding == 0) {
        thx_image_decode(img, (const unsigned char *)data, t, h.endian == 1);
    } else if (h.encoding == 1 && h.byte_skip != 0) {
        /* the whole stream, then the voxels at the skip (-1: its last bytes) */
        unsigned char *all = NULL;
        size_t nall = 0;
        if ((st = thx_image_inflate_all(ctx, (const unsigned char *)data, avail, &all, &nall, what)) != THX_OK)
            goto done;
        size_t off = h.byte_skip == -1 ? (nall >= need ? nall - need : 0) : (size_t)h.byte_skip;
        if (nall < need || nall - need < off) {
            st = thx_error(ctx, THX_EINPUT,
                           "%s: the compressed data give %zu bytes but the header claims %zu bytes of voxels after a byte "
                           "skip of %ld: truncated",
                           what, nall, need, h.byte_skip);
        } else if (h.byte_skip >= 0 && nall - need > off) {
            st = thx_error(ctx, THX_EINPUT,
                           "%s: the compressed data hold %zu bytes more than the byte skip and the header's voxels", what,
                           nall - need - off);
        } else {
            thx_image_decode(img, all + off, t, h.endian == 1);
        }
        free(all);
        if (st != THX_OK) goto done;
    } else if (h.encoding == 1) {
        unsigned char *raw = malloc(need ? need : 1);
        if (!raw) {
            st = thx_error(ctx, THX_ENOMEM, "%s: out of memory for %zu bytes of voxels", path, need);
            goto done;
        }
        st = thx_image_inflate(ctx, (const unsigned char *)data, avail, raw, need, what);
        if (st == THX_OK) thx_image_decode(img, raw, t, h.endian == 1);
        free(raw);
        if (st != THX_OK) goto done;
    } else if ((st = thx_image_decode_ascii(ctx, img, data, avail, t, what)) != THX_OK) {
        goto done;
    }
    snprintf(img->format, sizeof img->format, "nrrd");
    /* geometry */
    if (h.space >= 0) {
        static const char *const frames[] = {"RAS", "LAS", "LPS", "scanner-xyz (as LPS)"};
        snprintf(img->source_frame, sizeof img->source_frame, "%s", frames[h.space]);
        if (!h.have_dirs) {
            st = thx_error(ctx, THX_EINPUT, "%s: a space without \"space directions\"", path);
            goto done;
        }
        double sx = h.space == 0 ? 1 : -1, sy = h.space <= 1 ? 1 : -1; /* to RAS */
        for (int c = 0; c < h.n_dim; c++) {
            double v[3] = {sx * h.dirs[c][0] + 0.0, sy * h.dirs[c][1] + 0.0, h.dirs[c][2]};
            double l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
            img->spacing[c] = l * h.unit;
            for (int r = 0; r < 3; r++) img->dir[r * 3 + c] = l > 0 ? v[r] / l : 0;
        }
        if (h.have_origin) {
            img->origin[0] = sx * h.origin[0] * h.unit + 0.0;
            img->origin[1] = sy * h.origin[1] * h.unit + 0.0;
            img->origin[2] = h.origin[2] * h.unit;
        }
    } else {
        snprintf(img->source_frame, sizeof img->source_frame, "none (index axes taken as RAS)");
        for (int c = 0; c < h.n_dim; c++)
            img->spacing[c] = h.have_spacings && !isnan(h.spacings[c]) ? h.spacings[c] : 1.0;
    }
    if (h.n_dim == 2) {
        /* one plane: the third axis is the normal, right-handed, 1 mm */
        const double *d = img->dir;
        double u[3] = {d[0], d[3], d[6]}, w[3] = {d[1], d[4], d[7]};
        img->dir[2] = u[1] * w[2] - u[2] * w[1];
        img->dir[5] = u[2] * w[0] - u[0] * w[2];
        img->dir[8] = u[0] * w[1] - u[1] * w[0];
        img->spacing[2] = 1.0;
    }
    goto done;
short_data:
    st = thx_error(ctx, THX_EINPUT,
                   "%s: the header claims %zu x %zu x %zu %s voxels (%zu bytes) but the %sdata hold %zu bytes: truncated",
                   what, n[0], n[1], n[2], thx_raw_name(t), need,
                   h.encoding == 1 ? "compressed " : h.encoding == 2 ? "text " : "", avail);
done:
    free(buf);
    free(data_buf);
    if (st != THX_OK) thx_image_free(img);
    return st;
}

thx_status thx_image_write_nrrd(thx_ctx *ctx, const thx_image *img, thx_voxel_type type, thx_atomic_file *af)
{
    static const char *const nrrd_name[] = {"uint8", "int16", "uint16", "int32", "float"};
    if (thx_image_has_suffix(af->path, ".nhdr"))
        return thx_error(ctx, THX_EINPUT,
                         "%s: thorax writes NRRD as one file (.nrrd): a detached header and its data file cannot be "
                         "replaced together atomically",
                         af->path);
    char head[4096];
    int m = snprintf(head, sizeof head,
                     "NRRD0004\n# %s\n# written by thorax: voxel centres in RAS millimetres\ntype: %s\ndimension: 3\n"
                     "space: right-anterior-superior\nsizes: %zu %zu %zu\nspace directions:",
                     THX_IMAGE_MARKER, nrrd_name[type], img->n[0], img->n[1], img->n[2]);
    for (int c = 0; c < 3; c++)
        m += snprintf(head + m, sizeof head - (size_t)m, " (%.17g,%.17g,%.17g)", img->dir[0 * 3 + c] * img->spacing[c],
                      img->dir[1 * 3 + c] * img->spacing[c], img->dir[2 * 3 + c] * img->spacing[c]);
    m += snprintf(head + m, sizeof head - (size_t)m,
                  "\nkinds: domain domain domain\nendian: little\nencoding: gzip\nspace origin: (%.17g,%.17g,%.17g)\n"
                  "space units: \"mm\" \"mm\" \"mm\"\n\n",
                  img->origin[0], img->origin[1], img->origin[2]);
    unsigned char *raw = NULL, *z = NULL;
    size_t nraw = 0, nz = 0;
    THX_CHECK(thx_image_encode(ctx, img, type, &raw, &nraw));
    thx_status st = thx_image_deflate(ctx, raw, nraw, 1, &z, &nz, af->path);
    free(raw);
    if (st == THX_OK) st = thx_image_place_bytes(ctx, af, head, (size_t)m, z, nz);
    free(z);
    return st;
}
