/*
 * Time series, MATLAB .mat through libmatio (series.c has the dispatch).
 *
 * Decisions recorded here:
 *
 *  - .mat files go through libmatio as MATLAB 5 files without compression
 *    (scipy.io.loadmat and every MATLAB since 5 read them; compression would
 *    cost more time than the file size is worth here), with a fixed header
 *    text and no date, so the same series gives byte-identical files. Strings
 *    are written as UTF-16 code units (miUINT16), MATLAB's own char
 *    encoding: libmatio writes UTF-8 char arrays with one byte per
 *    character, which would cut multi-byte characters. On reading, UTF-8,
 *    UTF-16 and 8-bit (Latin-1) char data are accepted and stored as UTF-8.
 *    libmatio prints nothing unless someone calls Mat_LogInit, which the
 *    library never does; its failures are reported in our own words.
 */
#include "thorax/model/series.h"
#include "thorax/io/series_file.h"
#include <ctype.h>
#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include <matio.h>

#include "thorax/core/fileio.h"
#include "io/series/series_impl.h"

/* ------------------------------------------------------------- MATLAB */

#define MAT_HEADER_TEXT "MATLAB 5.0 MAT-file, Platform: any, Created by: thorax (libmatio)"

/* The code point of the UTF-8 sequence at p and its length in *len, or -1
 * (with *len = 1) for a byte that does not start a valid sequence. */
static long utf8_decode(const unsigned char *p, int *len)
{
    *len = 1;
    int n;
    uint32_t c;
    if (p[0] < 0x80) return p[0];
    if (p[0] >= 0xC2 && p[0] < 0xE0) n = 2, c = p[0] & 0x1Fu;
    else if (p[0] >= 0xE0 && p[0] < 0xF0) n = 3, c = p[0] & 0x0Fu;
    else if (p[0] >= 0xF0 && p[0] < 0xF5) n = 4, c = p[0] & 0x07u;
    else return -1;
    for (int i = 1; i < n; i++) {
        if ((p[i] & 0xC0) != 0x80) return -1; /* also stops at the NUL */
        c = (c << 6) | (p[i] & 0x3Fu);
    }
    static const uint32_t least[5] = {0, 0, 0x80, 0x800, 0x10000}; /* no overlong forms */
    if (c < least[n] || c > 0x10FFFF || (c >= 0xD800 && c < 0xE000)) return -1;
    *len = n;
    return (long)c;
}

/* UTF-8 to UTF-16 code units; a byte that is not valid UTF-8 is taken as
 * Latin-1. Returns the count (at most strlen(s)). */
static size_t utf8_to_utf16(const char *s, uint16_t *w)
{
    const unsigned char *p = (const unsigned char *)s;
    size_t n = 0;
    while (*p) {
        int len;
        long c = utf8_decode(p, &len);
        if (c < 0) c = *p;
        p += len;
        if (c >= 0x10000) {
            c -= 0x10000;
            w[n++] = (uint16_t)(0xD800 + (c >> 10));
            w[n++] = (uint16_t)(0xDC00 + (c & 0x3FF));
        } else {
            w[n++] = (uint16_t)c;
        }
    }
    return n;
}

/* Appends code point c as UTF-8 if it fits in cap bytes (NUL excluded); 0 if not. */
static int put_utf8(char *dst, size_t *n, size_t cap, uint32_t c)
{
    unsigned char b[4];
    size_t k = c < 0x80 ? 1 : c < 0x800 ? 2 : c < 0x10000 ? 3 : 4;
    if (*n + k > cap) return 0;
    if (k == 1) {
        b[0] = (unsigned char)c;
    } else {
        static const unsigned char lead[5] = {0, 0, 0xC0, 0xE0, 0xF0};
        for (size_t i = k - 1; i > 0; i--, c >>= 6) b[i] = (unsigned char)(0x80 | (c & 0x3F));
        b[0] = (unsigned char)(lead[k] | c);
    }
    memcpy(dst + *n, b, k);
    *n += k;
    return 1;
}

static thx_status mat_write_string(mat_t *mat, const char *name, const char *str, uint16_t *w)
{
    size_t n = utf8_to_utf16(str, w);
    size_t dims[2] = {n ? 1 : 0, n};
    matvar_t *v = Mat_VarCreate(name, MAT_C_CHAR, MAT_T_UINT16, 2, dims, n ? w : NULL, MAT_F_DONT_COPY_DATA);
    if (!v) return THX_EIO;
    int bad = Mat_VarWrite(mat, v, MAT_COMPRESSION_NONE);
    Mat_VarFree(v);
    return bad ? THX_EIO : THX_OK;
}

