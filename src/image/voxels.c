/* Voxel bytes as the NRRD and MetaImage files store them (image_impl.h): decoding every scalar type
 * in either byte order, text voxels, zlib/gzip streams inflated to exactly the size a header claims,
 * and the writers' encoding, compression and atomic placement. */
#include "image/image_impl.h"

#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <zlib.h>

size_t thx_raw_size(thx_raw_type t)
{
    static const size_t size[] = {1, 1, 2, 2, 4, 4, 8, 8, 4, 8};
    return size[t];
}

const char *thx_raw_name(thx_raw_type t)
{
    static const char *const name[] = {"int8",  "uint8",  "int16",  "uint16",  "int32",
                                       "uint32", "int64", "uint64", "float32", "float64"};
    return name[t];
}

thx_raw_type thx_raw_of_voxel(thx_voxel_type t)
{
    switch (t) {
    case THX_VOXEL_UINT8: return THX_RAW_UINT8;
    case THX_VOXEL_INT16: return THX_RAW_INT16;
    case THX_VOXEL_UINT16: return THX_RAW_UINT16;
    case THX_VOXEL_INT32: return THX_RAW_INT32;
    case THX_VOXEL_FLOAT32: return THX_RAW_FLOAT32;
    }
    return THX_RAW_FLOAT32;
}

/* One value of `size` bytes at p in the given byte order, as an unsigned integer of that width. */
static uint64_t load(const unsigned char *p, size_t size, int big_endian)
{
    uint64_t u = 0;
    for (size_t b = 0; b < size; b++) u |= (uint64_t)p[big_endian ? size - 1 - b : b] << (8 * b);
    return u;
}

static float value_of(uint64_t u, thx_raw_type t)
{
    switch (t) {
    case THX_RAW_INT8: return (float)(int8_t)(uint8_t)u;
    case THX_RAW_UINT8: return (float)(uint8_t)u;
    case THX_RAW_INT16: return (float)(int16_t)(uint16_t)u;
    case THX_RAW_UINT16: return (float)(uint16_t)u;
    case THX_RAW_INT32: return (float)(int32_t)(uint32_t)u;
    case THX_RAW_UINT32: return (float)(uint32_t)u;
    case THX_RAW_INT64: return (float)(int64_t)u;
    case THX_RAW_UINT64: return (float)u;
    case THX_RAW_FLOAT32: {
        uint32_t w = (uint32_t)u;
        float f;
        memcpy(&f, &w, sizeof f);
        return f;
    }
    case THX_RAW_FLOAT64: {
        double d;
        memcpy(&d, &u, sizeof d);
        return (float)d;
    }
    }
    return NAN;
}

void thx_image_decode(thx_image *img, const unsigned char *bytes, thx_raw_type t, int big_endian)
{
    size_t count = thx_image_count(img), size = thx_raw_size(t);
    for (size_t q = 0; q < count; q++) img->v[q] = value_of(load(bytes + q * size, size, big_endian), t);
    snprintf(img->stored_type, sizeof img->stored_type, "%s", thx_raw_name(t));
    img->integral = t != THX_RAW_FLOAT32 && t != THX_RAW_FLOAT64;
}

