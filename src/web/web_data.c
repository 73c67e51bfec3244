/*
 * The page's data (thorax/web/page.h): 16-bit quantization, frame deltas, raw deflate, base64.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include "thorax/web/page.h"

thx_status thx_web_quantize(thx_ctx *ctx, const double *v, size_t n_rows, size_t n_frames, thx_web_quant *q)
{
    memset(q, 0, sizeof *q);
    size_t n = n_rows * n_frames;
    if (n_frames && n / n_frames != n_rows) return thx_error(ctx, THX_EINPUT, "web: a series of %zu x %zu values is too large", n_rows, n_frames);
    double lo = INFINITY, hi = -INFINITY;
    size_t nan = 0;
    for (size_t k = 0; k < n; k++) {
        if (!isfinite(v[k])) { nan++; continue; }
        lo = v[k] < lo ? v[k] : lo;
        hi = v[k] > hi ? v[k] : hi;
    }
    q->codes = malloc((n ? n : 1) * sizeof *q->codes);
    if (!q->codes) return thx_error(ctx, THX_ENOMEM, "web: out of memory quantizing %zu values", n);
    q->n_rows = n_rows;
    q->n_frames = n_frames;
    q->min = lo;
    q->max = hi;
    q->n_nan = nan;
    q->origin = lo <= hi ? lo : 0;
    /* codes 0 .. 65534 span the range; a constant series has step 0 and every code 0 */
    q->step = lo < hi ? (hi - lo) / (THX_WEB_NAN_CODE - 1) : 0;
    for (size_t k = 0; k < n; k++) {
        if (!isfinite(v[k])) { q->codes[k] = THX_WEB_NAN_CODE; continue; }
        double c = q->step > 0 ? nearbyint((v[k] - q->origin) / q->step) : 0;
        q->codes[k] = (uint16_t)(c < 0 ? 0 : c > THX_WEB_NAN_CODE - 1 ? THX_WEB_NAN_CODE - 1 : c);
    }
    return THX_OK;
}

void thx_web_quant_free(thx_web_quant *q)
{
    if (!q) return;
    free(q->codes);
    memset(q, 0, sizeof *q);
}

double thx_web_dequantize(const thx_web_quant *q, uint16_t code)
{
    return code == THX_WEB_NAN_CODE ? NAN : q->origin + code * q->step;
}

double thx_web_quant_error(const thx_web_quant *q, const double *v)
{
    double e = 0;
    for (size_t k = 0; k < q->n_rows * q->n_frames; k++) {
        double d = thx_web_dequantize(q, q->codes[k]);
        if (!isfinite(v[k]) || !isfinite(d)) {
            if (isfinite(v[k]) != isfinite(d)) return INFINITY;
            continue;
        }
        e = fmax(e, fabs(d - v[k]));
    }
    return e;
}

void thx_web_delta_encode(uint16_t *c, size_t n_rows, size_t n_frames)
{
    for (size_t f = n_frames; f-- > 1;)
        for (size_t i = 0; i < n_rows; i++) c[f * n_rows + i] = (uint16_t)(c[f * n_rows + i] - c[(f - 1) * n_rows + i]);
}

void thx_web_delta_decode(uint16_t *c, size_t n_rows, size_t n_frames)
{
    for (size_t f = 1; f < n_frames; f++)
        for (size_t i = 0; i < n_rows; i++) c[f * n_rows + i] = (uint16_t)(c[f * n_rows + i] + c[(f - 1) * n_rows + i]);
}

thx_status thx_web_deflate(thx_ctx *ctx, const void *in, size_t n, unsigned char **out, size_t *out_n)
{
    *out = NULL;
    *out_n = 0;
    z_stream z;
    memset(&z, 0, sizeof z);
    if (deflateInit2(&z, 9, Z_DEFLATED, -15, 9, Z_DEFAULT_STRATEGY) != Z_OK)
        return thx_error(ctx, THX_ENOMEM, "web: zlib's deflate could not start");
    size_t cap = deflateBound(&z, (uLong)n) + 64;
    unsigned char *buf = malloc(cap);
    if (!buf) {
        deflateEnd(&z);
        return thx_error(ctx, THX_ENOMEM, "web: out of memory compressing %zu bytes", n);
    }
    /* in pieces: zlib's counts are 32-bit */
    const unsigned char *src = in;
    size_t left = n;
    int rc;
    z.next_out = buf;
    do {
        size_t piece = left > (1u << 30) ? (1u << 30) : left;
        z.next_in = (unsigned char *)src;
        z.avail_in = (uInt)piece;
        src += piece;
        left -= piece;
        size_t room = cap - (size_t)(z.next_out - buf);
        z.avail_out = room > (1u << 30) ? (1u << 30) : (uInt)room;
        rc = deflate(&z, left ? Z_NO_FLUSH : Z_FINISH);
    } while (left && rc == Z_OK);
    size_t got = (size_t)(z.next_out - buf);
    deflateEnd(&z);
    if (rc != Z_STREAM_END) {
        free(buf);
        return thx_error(ctx, THX_EINTERNAL, "web: zlib's deflate stopped short (%d)", rc);
    }
    *out = buf;
    *out_n = got;
    return THX_OK;
}

thx_status thx_web_inflate(thx_ctx *ctx, const unsigned char *in, size_t n, size_t want, unsigned char **out)
{
    *out = NULL;
    unsigned char *buf = malloc(want ? want : 1);
    if (!buf) return thx_error(ctx, THX_ENOMEM, "web: out of memory inflating %zu bytes", want);
    z_stream z;
    memset(&z, 0, sizeof z);
    if (inflateInit2(&z, -15) != Z_OK) {
        free(buf);
        return thx_error(ctx, THX_ENOMEM, "web: zlib's inflate could not start");
    }
    z.next_in = (unsigned char *)in;
    z.avail_in = (uInt)n;
    z.next_out = buf;
    z.avail_out = (uInt)want;
    int rc = inflate(&z, Z_FINISH);
    size_t got = (size_t)(z.next_out - buf);
    inflateEnd(&z);
    if (rc != Z_STREAM_END || got != want || z.avail_in) {
        free(buf);
        return thx_error(ctx, THX_EINPUT, "web: a blob inflates to %zu bytes, not %zu (zlib %d)", got, want, rc);
    }
    *out = buf;
    return THX_OK;
}

size_t thx_web_base64(const unsigned char *in, size_t n, char *out)
{
    static const char A[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    size_t o = 0, i = 0;
    for (; i + 3 <= n; i += 3) {
        uint32_t w = (uint32_t)in[i] << 16 | (uint32_t)in[i + 1] << 8 | in[i + 2];
        out[o++] = A[w >> 18];
        out[o++] = A[(w >> 12) & 63];
        out[o++] = A[(w >> 6) & 63];
        out[o++] = A[w & 63];
    }
    if (n - i == 1) {
        uint32_t w = (uint32_t)in[i] << 16;
        out[o++] = A[w >> 18];
        out[o++] = A[(w >> 12) & 63];
        out[o++] = '=';
        out[o++] = '=';
    } else if (n - i == 2) {
        uint32_t w = (uint32_t)in[i] << 16 | (uint32_t)in[i + 1] << 8;
        out[o++] = A[w >> 18];
        out[o++] = A[(w >> 12) & 63];
        out[o++] = A[(w >> 6) & 63];
        out[o++] = '=';
    }
    return o;
}