static const enum matio_classes field_class[] = {
    MAT_C_EMPTY, MAT_C_DOUBLE, MAT_C_SINGLE, MAT_C_INT8, MAT_C_UINT8, MAT_C_INT16, MAT_C_UINT16,
    MAT_C_INT32, MAT_C_UINT32, MAT_C_INT64, MAT_C_UINT64, MAT_C_CHAR, MAT_C_CELL};
static const enum matio_types field_type[] = {
    MAT_T_UNKNOWN, MAT_T_DOUBLE, MAT_T_SINGLE, MAT_T_INT8, MAT_T_UINT8, MAT_T_INT16, MAT_T_UINT16,
    MAT_T_INT32, MAT_T_UINT32, MAT_T_INT64, MAT_T_UINT64, MAT_T_UINT16, MAT_T_CELL};

/* A char matvar of UTF-8 text (UTF-16 code units, MATLAB's encoding); w holds 2 * strlen + 2 units.
 * dims0: the first dimension the file had for an empty string (0 or 1). */
static matvar_t *mat_char_var(const char *name, const char *str, uint16_t *w, size_t dims0)
{
    size_t n = utf8_to_utf16(str, w);
    size_t dims[2] = {n ? 1 : dims0, n};
    return Mat_VarCreate(name, MAT_C_CHAR, MAT_T_UINT16, 2, dims, n ? w : NULL, 0);
}

/* map3d's fids: a 1 x n struct array of value (double: 1 or one per row), type and fidset. */
static matvar_t *mat_fids_var(const char *name, const thx_series *s)
{
    const char *names[3] = {"value", "type", "fidset"};
    size_t dims[2] = {1, s->n_fids};
    matvar_t *st = Mat_VarCreateStruct(name, 2, dims, names, 3);
    for (size_t k = 0; st && k < s->n_fids; k++) {
        const thx_fiducial *f = &s->fids[k];
        size_t vd[2] = {f->n, 1}, sd[2] = {1, 1};
        double type = f->type, fidset = f->fidset;
        matvar_t *v = Mat_VarCreate(NULL, MAT_C_DOUBLE, MAT_T_DOUBLE, 2, vd, f->v, 0);
        matvar_t *t = Mat_VarCreate(NULL, MAT_C_DOUBLE, MAT_T_DOUBLE, 2, sd, &type, 0);
        matvar_t *g = Mat_VarCreate(NULL, MAT_C_DOUBLE, MAT_T_DOUBLE, 2, sd, &fidset, 0);
        if (!v || !t || !g) {
            Mat_VarFree(v), Mat_VarFree(t), Mat_VarFree(g), Mat_VarFree(st);
            return NULL;
        }
        Mat_VarSetStructFieldByName(st, "value", k, v);
        Mat_VarSetStructFieldByName(st, "type", k, t);
        Mat_VarSetStructFieldByName(st, "fidset", k, g);
    }
    return st;
}

/* The struct the series came from (s->group), its fields in the file's order. */
static matvar_t *mat_group_var(const thx_series *s, uint16_t *w, size_t wcap)
{
    size_t nf = s->n_fields;
    const char **names = malloc((nf + 4) * sizeof *names);
    if (!names) return NULL;
    for (size_t k = 0; k < nf; k++) names[k] = s->fields[k].name;
    /* what the series holds but the struct did not name */
    static const char *const own[4] = {"potvals", "unit", "label", "fids"};
    for (int j = 0; j < 4; j++)
        if (!thx_series_field_get(s, own[j]) && (j == 0 || (j == 1 && s->unit[0]) || (j == 2 && s->label[0]) ||
                                                 (j == 3 && s->n_fids)))
            names[nf++] = own[j];
    size_t dims[2] = {1, 1};
    matvar_t *st = Mat_VarCreateStruct(s->group, 2, dims, names, (unsigned)nf);
    for (size_t k = 0; st && k < nf; k++) {
        const thx_series_field *f = k < s->n_fields ? &s->fields[k] : NULL;
        matvar_t *v = NULL;
        if (!f || f->cls == THX_FIELD_SERIES) {
            if (!strcmp(names[k], "potvals")) {
                size_t d[2] = {s->n_rows, s->n_frames};
                v = Mat_VarCreate(NULL, MAT_C_DOUBLE, MAT_T_DOUBLE, 2, d, s->v, 0);
            } else if (!strcmp(names[k], "unit")) {
                v = mat_char_var(NULL, s->unit, w, 1);
            } else if (!strcmp(names[k], "label")) {
                v = mat_char_var(NULL, s->label, w, 1);
            } else if (!strcmp(names[k], "fids")) {
                v = mat_fids_var(NULL, s);
            }
        } else if (f->cls == THX_FIELD_CHAR) {
            const char *txt = f->data ? (const char *)f->data : "";
            if (2 * strlen(txt) + 2 > wcap) {
                uint16_t *big = malloc((2 * strlen(txt) + 2) * sizeof *big);
                if (big) v = mat_char_var(NULL, txt, big, f->dims[0]);
                free(big);
            } else {
                v = mat_char_var(NULL, txt, w, f->dims[0]);
            }
        } else if (f->cls == THX_FIELD_EMPTY_CELL) {
            size_t d[2] = {f->dims[0], f->dims[1]};
            v = Mat_VarCreate(NULL, MAT_C_CELL, MAT_T_CELL, 2, d, NULL, 0);
        } else {
            size_t d[2] = {f->dims[0], f->dims[1]};
            v = Mat_VarCreate(NULL, field_class[f->cls], field_type[f->cls], 2, d, f->data, 0);
        }
        if (!v) {
            Mat_VarFree(st);
            st = NULL;
            break;
        }
        Mat_VarSetStructFieldByName(st, names[k], 0, v);
    }
    free(names);
    return st;
}

