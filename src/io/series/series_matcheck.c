/*
 * The check of a MATLAB 5 .mat file before libmatio reads it
 * (series_mat_preflight; series_mat.c calls it first).
 *
 * Why: libmatio sizes its arrays from the dimensions a variable's header
 * claims and only then reads the data, so a file of a few hundred bytes can
 * make it allocate gigabytes (issue 11: 16.8 GB, exit 0), and a file cut in
 * half reads as the variables before the cut (the time axis, unit and label
 * lost, exit 0). So every element of the file is walked here first, with
 * nothing allocated but fixed buffers, and the file is refused unless the
 * whole of it is well-formed:
 *
 *  - the 128-byte header: text, version 0x0100 and the byte order mark
 *    ('IM' little-endian, 'MI' big-endian; both are read). Version 0x0200
 *    (v7.3, HDF5) is refused: an HDF5 dataset may claim any size with no
 *    storage at all (fill values), so its size cannot be checked against the
 *    file the way a v5 element can; MATLAB saves v7 with -v7. MATLAB 4 files
 *    (no header text) are refused too.
 *  - every top-level element is a variable (miMATRIX, or miCOMPRESSED holding
 *    one miMATRIX) whose size fits in what is left of the file; nothing but
 *    whole variables up to the end of the file (a cut variable, stray bytes
 *    after the last one: refused, naming the byte offset).
 *  - inside a variable, recursively (cells, struct fields; at most 32
 *    levels): the array flags, dimensions and name sub-elements; numeric and
 *    char data of exactly the bytes its dimensions and stored type need (so
 *    libmatio's arrays, numel x class size, are at most 8 times the bytes the
 *    file holds for them); sparse arrays with consistent ir/jc/data lengths;
 *    a cell's or struct's claimed count of sub-variables checked against the
 *    bytes left before any is walked (each takes at least its 8-byte tag);
 *    object, function-handle and opaque classes refused (libmatio cannot
 *    read them).
 *  - a compressed variable (zlib) is inflated here through a fixed buffer.
 *    Its stream must end exactly where its element does, hold one whole
 *    variable and nothing after it, and inflate to at most 1032 times its
 *    compressed size (deflate cannot exceed 1032:1: a longer output is not a
 *    deflate stream). And the doubles thorax makes of it (8 bytes per
 *    element) must stay within 1032 times the compressed bytes plus 1 MiB:
 *    an all-zero matrix that MATLAB stored as uint8 (it packs integer-valued
 *    doubles into the smallest integer type) could otherwise turn 1 byte of
 *    file into 8 KB of memory. Real recordings compress 2-10 times; the
 *    1 MiB lets small variables of any ratio through.
 * So reading a file costs at most about 8 times its size uncompressed,
 * 1032 times it compressed, plus libmatio's own small structures.
 */
#include <errno.h>
#include <inttypes.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <zlib.h>

#include "io/series/series_impl.h"

#define MAT_MAX_DEPTH 32
#define ZLIB_MAX_RATIO 1032u
#define ZLIB_SLACK (1u << 20)

/* MATLAB 5 data types and array classes (the MAT-file format, tables 1-2 and 1-3) */
enum { miINT8 = 1, miUINT8, miINT16, miUINT16, miINT32, miUINT32, miSINGLE, miDOUBLE = 9, miINT64 = 12, miUINT64,
       miMATRIX, miCOMPRESSED, miUTF8, miUTF16, miUTF32 };
enum { mxCELL = 1, mxSTRUCT, mxOBJECT, mxCHAR, mxSPARSE, mxDOUBLE, mxSINGLE, mxINT8, mxUINT8, mxINT16, mxUINT16,
       mxINT32, mxUINT32, mxINT64, mxUINT64, mxFUNCTION, mxOPAQUE };

/* Bytes per element of a numeric or char data type; 0 for any other. */
static unsigned type_size(uint32_t t)
{
    switch (t) {
    case miINT8: case miUINT8: case miUTF8: return 1;
    case miINT16: case miUINT16: case miUTF16: return 2;
    case miINT32: case miUINT32: case miSINGLE: case miUTF32: return 4;
    case miDOUBLE: case miINT64: case miUINT64: return 8;
    default: return 0;
    }
}