thx_status thx_image_decode_ascii(thx_ctx *ctx, thx_image *img, const char *text, size_t len, thx_raw_type t,
                                  const char *what)
{
    size_t count = thx_image_count(img), q = 0, pos = 0;
    int integer = t != THX_RAW_FLOAT32 && t != THX_RAW_FLOAT64;
    char word[64];
    for (;;) {
        while (pos < len && (text[pos] == ' ' || text[pos] == '\t' || text[pos] == '\n' || text[pos] == '\r' ||
                             text[pos] == ','))
            pos++;
        if (pos >= len) break;
        size_t start = pos;
        while (pos < len && !(text[pos] == ' ' || text[pos] == '\t' || text[pos] == '\n' || text[pos] == '\r' ||
                              text[pos] == ','))
            pos++;
        if (q == count)
            return thx_error(ctx, THX_EINPUT, "%s: the text data hold more than the header's %zu values (at byte %zu)",
                             what, count, start);
        size_t w = pos - start;
        if (w >= sizeof word)
            return thx_error(ctx, THX_EINPUT, "%s: text value %zu (at byte %zu) is not a number", what, q + 1, start);
        memcpy(word, text + start, w);
        word[w] = '\0';
        char *end;
        errno = 0;
        double v = strtod(word, &end);
        if (*end || end == word || (integer && v != floor(v)))
            return thx_error(ctx, THX_EINPUT, "%s: text value %zu (at byte %zu) \"%s\" is not %s", what, q + 1,
                             start, word, integer ? "an integer" : "a number");
        static const double lo[] = {-128, 0, -32768, 0, -2147483648.0, 0, -9223372036854775808.0, 0},
                            hi[] = {127, 255, 32767, 65535, 2147483647.0, 4294967295.0, 9223372036854775807.0,
                                    18446744073709551615.0};
        if (integer && (v < lo[t] || v > hi[t]))
            return thx_error(ctx, THX_EINPUT, "%s: text value %zu (at byte %zu) %s is outside the range of %s", what,
                             q + 1, start, word, thx_raw_name(t));
        img->v[q++] = (float)v;
    }
    if (q < count)
        return thx_error(ctx, THX_EINPUT, "%s: the text data hold %zu values but the header claims %zu: truncated",
                         what, q, count);
    snprintf(img->stored_type, sizeof img->stored_type, "%s", thx_raw_name(t));
    img->integral = integer;
    return THX_OK;
}

double thx_image_inflate_bound(size_t n) { return 1100.0 * (double)n + 4096.0; }

thx_status thx_image_inflate(thx_ctx *ctx, const unsigned char *src, size_t n, unsigned char *dst, size_t need,
                             const char *what)
{
    z_stream z;
    memset(&z, 0, sizeof z);
    if (inflateInit2(&z, 15 + 32) != Z_OK) return thx_error(ctx, THX_ENOMEM, "%s: zlib cannot start", what);
    size_t in_done = 0, out_done = 0;
    int rc = Z_OK;
    /* in chunks: zlib's counts are 32-bit */
    while (rc == Z_OK) {
        size_t ci = n - in_done, co = need - out_done;
        z.next_in = (Bytef *)(src + in_done);
        z.avail_in = (uInt)(ci > (1u << 30) ? (1u << 30) : ci);
        unsigned char spare;
        /* a full output gets one spare byte: more data than claimed shows as output there */
        z.next_out = co ? dst + out_done : &spare;
        z.avail_out = (uInt)(co ? (co > (1u << 30) ? (1u << 30) : co) : 1);
        uInt ai = z.avail_in, ao = z.avail_out;
        rc = inflate(&z, Z_NO_FLUSH);
        in_done += ai - z.avail_in;
        size_t made = ao - z.avail_out;
        if (!co && made) {
            inflateEnd(&z);
            return thx_error(ctx, THX_EINPUT,
                             "%s: the compressed data hold more than the header's %zu bytes of voxels", what, need);
        }
        out_done += co ? made : 0;
        if (rc == Z_BUF_ERROR && ai == z.avail_in && made == 0) break; /* no progress: input ended */
        if (rc == Z_BUF_ERROR) rc = Z_OK;
    }
    inflateEnd(&z);
    if (rc == Z_DATA_ERROR || rc == Z_NEED_DICT || rc == Z_STREAM_ERROR)
        return thx_error(ctx, THX_EINPUT, "%s: the compressed data are corrupt (zlib: %s, after %zu of %zu bytes)",
                         what, z.msg ? z.msg : "data error", out_done, need);
    if (rc == Z_MEM_ERROR) return thx_error(ctx, THX_ENOMEM, "%s: out of memory inflating the data", what);
    if (out_done < need)
        return thx_error(ctx, THX_EINPUT,
                         "%s: the compressed data give %zu bytes but the header claims %zu bytes of voxels: truncated",
                         what, out_done, need);
    if (rc != Z_STREAM_END)
        return thx_error(ctx, THX_EINPUT, "%s: the compressed data stop before their end mark: truncated", what);
    if (in_done < n) {
        /* gzip allows members back to back; anything else after the stream is not ours to ignore */
        return thx_error(ctx, THX_EINPUT, "%s: %zu bytes follow the compressed voxel data", what, n - in_done);
    }
    return THX_OK;
}