thx_status series_write_mat(thx_ctx *ctx, const thx_series *s, const char *path)
{
    /* An existing file is replaced only when libmatio wrote it for thorax (its header text). */
    thx_atomic_file af;
    THX_CHECK(thx_atomic_open_output(ctx, path, "Created by: thorax", 18, NULL, 0, &af));
    /* libmatio opens files by name: keep the temporary name, write through it */
    fclose(af.f);
    af.f = NULL;
    errno = 0;
    mat_t *mat = Mat_CreateVer(af.tmp, MAT_HEADER_TEXT, MAT_FT_MAT5);
    if (!mat) {
        thx_atomic_abort(&af);
        return thx_error(ctx, THX_EIO, "%s: libmatio cannot create the file", path);
    }
    const char *what = "potvals";
    uint16_t w[2 * sizeof s->label];
    int bad = 0;
    matvar_t *v = NULL;
    if (s->group[0]) {
        /* the struct it came from (map3d's ts), every field kept */
        what = s->group;
        v = mat_group_var(s, w, sizeof w / sizeof w[0]);
        bad = !v || Mat_VarWrite(mat, v, MAT_COMPRESSION_NONE) != 0;
        Mat_VarFree(v);
        goto close;
    }
    size_t dims[2] = {s->n_rows, s->n_frames};
    v = Mat_VarCreate("potvals", MAT_C_DOUBLE, MAT_T_DOUBLE, 2, dims, s->v, MAT_F_DONT_COPY_DATA);
    bad = !v || Mat_VarWrite(mat, v, MAT_COMPRESSION_NONE) != 0;
    Mat_VarFree(v);
    if (!bad) {
        what = "time";
        size_t tdims[2] = {1, s->n_frames};
        v = Mat_VarCreate("time", MAT_C_DOUBLE, MAT_T_DOUBLE, 2, tdims, s->time, MAT_F_DONT_COPY_DATA);
        bad = !v || Mat_VarWrite(mat, v, MAT_COMPRESSION_NONE) != 0;
        Mat_VarFree(v);
    }
    if (!bad) bad = mat_write_string(mat, what = "unit", s->unit, w) != THX_OK;
    if (!bad) bad = mat_write_string(mat, what = "time_unit", s->time_unit, w) != THX_OK;
    if (!bad) bad = mat_write_string(mat, what = "label", s->label, w) != THX_OK;
    if (!bad && s->n_fids) {
        what = "fids";
        v = mat_fids_var("fids", s);
        bad = !v || Mat_VarWrite(mat, v, MAT_COMPRESSION_NONE) != 0;
        Mat_VarFree(v);
    }
close:;
    int e = errno;
    if (Mat_Close(mat) != 0 && !bad) {
        bad = 1;
        what = "the end of the file";
    }
    /* libmatio does not always report a failed fwrite: a file shorter than
     * its data is (a full disk) is caught here */
    struct stat sb;
    if (!bad && (stat(af.tmp, &sb) != 0 || (uint64_t)sb.st_size < 128 + 8 * (uint64_t)s->n_frames * (s->n_rows + (s->group[0] ? 0 : 1)))) {
        bad = 1;
        what = "the data (the file is too short: disk full?)";
    }
    if (bad) {
        thx_atomic_abort(&af);
        return thx_error(ctx, THX_EIO, "%s: writing %s failed: %s", path, what, e ? strerror(e) : "libmatio error");
    }
    thx_status st = thx_output_place(ctx, &af, af.tmp); /* under the claim: see thorax/core/fileio.h */
    af.tmp[0] = '\0';
    return st;
}