/* The bytes of the file, or of one compressed variable's inflated stream. */
typedef struct {
    FILE *f;
    int swap;           /* the file is big-endian */
    uint64_t pos;       /* bytes consumed (file offset, or inflated offset) */
    z_stream *z;        /* non-NULL: reading the inflated stream */
    uint64_t z_left;    /* compressed bytes not yet fed to zlib */
    int z_end;          /* Z_STREAM_END seen */
    unsigned char zin[16384];
} msrc;

/* Reads n bytes (buf NULL: skips them); -1 if the source ends first, -2 if zlib refuses the stream. */
static int src_read(msrc *s, void *buf, uint64_t n)
{
    if (!s->z) {
        if (!buf) {
            if (fseeko(s->f, (off_t)n, SEEK_CUR) != 0) return -1;
            s->pos += n;
            return 0;
        }
        if (fread(buf, 1, n, s->f) != n) return -1;
        s->pos += n;
        return 0;
    }
    unsigned char scratch[16384];
    while (n) {
        if (s->z_end) return -1;
        size_t want = n < sizeof scratch ? (size_t)n : sizeof scratch;
        s->z->next_out = buf ? (unsigned char *)buf : scratch;
        s->z->avail_out = (uInt)want;
        while (s->z->avail_out) {
            if (s->z->avail_in == 0 && s->z_left) {
                size_t k = s->z_left < sizeof s->zin ? (size_t)s->z_left : sizeof s->zin;
                if (fread(s->zin, 1, k, s->f) != k) return -1;
                s->z_left -= k;
                s->z->next_in = s->zin;
                s->z->avail_in = (uInt)k;
            }
            int rc = inflate(s->z, Z_NO_FLUSH);
            if (rc == Z_STREAM_END) {
                s->z_end = 1;
                break;
            }
            if (rc == Z_BUF_ERROR && s->z->avail_in == 0 && s->z_left == 0) return -1; /* stream cut short */
            if (rc != Z_OK && rc != Z_BUF_ERROR) return -2;
        }
        size_t got = want - s->z->avail_out;
        s->pos += got;
        n -= got;
        if (buf) buf = (unsigned char *)buf + got;
        if (got < want) return -1;
    }
    return 0;
}

static uint32_t get_u32(const msrc *s, const unsigned char *p)
{
    return s->swap ? (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3]
                   : (uint32_t)p[3] << 24 | (uint32_t)p[2] << 16 | (uint32_t)p[1] << 8 | p[0];
}

typedef struct {
    thx_ctx *ctx;
    const char *path;
    msrc *src;
    size_t var;           /* top-level variable number, from 1 */
    uint64_t var_offset;  /* its byte offset in the file */
    int compressed;
    char name[64];        /* its name, as far as read */
    char where[160];      /* the sub-variable being walked: "", ".potvals", "{3}" ... */
    uint64_t cost;        /* bytes of doubles thorax would make of the variable's arrays */
} mcheck;