thx_status thx_image_inflate_all(thx_ctx *ctx, const unsigned char *src, size_t n, unsigned char **out, size_t *len,
                                 const char *what)
{
    double bound = thx_image_inflate_bound(n);
    size_t cap = n * 4 + 4096, done = 0, in_done = 0;
    unsigned char *b = malloc(cap);
    z_stream z;
    memset(&z, 0, sizeof z);
    if (!b || inflateInit2(&z, 15 + 32) != Z_OK) {
        free(b);
        return thx_error(ctx, THX_ENOMEM, "%s: out of memory inflating the data", what);
    }
    int rc = Z_OK;
    while (rc == Z_OK) {
        if (cap - done < 65536) {
            size_t nc = cap * 2;
            if ((double)nc > bound + 65536) nc = (size_t)bound + 65536;
            unsigned char *nb = nc > cap ? realloc(b, nc) : NULL;
            if (!nb) {
                rc = Z_MEM_ERROR;
                break;
            }
            b = nb;
            cap = nc;
        }
        size_t ci = n - in_done, co = cap - done;
        z.next_in = (Bytef *)(src + in_done);
        z.avail_in = (uInt)(ci > (1u << 30) ? (1u << 30) : ci);
        z.next_out = b + done;
        z.avail_out = (uInt)(co > (1u << 30) ? (1u << 30) : co);
        uInt ai = z.avail_in, ao = z.avail_out;
        rc = inflate(&z, Z_NO_FLUSH);
        in_done += ai - z.avail_in;
        done += ao - z.avail_out;
        if (rc == Z_BUF_ERROR && ai == z.avail_in && ao == z.avail_out) break; /* input ended */
        if (rc == Z_BUF_ERROR) rc = Z_OK;
    }
    inflateEnd(&z);
    thx_status st = THX_OK;
    if (rc == Z_MEM_ERROR)
        st = thx_error(ctx, THX_EINPUT, "%s: the compressed data inflate to more than %.0f bytes", what, bound);
    else if (rc != Z_STREAM_END)
        st = thx_error(ctx, THX_EINPUT, "%s: the compressed data are corrupt or stop before their end mark: truncated",
                       what);
    else if (in_done < n)
        st = thx_error(ctx, THX_EINPUT, "%s: %zu bytes follow the compressed voxel data", what, n - in_done);
    if (st != THX_OK) {
        free(b);
        return st;
    }
    *out = b;
    *len = done;
    return THX_OK;
}

thx_status thx_image_encode(thx_ctx *ctx, const thx_image *img, thx_voxel_type t, unsigned char **out, size_t *len)
{
    thx_raw_type r = thx_raw_of_voxel(t);
    size_t count = thx_image_count(img), size = thx_raw_size(r);
    unsigned char *b = malloc(count * size > 0 ? count * size : 1);
    if (!b) return thx_error(ctx, THX_ENOMEM, "out of memory for %zu voxels", count);
    for (size_t q = 0; q < count; q++) {
        float v = img->v[q];
        uint64_t u = 0;
        switch (t) {
        case THX_VOXEL_UINT8: u = (uint8_t)v; break;
        case THX_VOXEL_INT16: u = (uint16_t)(int16_t)v; break;
        case THX_VOXEL_UINT16: u = (uint16_t)v; break;
        case THX_VOXEL_INT32: u = (uint32_t)(int32_t)v; break;
        case THX_VOXEL_FLOAT32: {
            uint32_t w;
            memcpy(&w, &v, sizeof w);
            u = w;
            break;
        }
        }
        for (size_t k = 0; k < size; k++) b[q * size + k] = (unsigned char)(u >> (8 * k));
    }
    *out = b;
    *len = count * size;
    return THX_OK;
}