static const char *mat_class_name(const matvar_t *v)
{
    static const char *const names[] = {"empty", "cell", "struct", "object", "char", "sparse", "double", "single",
                                        "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64",
                                        "function", "opaque"};
    if (v->isLogical) return "logical";
    return (unsigned)v->class_type < sizeof names / sizeof names[0] ? names[v->class_type] : "unknown";
}

static int mat_is_numeric_class(enum matio_classes c)
{
    return c == MAT_C_DOUBLE || c == MAT_C_SINGLE || c == MAT_C_INT8 || c == MAT_C_UINT8 || c == MAT_C_INT16 ||
           c == MAT_C_UINT16 || c == MAT_C_INT32 || c == MAT_C_UINT32 || c == MAT_C_INT64 || c == MAT_C_UINT64;
}

static size_t mat_numel(const matvar_t *v)
{
    size_t n = 1;
    for (int i = 0; i < v->rank; i++) n *= v->dims[i];
    return v->rank > 0 ? n : 0;
}

/* A candidate for the values: real, numeric, 2-D, not empty. */
static int mat_is_matrix(const matvar_t *v)
{
    return v && mat_is_numeric_class(v->class_type) && !v->isComplex && !v->isLogical && v->rank == 2 &&
           mat_numel(v) > 0;
}

/* Why v cannot be the values (for messages), or NULL. */
static const char *mat_not_matrix(const matvar_t *v)
{
    if (!mat_is_numeric_class(v->class_type)) return "not a numeric matrix";
    if (v->isComplex) return "complex (only real values are supported)";
    if (v->rank != 2) return "not 2-D (a series is a rows x frames matrix)";
    if (mat_numel(v) == 0) return "empty";
    return NULL;
}

/* Converts n numeric elements of v (any real class) to double. */
static int mat_to_double(const matvar_t *v, size_t n, double *out)
{
    if (!v->data) return 0;
    switch (v->class_type) {
#define CONV(T)                                                 \
    do {                                                        \
        const T *d = (const T *)v->data;                        \
        for (size_t i = 0; i < n; i++) out[i] = (double)d[i];   \
    } while (0)
    case MAT_C_DOUBLE: memcpy(out, v->data, n * sizeof *out); return 1;
    case MAT_C_SINGLE: CONV(float); return 1;
    case MAT_C_INT8: CONV(int8_t); return 1;
    case MAT_C_UINT8: CONV(uint8_t); return 1;
    case MAT_C_INT16: CONV(int16_t); return 1;
    case MAT_C_UINT16: CONV(uint16_t); return 1;
    case MAT_C_INT32: CONV(int32_t); return 1;
    case MAT_C_UINT32: CONV(uint32_t); return 1;
    case MAT_C_INT64: CONV(int64_t); return 1;
    case MAT_C_UINT64: CONV(uint64_t); return 1;
    default: return 0;
#undef CONV
    }
}

/* A char variable as UTF-8 into dst (cap bytes with the NUL). Returns 0 if it
 * is not a one-line char array; sets *cut when it had to be shortened. */