static thx_status mfail(mcheck *m, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static thx_status mfail(mcheck *m, const char *fmt, ...)
{
    char msg[700];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    char at[96];
    if (m->compressed)
        snprintf(at, sizeof at, "compressed, byte %" PRIu64 " of its inflated data", m->src->pos);
    else
        snprintf(at, sizeof at, "byte offset %" PRIu64, m->src->pos);
    return thx_error(m->ctx, THX_EINPUT, "%s: variable %zu ('%s%s', at byte offset %" PRIu64 "; %s): %s", m->path,
                     m->var, m->name[0] ? m->name : "?", m->where, m->var_offset, at, msg);
}

/* A sub-element tag within `left` bytes: type, data bytes, and the bytes the whole sub-element takes
 * (small elements: 8; others: 8 + data padded to 8, the padding allowed to be cut at the end of the
 * enclosing element). Small elements keep their data in small[4]. */
typedef struct {
    uint32_t type, bytes;
    uint64_t span;
    int small;
    unsigned char data[4];
} mtag;

static thx_status read_tag(mcheck *m, uint64_t *left, mtag *t, const char *what)
{
    unsigned char b[8];
    if (*left < 8) return mfail(m, "%s: %" PRIu64 " bytes left, a tag takes 8 (truncated or damaged)", what, *left);
    int rc = src_read(m->src, b, 8);
    if (rc) return mfail(m, "%s: %s", what, rc == -2 ? "the compressed data is not a valid zlib stream" : "the data ends inside its tag (truncated)");
    *left -= 8;
    uint32_t w = get_u32(m->src, b);
    memset(t, 0, sizeof *t);
    if (w >> 16) {
        t->small = 1;
        t->type = w & 0xFFFF;
        t->bytes = w >> 16;
        if (t->bytes > 4) return mfail(m, "%s: a small element of %" PRIu32 " bytes (at most 4)", what, t->bytes);
        memcpy(t->data, b + 4, 4);
        t->span = 8;
        return THX_OK;
    }
    t->type = w;
    t->bytes = get_u32(m->src, b + 4);
    if (t->bytes > *left)
        return mfail(m, "%s: claims %" PRIu32 " bytes, only %" PRIu64 " left (truncated or damaged)", what, t->bytes,
                     *left);
    uint64_t pad = ((uint64_t)t->bytes + 7) / 8 * 8;
    t->span = 8 + (pad <= *left ? pad : *left);
    return THX_OK;
}

/* Reads a tag's data (at most cap bytes kept; the rest and the padding skipped). */
static thx_status read_data(mcheck *m, uint64_t *left, const mtag *t, void *dst, size_t cap, const char *what)
{
    if (t->small) {
        if (dst && cap) memcpy(dst, t->data, t->bytes < cap ? t->bytes : cap);
        return THX_OK;
    }
    uint64_t n = t->span - 8, keep = t->bytes < cap ? t->bytes : cap;
    int rc = dst && keep ? src_read(m->src, dst, keep) : 0;
    if (!rc) rc = src_read(m->src, NULL, n - (dst ? keep : 0));
    if (rc) return mfail(m, "%s: %s", what, rc == -2 ? "the compressed data is not a valid zlib stream" : "the data ends inside it (truncated)");
    *left -= n;
    return THX_OK;
}

static thx_status skip_data(mcheck *m, uint64_t *left, const mtag *t, const char *what)
{
    return read_data(m, left, t, NULL, 0, what);
}

/* The name of an uncompressed top-level variable whose element is cut short, read from what is
 * left of its header (best effort, for the message); "" if that is cut too. */
static void peek_name(msrc *s, uint64_t avail, char *name, size_t cap)
{
    unsigned char b[512];
    size_t n = avail < sizeof b ? (size_t)avail : sizeof b;
    name[0] = '\0';
    long at = ftell(s->f);
    if (at < 0 || fread(b, 1, n, s->f) != n) n = 0;
    fseek(s->f, at, SEEK_SET);
    /* flags: 8 + 8 bytes; then the dimensions' tag and data */
    if (n < 24) return;
    uint32_t dbytes = get_u32(s, b + 20);
    uint64_t p = 24 + ((uint64_t)dbytes + 7) / 8 * 8;
    if (p + 8 > n) return;
    uint32_t w = get_u32(s, b + p), len;
    const unsigned char *d;
    if (w >> 16) {
        len = w >> 16;
        d = b + p + 4;
        if (len > 4) return;
    } else {
        len = get_u32(s, b + p + 4);
        d = b + p + 8;
        if (p + 8 + len > n) return;
    }
    size_t k = len < cap - 1 ? len : cap - 1;
    for (size_t i = 0; i < k; i++) name[i] = (d[i] >= ' ' && d[i] < 127) ? (char)d[i] : '?';
    name[k] = '\0';
}

static thx_status check_matrix(mcheck *m, uint64_t size, int depth);

/* `count` sub-variables (cells, struct fields), each a miMATRIX element, within *left bytes. */
static thx_status check_children(mcheck *m, uint64_t *left, uint64_t count, int depth, const char *kind,
                                 const char (*fields)[64], uint64_t nfields)
{
    if (count > *left / 8)
        return mfail(m, "%" PRIu64 " %s claimed, but %" PRIu64 " bytes can hold at most %" PRIu64
                        " (8 bytes each at least)",
                     count, kind, *left, *left / 8);
    size_t keep = strlen(m->where);
    for (uint64_t i = 0; i < count; i++) {
        if (fields && nfields)
            snprintf(m->where + keep, sizeof m->where - keep, "(%" PRIu64 ").%s", i / nfields + 1, fields[i % nfields]);
        else
            snprintf(m->where + keep, sizeof m->where - keep, "{%" PRIu64 "}", i + 1);
        mtag t;
        THX_CHECK(read_tag(m, left, &t, kind));
        if (t.small || t.type != miMATRIX)
            return mfail(m, "%s: element of type %" PRIu32 " where a variable (miMATRIX) must be", kind, t.type);
        THX_CHECK(check_matrix(m, t.bytes, depth + 1));
        *left -= t.bytes;
        uint64_t pad = t.span - 8 - t.bytes;
        if (pad && src_read(m->src, NULL, pad)) return mfail(m, "%s: the data ends inside its padding", kind);
        *left -= pad;
    }
    m->where[keep] = '\0';
    return THX_OK;
}

/* One miMATRIX element's contents: `size` bytes from the current position. */
static thx_status check_matrix(mcheck *m, uint64_t size, int depth)
{
    if (size == 0) return THX_OK; /* an empty array ([] in a cell or field) */
    if (depth > MAT_MAX_DEPTH) return mfail(m, "cells or structs nested more than %d levels deep", MAT_MAX_DEPTH);
    uint64_t left = size;
    mtag t;
    /* array flags */
    THX_CHECK(read_tag(m, &left, &t, "array flags"));
    if (t.type != miUINT32 || t.bytes != 8) return mfail(m, "array flags: type %" PRIu32 " of %" PRIu32 " bytes (miUINT32, 8 bytes expected)", t.type, t.bytes);
    unsigned char fl[8];
    THX_CHECK(read_data(m, &left, &t, fl, 8, "array flags"));
    uint32_t flags = get_u32(m->src, fl), nzmax = get_u32(m->src, fl + 4);
    unsigned cls = flags & 0xFF;
    int complex = (flags & 0x800) != 0;
    /* dimensions */
    THX_CHECK(read_tag(m, &left, &t, "dimensions"));
    if (t.type != miINT32 || t.bytes % 4 || t.bytes < 8)
        return mfail(m, "dimensions: type %" PRIu32 " of %" PRIu32 " bytes (miINT32, 2 or more dimensions expected)", t.type, t.bytes);
    uint64_t rank = t.bytes / 4, numel = 1, dim1 = 0;
    int overflow = 0;
    for (uint64_t i = 0; i < rank; i++) {
        unsigned char d[4];
        if (src_read(m->src, d, 4)) return mfail(m, "dimensions: the data ends inside them (truncated)");
        uint32_t v = get_u32(m->src, d);
        if (v > INT32_MAX) return mfail(m, "dimension %" PRIu64 " is negative (%" PRId32 ")", i + 1, (int32_t)v);
        if (i == 1) dim1 = v;
        if (v && numel > UINT64_MAX / v) overflow = 1;
        else numel *= v;
        if (v == 0) numel = 0, overflow = 0;
    }
    if (overflow) return mfail(m, "its dimensions multiply to more than 2^64 elements");
    uint64_t pad = t.span - 8 - t.bytes;
    if (pad && src_read(m->src, NULL, pad)) return mfail(m, "dimensions: the data ends inside their padding");
    left -= t.span - 8;
    /* name */
    THX_CHECK(read_tag(m, &left, &t, "name"));
    if (t.type != miINT8) return mfail(m, "name: type %" PRIu32 " (miINT8 expected)", t.type);
    char name[64] = "";
    THX_CHECK(read_data(m, &left, &t, name, sizeof name - 1, "name"));
    name[sizeof name - 1] = '\0';
    for (size_t i = 0; name[i]; i++)
        if ((unsigned char)name[i] < ' ' || (unsigned char)name[i] >= 127) name[i] = '?';
    if (depth == 0) snprintf(m->name, sizeof m->name, "%s", name);
    switch (cls) {
    case mxDOUBLE: case mxSINGLE: case mxINT8: case mxUINT8: case mxINT16: case mxUINT16: case mxINT32:
    case mxUINT32: case mxINT64: case mxUINT64: case mxCHAR:
        for (int part = 0; part < 1 + complex; part++) {
            const char *what = part ? "imaginary part" : cls == mxCHAR ? "characters" : "real part";
            THX_CHECK(read_tag(m, &left, &t, what));
            unsigned es = type_size(t.type);
            if (!es || (cls != mxCHAR && t.type >= miUTF8))
                return mfail(m, "%s: data type %" PRIu32 " is not a numeric type", what, t.type);
            if (numel > UINT64_MAX / es || numel * es != t.bytes)
                return mfail(m, "%s: its %" PRIu64 " elements of %u bytes need %" PRIu64 " bytes, the file holds %" PRIu32,
                             what, numel, es, numel > UINT64_MAX / es ? UINT64_MAX : numel * es, t.bytes);
            THX_CHECK(skip_data(m, &left, &t, what));
            m->cost += 8 * numel;
        }
        break;
    case mxSPARSE: {
        /* ir (row indices), jc (column starts, columns + 1), then the data of as many values as ir holds */
        THX_CHECK(read_tag(m, &left, &t, "sparse row indices"));
        if (t.type != miINT32 && t.type != miUINT32) return mfail(m, "sparse row indices: type %" PRIu32 " (miINT32 expected)", t.type);
        uint64_t nir = t.bytes / 4;
        if (t.bytes % 4 || nir > nzmax) return mfail(m, "sparse row indices: %" PRIu32 " bytes for nzmax %" PRIu32, t.bytes, nzmax);
        THX_CHECK(skip_data(m, &left, &t, "sparse row indices"));
        THX_CHECK(read_tag(m, &left, &t, "sparse column starts"));
        if ((t.type != miINT32 && t.type != miUINT32) || t.bytes != 4 * (dim1 + 1))
            return mfail(m, "sparse column starts: %" PRIu32 " bytes, %" PRIu64 " columns need %" PRIu64, t.bytes, dim1, 4 * (dim1 + 1));
        THX_CHECK(skip_data(m, &left, &t, "sparse column starts"));
        for (int part = 0; part < 1 + complex; part++) {
            const char *what = part ? "sparse imaginary part" : "sparse values";
            THX_CHECK(read_tag(m, &left, &t, what));
            unsigned es = type_size(t.type);
            if (!es || t.type >= miUTF8 || t.bytes != nir * es)
                return mfail(m, "%s: type %" PRIu32 ", %" PRIu32 " bytes for %" PRIu64 " row indices", what, t.type, t.bytes, nir);
            THX_CHECK(skip_data(m, &left, &t, what));
        }
        m->cost += 8 * nir + 4 * (dim1 + 1);
        break;
    }
    case mxCELL: THX_CHECK(check_children(m, &left, numel, depth, "cells", NULL, 0)); break;
    case mxSTRUCT: {
        THX_CHECK(read_tag(m, &left, &t, "field name length"));
        if (t.type != miINT32 || t.bytes != 4) return mfail(m, "field name length: type %" PRIu32 " of %" PRIu32 " bytes (miINT32, 4 expected)", t.type, t.bytes);
        unsigned char lb[4];
        THX_CHECK(read_data(m, &left, &t, lb, 4, "field name length"));
        uint32_t flen = get_u32(m->src, lb);
        if (flen == 0 || flen > 4096) return mfail(m, "field name length %" PRIu32 " (1 to 4096)", flen);
        THX_CHECK(read_tag(m, &left, &t, "field names"));
        if (t.type != miINT8 || t.bytes % flen) return mfail(m, "field names: type %" PRIu32 ", %" PRIu32 " bytes, not a multiple of %" PRIu32, t.type, t.bytes, flen);
        uint64_t nfields = t.bytes / flen;
        /* the first 64 fields' names, for messages */
        char (*fields)[64] = calloc(nfields < 64 ? (nfields ? nfields : 1) : 64, sizeof *fields);
        if (!fields) return thx_error(m->ctx, THX_ENOMEM, "%s: out of memory", m->path);
        uint64_t got = 0;
        thx_status st = THX_OK;
        unsigned char nb[64];
        if (t.small) {
            if (nfields) memcpy(fields[0], t.data, t.bytes < 63 ? t.bytes : 63);
        } else {
            for (uint64_t i = 0; i < nfields && st == THX_OK; i++) {
                size_t k = flen < 63 ? flen : 63;
                if (src_read(m->src, nb, k) || src_read(m->src, NULL, flen - k)) {
                    st = mfail(m, "field names: the data ends inside them (truncated)");
                    break;
                }
                if (i < 64) {
                    memcpy(fields[i], nb, k);
                    fields[i][k] = '\0';
                    for (size_t c = 0; fields[i][c]; c++)
                        if ((unsigned char)fields[i][c] < ' ' || (unsigned char)fields[i][c] >= 127) fields[i][c] = '?';
                }
                got += flen;
            }
            uint64_t padn = t.span - 8 - got;
            if (st == THX_OK && padn && src_read(m->src, NULL, padn)) st = mfail(m, "field names: the data ends inside their padding");
            left -= t.span - 8;
        }
        if (st == THX_OK && nfields > 64) {
            /* names past the 64th are not kept: messages give them as "?" */
            free(fields);
            fields = NULL;
        }
        if (st == THX_OK && numel && nfields > UINT64_MAX / numel) st = mfail(m, "%" PRIu64 " x %" PRIu64 " fields is too many", numel, nfields);
        if (st == THX_OK)
            st = check_children(m, &left, numel * nfields, depth, "struct fields", (const char (*)[64])fields,
                                fields ? nfields : 0);
        free(fields);
        THX_CHECK(st);
        break;
    }
    case mxOBJECT: return mfail(m, "a MATLAB object (class 3): not supported (libmatio cannot read objects)");
    case mxFUNCTION: return mfail(m, "a function handle (class 16): not supported");
    case mxOPAQUE: return mfail(m, "an opaque object (class 17, e.g. a string or table): not supported");
    default: return mfail(m, "unknown array class %u", cls);
    }
    /* a variable ends with its last sub-element (and at most 7 bytes of padding) */
    if (left >= 8) return mfail(m, "%" PRIu64 " bytes after its data (damaged file?)", left);
    if (left && src_read(m->src, NULL, left)) return mfail(m, "the data ends inside its padding (truncated)");
    return THX_OK;
}

thx_status series_mat_preflight(thx_ctx *ctx, const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) return thx_error(ctx, THX_EIO, "%s: cannot open: %s", path, strerror(errno));
    thx_status st = THX_OK;
    struct stat sb;
    z_stream z;
    int z_live = 0;
    msrc *src = calloc(1, sizeof *src);
    if (!src) {
        fclose(f);
        return thx_error(ctx, THX_ENOMEM, "%s: out of memory", path);
    }
    if (fstat(fileno(f), &sb) != 0) {
        st = thx_error(ctx, THX_EIO, "%s: cannot stat: %s", path, strerror(errno));
        goto done;
    }
    uint64_t size = (uint64_t)sb.st_size;
    unsigned char h[128];
    size_t got = fread(h, 1, sizeof h, f);
    if (got < 6 || memcmp(h, "MATLAB", 6) != 0) {
        st = thx_error(ctx, THX_EINPUT, "%s: byte offset 0: not a MATLAB .mat file (no 'MATLAB' header text of a MATLAB 5/7 file; MATLAB 4 files "
                                        "are not read: save with -v7)", path);
        goto done;
    }
    if (got < sizeof h) {
        st = thx_error(ctx, THX_EINPUT, "%s: byte offset %" PRIu64 ": truncated: the file ends inside the 128-byte MAT-file header", path, size);
        goto done;
    }
    if (!(h[126] == 'I' && h[127] == 'M') && !(h[126] == 'M' && h[127] == 'I')) {
        st = thx_error(ctx, THX_EINPUT, "%s: byte offset 126: byte order mark '%c%c' is neither 'IM' nor 'MI' (damaged header)", path,
                       h[126] >= ' ' && h[126] < 127 ? h[126] : '?', h[127] >= ' ' && h[127] < 127 ? h[127] : '?');
        goto done;
    }
    src->f = f;
    src->swap = h[126] == 'M';
    src->pos = 128;
    unsigned version = src->swap ? (unsigned)h[124] << 8 | h[125] : (unsigned)h[125] << 8 | h[124];
    if (version == 0x0200) {
        st = thx_error(ctx, THX_EINPUT, "%s: byte offset 124: a MATLAB v7.3 (HDF5) file: not read (its variables' sizes cannot be checked "
                                        "against the file before they are allocated); save it with -v7", path);
        goto done;
    }
    if (version != 0x0100) {
        st = thx_error(ctx, THX_EINPUT, "%s: byte offset 124: MAT-file version 0x%04x (0x0100 expected)", path, version);
        goto done;
    }
    mcheck m = {ctx, path, src, 0, 0, 0, "", "", 0};
    while (src->pos < size) {
        m.var++;
        m.var_offset = src->pos;
        m.name[0] = m.where[0] = '\0';
        m.compressed = 0;
        m.cost = 0;
        uint64_t left = size - src->pos;
        if (left < 8) {
            st = thx_error(ctx, THX_EINPUT, "%s: byte offset %" PRIu64 ": %" PRIu64 " stray bytes after the last variable "
                                            "(truncated or damaged file)", path, src->pos, left);
            goto done;
        }
        mtag t;
        if (left >= 8) {
            /* a variable cut short: name it from what is left of its header */
            unsigned char tb[8];
            if (fread(tb, 1, 8, f) == 8 && get_u32(src, tb) == miMATRIX && get_u32(src, tb + 4) > left - 8)
                peek_name(src, left - 8, m.name, sizeof m.name);
            fseeko(f, (off_t)src->pos, SEEK_SET);
        }
        if ((st = read_tag(&m, &left, &t, "variable tag")) != THX_OK) goto done;
        if (t.small || (t.type != miMATRIX && t.type != miCOMPRESSED)) {
            st = thx_error(ctx, THX_EINPUT, "%s: byte offset %" PRIu64 ": element of type %" PRIu32 " where a variable "
                                            "(miMATRIX 14 or miCOMPRESSED 15) must be (damaged file?)", path, m.var_offset, t.type);
            goto done;
        }
        if (t.type == miMATRIX) {
            if ((st = check_matrix(&m, t.bytes, 0)) != THX_OK) goto done;
            /* padding to 8 bytes, where the file has it */
            uint64_t pad = t.span - 8 - t.bytes;
            if (pad && src_read(src, NULL, pad)) pad = 0;
            continue;
        }
        /* miCOMPRESSED: the element is t.bytes of zlib stream, unpadded */
        memset(&z, 0, sizeof z);
        if (inflateInit(&z) != Z_OK) {
            st = thx_error(ctx, THX_ENOMEM, "%s: zlib cannot start", path);
            goto done;
        }
        z_live = 1;
        uint64_t file_end = src->pos + t.bytes, csize = t.bytes;
        src->z = &z;
        src->z_left = t.bytes;
        src->z_end = 0;
        src->pos = 0;
        m.compressed = 1;
        uint64_t ileft = (uint64_t)ZLIB_MAX_RATIO * csize + 64;
        mtag it;
        if ((st = read_tag(&m, &ileft, &it, "compressed variable")) != THX_OK) goto done;
        if (it.small || it.type != miMATRIX) {
            st = mfail(&m, "the compressed data holds an element of type %" PRIu32 ", not a variable (miMATRIX)", it.type);
            goto done;
        }
        if ((st = check_matrix(&m, it.bytes, 0)) != THX_OK) goto done;
        /* the stream must end here: nothing after the variable, inflated or compressed */
        unsigned char extra;
        int rc = src_read(src, &extra, 1);
        if (rc == 0) {
            st = mfail(&m, "inflated data goes on after the variable's %" PRIu32 " bytes (damaged file?)", it.bytes);
            goto done;
        }
        if (rc == -2 || !src->z_end) {
            st = mfail(&m, "the compressed data is not a valid zlib stream, or is cut short");
            goto done;
        }
        if (src->z_left || z.avail_in) {
            st = mfail(&m, "%" PRIu64 " compressed bytes after the end of its zlib stream (damaged file?)",
                       src->z_left + z.avail_in);
            goto done;
        }
        if (m.cost > (uint64_t)ZLIB_MAX_RATIO * csize + ZLIB_SLACK) {
            st = mfail(&m, "%" PRIu64 " bytes of compressed data would expand to %" PRIu64 " bytes of values, more than "
                           "%u times the compressed size plus 1 MiB (refused: a file must not claim far more memory "
                           "than it holds)", csize, m.cost, ZLIB_MAX_RATIO);
            goto done;
        }
        inflateEnd(&z);
        z_live = 0;
        src->z = NULL;
        src->pos = file_end;
        if (fseeko(f, (off_t)file_end, SEEK_SET) != 0) {
            st = thx_error(ctx, THX_EIO, "%s: cannot seek to byte %" PRIu64, path, file_end);
            goto done;
        }
    }
    if (m.var == 0) st = thx_error(ctx, THX_EINPUT, "%s: byte offset 128: no variables (a 128-byte header only)", path);
done:
    if (z_live) inflateEnd(&z);
    free(src);
    fclose(f);
    return st;
}