thx_status thx_image_deflate(thx_ctx *ctx, const unsigned char *src, size_t n, int gzip, unsigned char **out,
                             size_t *len, const char *what)
{
    z_stream z;
    memset(&z, 0, sizeof z);
    if (deflateInit2(&z, 6, Z_DEFLATED, gzip ? 15 + 16 : 15, 8, Z_DEFAULT_STRATEGY) != Z_OK)
        return thx_error(ctx, THX_ENOMEM, "%s: zlib cannot start", what);
    gz_header h;
    if (gzip) {
        memset(&h, 0, sizeof h);
        h.comment = (Bytef *)THX_IMAGE_MARKER;
        h.os = 3;
        deflateSetHeader(&z, &h);
    }
    size_t cap = n + n / 1000 + 1024, done = 0, in_done = 0;
    unsigned char *b = malloc(cap);
    if (!b) {
        deflateEnd(&z);
        return thx_error(ctx, THX_ENOMEM, "%s: out of memory compressing the voxels", what);
    }
    int rc = Z_OK;
    while (rc != Z_STREAM_END) {
        if (cap - done < 65536) {
            unsigned char *nb = realloc(b, cap * 2);
            if (!nb) {
                free(b);
                deflateEnd(&z);
                return thx_error(ctx, THX_ENOMEM, "%s: out of memory compressing the voxels", what);
            }
            b = nb;
            cap *= 2;
        }
        size_t ci = n - in_done, co = cap - done;
        z.next_in = (Bytef *)(src + in_done);
        z.avail_in = (uInt)(ci > (1u << 30) ? (1u << 30) : ci);
        z.next_out = b + done;
        z.avail_out = (uInt)(co > (1u << 30) ? (1u << 30) : co);
        uInt ai = z.avail_in, ao = z.avail_out;
        int last = ci <= (1u << 30);
        rc = deflate(&z, last ? Z_FINISH : Z_NO_FLUSH);
        in_done += ai - z.avail_in;
        done += ao - z.avail_out;
        if (rc == Z_STREAM_ERROR) {
            free(b);
            deflateEnd(&z);
            return thx_error(ctx, THX_EINTERNAL, "%s: zlib failed compressing the voxels", what);
        }
    }
    deflateEnd(&z);
    *out = b;
    *len = done;
    return THX_OK;
}

thx_status thx_image_place_bytes(thx_ctx *ctx, thx_atomic_file *af, const char *head, size_t nh,
                                 const unsigned char *data, size_t nd)
{
    char tmp[1200];
    THX_CHECK(thx_image_temp_beside(ctx, af, ".part", tmp, sizeof tmp));
    FILE *f = fopen(tmp, "wb");
    int ok = f && fwrite(head, 1, nh, f) == nh && (nd == 0 || fwrite(data, 1, nd, f) == nd);
    if (f && fclose(f) != 0) ok = 0;
    if (!ok) {
        unlink(tmp);
        return thx_error(ctx, THX_EIO, "%s: write failed (disk full?): nothing was written", af->path);
    }
    return thx_output_place(ctx, af, tmp);
}

void thx_image_beside(const char *header, const char *name, char *out, size_t size)
{
    const char *slash = strrchr(header, '/');
    if (name[0] == '/' || !slash) snprintf(out, size, "%s", name);
    else snprintf(out, size, "%.*s/%s", (int)(slash - header), header, name);
}