static int mat_string(const matvar_t *v, char *dst, size_t cap, int *cut)
{
    *cut = 0;
    dst[0] = '\0';
    if (v->class_type != MAT_C_CHAR || v->rank != 2 || v->dims[0] > 1) return 0;
    size_t n = 0, limit = cap - 1;
    if (!v->data || v->nbytes == 0 || mat_numel(v) == 0) return 1;
    switch (v->data_type) {
    case MAT_T_UTF8: {
        /* whole characters only */
        const unsigned char *b = v->data;
        size_t len = v->nbytes, i = 0;
        while (i < len && b[i]) {
            size_t k = 1;
            if (b[i] >= 0xC0) while (i + k < len && (b[i + k] & 0xC0) == 0x80) k++;
            if (n + k > limit) {
                *cut = 1;
                break;
            }
            memcpy(dst + n, b + i, k);
            n += k;
            i += k;
        }
        break;
    }
    case MAT_T_UINT16:
    case MAT_T_INT16:
    case MAT_T_UTF16: {
        const uint16_t *w = v->data;
        size_t len = v->nbytes / 2;
        for (size_t i = 0; i < len && w[i]; i++) {
            uint32_t c = w[i];
            if (c >= 0xD800 && c < 0xDC00 && i + 1 < len && w[i + 1] >= 0xDC00 && w[i + 1] < 0xE000) {
                c = 0x10000 + ((c - 0xD800) << 10) + (w[i + 1] - 0xDC00u);
                i++;
            } else if (c >= 0xD800 && c < 0xE000) {
                c = 0xFFFD;
            }
            if (!put_utf8(dst, &n, limit, c)) {
                *cut = 1;
                break;
            }
        }
        break;
    }
    case MAT_T_UINT8:
    case MAT_T_INT8: {
        const unsigned char *b = v->data;
        for (size_t i = 0; i < v->nbytes && b[i]; i++)
            if (!put_utf8(dst, &n, limit, b[i])) {
                *cut = 1;
                break;
            }
        break;
    }
    default: return 0;
    }
    dst[n] = '\0';
    return 1;
}

/* Where the metadata (time, unit, time_unit, label) come from: top-level
 * variables, or the fields of the struct that held the values. */
typedef struct {
    mat_t *mat;
    matvar_t *holder; /* the struct, or NULL for top level */
    matvar_t *owned;  /* the top-level variable last read (freed by the next mat_meta_get or the caller) */
} mat_meta;

static matvar_t *mat_meta_get(mat_meta *m, const char *name)
{
    if (m->holder) return Mat_VarGetStructFieldByName(m->holder, name, 0);
    Mat_VarFree(m->owned);
    m->owned = NULL;
    matvar_t *info = Mat_VarReadInfo(m->mat, name);
    if (!info) return NULL;
    Mat_VarFree(info);
    m->owned = Mat_VarRead(m->mat, name);
    return m->owned;
}

static thx_status mat_read_meta(thx_ctx *ctx, const char *path, const char *where, mat_meta *m, thx_series *s)
{
    matvar_t *t = mat_meta_get(m, "time");
    int have_time = 0;
    if (t && t->class_type == MAT_C_CHAR) {
        /* map3d's ts.time is the clock time of the recording ("2:06:25 PM"), not an axis */
        char clock[64];
        int cut = 0;
        if (mat_string(t, clock, sizeof clock, &cut))
            thx_log(ctx, THX_LOG_DEBUG, "%s: %stime '%s' is text (a clock time), not a time axis", path, where, clock);
        t = NULL;
    }
    if (t) {
        have_time = 1;
        size_t n = mat_numel(t);
        if (!mat_is_numeric_class(t->class_type) || t->isComplex || n != s->n_frames)
            return thx_error(ctx, THX_EINPUT, "%s: %stime is %s with %zu elements, but the series has %zu frames "
                                              "(a numeric vector of one time per frame is needed)",
                             path, where, mat_class_name(t), n, s->n_frames);
        if (!mat_to_double(t, n, s->time))
            return thx_error(ctx, THX_EINPUT, "%s: %stime: no data", path, where);
    }
    if (!have_time) {
        /* map3d's samplefrequency (Hz): frames 1 / fs apart, in ms */
        matvar_t *fs = mat_meta_get(m, "samplefrequency");
        double hz = 0;
        if (fs && mat_is_numeric_class(fs->class_type) && !fs->isComplex && mat_numel(fs) == 1 && mat_to_double(fs, 1, &hz) &&
            isfinite(hz) && hz > 0) {
            for (size_t f = 0; f < s->n_frames; f++) s->time[f] = (double)f * (1000.0 / hz);
            snprintf(s->time_unit, sizeof s->time_unit, "ms");
        } else if (fs) {
            thx_log(ctx, THX_LOG_WARN, "%s: %ssamplefrequency ignored: not one positive number", path, where);
        }
    }
    static const char *const names[] = {"unit", "time_unit", "label"};
    char *dst[] = {s->unit, s->time_unit, s->label};
    size_t cap[] = {sizeof s->unit, sizeof s->time_unit, sizeof s->label};
    for (int k = 0; k < 3; k++) {
        matvar_t *v = mat_meta_get(m, names[k]);
        if (!v) continue;
        char tmp[128];
        int cut = 0;
        if (!mat_string(v, tmp, cap[k], &cut)) {
            thx_log(ctx, THX_LOG_WARN, "%s: %s%s ignored: %s, not a one-line char array", path, where, names[k],
                    mat_class_name(v));
            continue;
        }
        if (cut) thx_log(ctx, THX_LOG_WARN, "%s: %s%s cut to %zu bytes", path, where, names[k], cap[k] - 1);
        memcpy(dst[k], tmp, cap[k]);
    }
    Mat_VarFree(m->owned);
    m->owned = NULL;
    return THX_OK;
}

static const thx_field_class class_field[] = {
    [MAT_C_DOUBLE] = THX_FIELD_DOUBLE, [MAT_C_SINGLE] = THX_FIELD_SINGLE, [MAT_C_INT8] = THX_FIELD_INT8,
    [MAT_C_UINT8] = THX_FIELD_UINT8, [MAT_C_INT16] = THX_FIELD_INT16, [MAT_C_UINT16] = THX_FIELD_UINT16,
    [MAT_C_INT32] = THX_FIELD_INT32, [MAT_C_UINT32] = THX_FIELD_UINT32, [MAT_C_INT64] = THX_FIELD_INT64,
    [MAT_C_UINT64] = THX_FIELD_UINT64};

/* map3d's fids (a struct array of value, type, fidset) into the series' fiducials. */
static thx_status mat_read_fids(thx_ctx *ctx, const char *path, const char *where, matvar_t *fv, thx_series *s)
{
    if (fv->class_type != MAT_C_STRUCT) {
        thx_log(ctx, THX_LOG_WARN, "%s: %sfids is %s, not a struct array: not kept", path, where, mat_class_name(fv));
        return THX_OK;
    }
    size_t n = mat_numel(fv);
    for (size_t k = 0; k < n; k++) {
        matvar_t *val = Mat_VarGetStructFieldByName(fv, "value", k), *typ = Mat_VarGetStructFieldByName(fv, "type", k);
        matvar_t *set = Mat_VarGetStructFieldByName(fv, "fidset", k);
        double t = 0, g = 0;
        size_t nv = val ? mat_numel(val) : 0;
        /* the data buffers must hold what the dimensions say before they are converted */
        int ok = val && typ && mat_is_numeric_class(val->class_type) && !val->isComplex &&
                 mat_is_numeric_class(typ->class_type) && mat_numel(typ) == 1 && (nv == 1 || nv == s->n_rows) &&
                 val->data && typ->data && val->nbytes >= nv * Mat_SizeOfClass(val->class_type) &&
                 typ->nbytes >= Mat_SizeOfClass(typ->class_type);
        if (!ok || !mat_to_double(typ, 1, &t)) {
            thx_log(ctx, THX_LOG_WARN, "%s: %sfids(%zu) not kept: a numeric type and one value or one per row (%zu) "
                                       "are needed", path, where, k + 1, s->n_rows);
            continue;
        }
        if (set && mat_is_numeric_class(set->class_type) && mat_numel(set) == 1 && set->data &&
            set->nbytes >= Mat_SizeOfClass(set->class_type))
            mat_to_double(set, 1, &g);
        if (!isfinite(t) || t < -1e6 || t > 1e6 || !isfinite(g) || g < -1e6 || g > 1e6) {
            thx_log(ctx, THX_LOG_WARN, "%s: %sfids(%zu) not kept: type %g, fidset %g", path, where, k + 1, t, g);
            continue;
        }
        double *x = malloc(nv * sizeof *x);
        if (!x) return thx_error(ctx, THX_ENOMEM, "%s: out of memory", path);
        if (!mat_to_double(val, nv, x)) {
            free(x);
            continue;
        }
        thx_status st = thx_series_add_fiducial(ctx, s, (int)t, (int)g, nv, x);
        free(x);
        THX_CHECK(st);
    }
    return THX_OK;
}

/* Every field of the struct the values came from, kept in order (potvals, unit, label and fids as
 * the series' own). */
static thx_status mat_keep_fields(thx_ctx *ctx, const char *path, matvar_t *top, thx_series *s)
{
    unsigned nf = Mat_VarGetNumberOfFields(top);
    char *const *names = Mat_VarGetStructFieldnames(top);
    snprintf(s->group, sizeof s->group, "%s", top->name ? top->name : "ts");
    char where[80];
    snprintf(where, sizeof where, "%.60s.", s->group);
    for (unsigned k = 0; k < nf && names; k++) {
        const char *nm = names[k];
        matvar_t *f = Mat_VarGetStructFieldByIndex(top, k, 0);
        size_t d0[2] = {0, 0};
        if (!strcmp(nm, "potvals") || !strcmp(nm, "unit") || !strcmp(nm, "label") || !strcmp(nm, "fids")) {
            if (!strcmp(nm, "fids") && f) THX_CHECK(mat_read_fids(ctx, path, where, f, s));
            THX_CHECK(thx_series_add_field(ctx, s, nm, THX_FIELD_SERIES, d0, NULL, 0));
            continue;
        }
        if (!f) continue;
        size_t dims[2] = {f->rank >= 1 ? f->dims[0] : 0, f->rank >= 2 ? f->dims[1] : 1};
        if (f->class_type == MAT_C_EMPTY) {
            /* libmatio's empty array (MATLAB's [] of any class; its size is not kept): an empty double */
            THX_CHECK(thx_series_add_field(ctx, s, nm, THX_FIELD_DOUBLE, d0, NULL, 0));
        } else if (f->rank != 2) {
            thx_log(ctx, THX_LOG_WARN, "%s: %s%s not kept: %d-D", path, where, nm, f->rank);
        } else if (mat_is_numeric_class(f->class_type) && !f->isComplex) {
            thx_field_class c = class_field[f->class_type];
            size_t nb = mat_numel(f) * thx_field_class_size(c);
            if (nb && (!f->data || f->nbytes < nb))
                thx_log(ctx, THX_LOG_WARN, "%s: %s%s not kept: no data", path, where, nm);
            else
                THX_CHECK(thx_series_add_field(ctx, s, nm, c, dims, f->data, nb));
        } else if (f->class_type == MAT_C_CHAR) {
            size_t cap = 3 * f->nbytes + 2;
            char *txt = malloc(cap);
            int cut = 0;
            if (!txt) return thx_error(ctx, THX_ENOMEM, "%s: out of memory", path);
            if (mat_string(f, txt, cap, &cut))
                THX_CHECK(thx_series_add_field(ctx, s, nm, THX_FIELD_CHAR, dims, txt, strlen(txt) + 1));
            else
                thx_log(ctx, THX_LOG_WARN, "%s: %s%s not kept: a char array of several lines", path, where, nm);
            free(txt);
        } else if (f->class_type == MAT_C_CELL && mat_numel(f) == 0) {
            THX_CHECK(thx_series_add_field(ctx, s, nm, THX_FIELD_EMPTY_CELL, dims, NULL, 0));
        } else {
            thx_log(ctx, THX_LOG_WARN, "%s: %s%s (%s) not kept: only numeric arrays, text and empty cells are", path,
                    where, nm, mat_class_name(f));
        }
    }
    return THX_OK;
}

/* "a (double 3x4), b (char 1x2)" for messages. */
static void mat_list_vars(mat_t *mat, char *buf, size_t cap)
{
    size_t n = 0;
    buf[0] = '\0';
    Mat_Rewind(mat);
    matvar_t *v;
    int count = 0;
    while ((v = Mat_VarReadNextInfo(mat)) && n < cap) {
        int w = snprintf(buf + n, cap - n, "%s%s (%s", count++ ? ", " : "", v->name ? v->name : "?",
                         mat_class_name(v));
        n += w > 0 ? (size_t)w : 0;
        for (int i = 0; i < v->rank && n < cap; i++) {
            w = snprintf(buf + n, cap - n, "%s%zu", i ? "x" : " ", v->dims[i]);
            n += w > 0 ? (size_t)w : 0;
        }
        if (n < cap) {
            w = snprintf(buf + n, cap - n, ")");
            n += w > 0 ? (size_t)w : 0;
        }
        Mat_VarFree(v);
    }
    Mat_VarFree(v);
    if (!count) snprintf(buf, cap, "none");
}

thx_status series_read_mat(thx_ctx *ctx, const char *path, const char *varname, thx_series **out)
{
    *out = NULL;
    FILE *probe = fopen(path, "rb");
    if (!probe) return thx_error(ctx, THX_EIO, "%s: cannot open: %s", path, strerror(errno));
    fclose(probe);
    /* nothing reaches libmatio unless every variable's size has been checked against the file */
    THX_CHECK(series_mat_preflight(ctx, path));
    mat_t *mat = Mat_Open(path, MAT_ACC_RDONLY);
    if (!mat) return thx_error(ctx, THX_EINPUT, "%s: not a MATLAB .mat file that libmatio can read", path);
    thx_status st = THX_OK;
    thx_series *s = NULL;
    matvar_t *top = NULL;     /* the variable read */
    const matvar_t *vals = NULL;
    char where[200] = "", vars[1024];
    const char *name = varname;
    if (!name) {
        /* potvals, else the first struct with a potvals field, else the first matrix */
        matvar_t *info = Mat_VarReadInfo(mat, "potvals");
        if (info) {
            name = "potvals";
            Mat_VarFree(info);
        } else {
            char fs[256] = "", fm[256] = "";
            Mat_Rewind(mat);
            while ((info = Mat_VarReadNextInfo(mat))) {
                if (!fs[0] && info->class_type == MAT_C_STRUCT && mat_numel(info) >= 1 && info->name &&
                    Mat_VarGetStructFieldByName(info, "potvals", 0))
                    snprintf(fs, sizeof fs, "%s", info->name);
                if (!fm[0] && mat_is_matrix(info) && info->name) snprintf(fm, sizeof fm, "%s", info->name);
                Mat_VarFree(info);
            }
            if (!fs[0] && !fm[0]) {
                mat_list_vars(mat, vars, sizeof vars);
                st = thx_error(ctx, THX_EINPUT,
                               "%s: no numeric variable: no 'potvals', no struct with a 'potvals' field, no 2-D "
                               "numeric matrix (variables: %s)",
                               path, vars);
                goto done;
            }
            top = Mat_VarRead(mat, fs[0] ? fs : fm);
            if (!top) {
                st = thx_error(ctx, THX_EINPUT, "%s: variable '%s' cannot be read (damaged file?)", path,
                               fs[0] ? fs : fm);
                goto done;
            }
            name = top->name;
        }
    }
    if (!top) {
        matvar_t *info = Mat_VarReadInfo(mat, name);
        if (!info) {
            mat_list_vars(mat, vars, sizeof vars);
            st = thx_error(ctx, THX_EINPUT, "%s: no variable '%s' (variables: %s)", path, name, vars);
            goto done;
        }
        Mat_VarFree(info);
        top = Mat_VarRead(mat, name);
        if (!top) {
            st = thx_error(ctx, THX_EINPUT, "%s: variable '%s' cannot be read (damaged file?)", path, name);
            goto done;
        }
    }
    mat_meta meta = {mat, NULL, NULL};
    if (top->class_type == MAT_C_STRUCT) {
        const matvar_t *pv = mat_numel(top) >= 1 ? Mat_VarGetStructFieldByName(top, "potvals", 0) : NULL;
        if (!pv) {
            st = thx_error(ctx, THX_EINPUT, "%s: variable '%s' is a struct without a 'potvals' field", path,
                           top->name);
            goto done;
        }
        if (mat_numel(top) > 1)
            thx_log(ctx, THX_LOG_WARN, "%s: '%s' is a struct array of %zu elements; the first is read", path,
                    top->name, mat_numel(top));
        vals = pv;
        meta.holder = top;
        snprintf(where, sizeof where, "%s.", top->name);
    } else {
        vals = top;
    }
    const char *why = mat_not_matrix(vals);
    if (why) {
        st = thx_error(ctx, THX_EINPUT, "%s: %s%s (%s) is %s", path, where, meta.holder ? "potvals" : top->name,
                       mat_class_name(vals), why);
        goto done;
    }
    if ((st = thx_series_create(ctx, vals->dims[0], vals->dims[1], &s)) != THX_OK) goto done;
    if (!mat_to_double(vals, s->n_rows * s->n_frames, s->v)) {
        st = thx_error(ctx, THX_EINPUT, "%s: %s%s: no data", path, where, meta.holder ? "potvals" : top->name);
        goto done;
    }
    if ((st = mat_read_meta(ctx, path, where, &meta, s)) != THX_OK) {
        Mat_VarFree(meta.owned);
        goto done;
    }
    if (meta.holder) {
        if ((st = mat_keep_fields(ctx, path, top, s)) != THX_OK) goto done;
    } else {
        /* top-level potvals: a top-level fids */
        matvar_t *info = Mat_VarReadInfo(mat, "fids");
        if (info) {
            Mat_VarFree(info);
            matvar_t *fv = Mat_VarRead(mat, "fids");
            if (fv) st = mat_read_fids(ctx, path, "", fv, s);
            Mat_VarFree(fv);
            if (st != THX_OK) goto done;
        }
    }
    st = thx_series_validate(ctx, s, path);
done:
    Mat_VarFree(top);
    Mat_Close(mat);
    if (st != THX_OK) thx_series_destroy(&s);
    *out = s;
    return st;
}

